// The key light's shadow map (RenderSettings::shadows): an orthographic depth map of the skin and the
// alpha-tested coat from light 0, drawn again only when what casts it changes (docs/render.md).
#include <algorithm>
#include <cmath>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "pteryla/core/error.hpp"
#include "renderer_impl.hpp"

namespace pteryla::render {
using namespace detail;

void Renderer::Impl::releaseShadow() {
  if (shadow.fbo) gl.DeleteFramebuffers(1, &shadow.fbo);
  if (shadow.depthTex) gl.DeleteTextures(1, &shadow.depthTex);
  shadow = Shadow();
}

bool Renderer::Impl::shadowBounds(glm::vec3& lo, glm::vec3& hi) const {
  bool any = false;
  if (hasSkinBounds && skin.indexCount > 0) lo = skinLo, hi = skinHi, any = true;
  for (size_t i = 0; i < plan.ranges().size(); ++i) {
    if (plan.ranges()[i].indexCount == 0) continue;
    lo = any ? glm::min(lo, plan.featherLo(i)) : plan.featherLo(i);
    hi = any ? glm::max(hi, plan.featherHi(i)) : plan.featherHi(i);
    any = true;
  }
  return any;
}

bool Renderer::Impl::updateShadowMap(const glm::vec3& toLight, const RenderSettings& s) {
  glm::vec3 lo(0.0f), hi(0.0f);
  if (!shadowBounds(lo, hi)) return false;
  const int size = std::clamp(s.shadowMapSize, 64, 8192);
  if (shadow.valid && shadow.size == size && shadow.lightDir == toLight && shadow.alphaTexture == s.useAlphaTexture)
    return false;
  // The caller's framebuffer and viewport, before anything here binds another.
  GLint previous = 0, viewport[4] = {};
  gl.GetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  gl.GetIntegerv(GL_VIEWPORT, viewport);
  if (shadow.size != size || !shadow.fbo) {
    if (shadow.fbo) gl.DeleteFramebuffers(1, &shadow.fbo);
    if (shadow.depthTex) gl.DeleteTextures(1, &shadow.depthTex);
    gl.GenTextures(1, &shadow.depthTex);
    gl.BindTexture(GL_TEXTURE_2D, shadow.depthTex);
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, size, size, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    setSampling(GL_LINEAR, GL_CLAMP_TO_EDGE, GL_CLAMP_TO_EDGE);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    gl.GenFramebuffers(1, &shadow.fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, shadow.fbo);
    gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow.depthTex, 0);
    gl.DrawBuffer(GL_NONE);
    gl.ReadBuffer(GL_NONE);
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("cannot create a " + std::to_string(size) + "x" + std::to_string(size) + " shadow map", {},
                  "shadowMapSize");
    shadow.size = size;
  }
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-6f);
  const glm::vec3 up = std::abs(toLight.y) < 0.95f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::mat4 lightView = glm::lookAt(centre + toLight * (2.0f * radius), centre, up);
  // Far enough behind the model for a ground plane's contact shadow under a low light.
  const glm::mat4 lightProj = glm::ortho(-radius, radius, -radius, radius, 0.5f * radius, 12.0f * radius);
  shadow.viewProj = lightProj * lightView;
  shadow.texelWorld = 2.0f * radius / float(size);

  gl.BindFramebuffer(GL_FRAMEBUFFER, shadow.fbo);
  gl.Viewport(0, 0, size, size);
  gl.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  gl.DepthMask(GL_TRUE);
  gl.ClearDepth(1.0);
  gl.Clear(GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LEQUAL);
  gl.Disable(GL_BLEND);
  gl.Enable(GL_POLYGON_OFFSET_FILL);
  gl.PolygonOffset(1.5f, 2.0f);
  shadow.triangles = 0;
  const Program& p = depthProg;
  gl.UseProgram(p.id);
  gl.UniformMatrix4fv(p.u.lightViewProj, 1, GL_FALSE, glm::value_ptr(shadow.viewProj));
  gl.Uniform1i(p.u.colorTex, 0);
  gl.Uniform1i(p.u.alphaTex, 1);
  gl.Uniform1i(p.u.useAlphaTex, s.useAlphaTexture ? 1 : 0);
  bindTextures({white, white});
  if (skin.indexCount > 0) {  // opaque
    gl.Uniform1f(p.u.alphaCut, 0.0f);
    gl.Uniform1i(p.u.colorUv, 0);
    gl.BindVertexArray(skin.vao);
    applyDefaults(skin);
    drawIndices(0, skin.indexCount);
  }
  if (coat.indexCount > 0 && !plan.ranges().empty()) {
    gl.Uniform1f(p.u.alphaCut, 0.5f);
    gl.BindVertexArray(coat.vao);
    applyDefaults(coat);
    // Every coat triangle, in the coat's index-list order; with sub-pixel culling, less those that cover
    // no texel centre of the map (they draw no depth: the map is the same).
    const bool cull = s.subpixelCulling;
    if (cull) plan.buildShadow(shadow.viewProj, size);
    if (cull)
      streamIndices(coat, plan.indices().data(), plan.indices().size(), GL_STREAM_DRAW);
    else
      streamIndices(coat, plan.coatIndices(), plan.coatIndexCount(), GL_STREAM_DRAW);
    size_t sinceWait = 0;
    for (const DrawRun& run : cull ? plan.runs() : plan.shadowRuns()) {
      if (run.material >= materials.size()) continue;
      const GpuMaterial& m = materials[run.material];
      bindTextures({m.colorTex, m.alphaTex});
      gl.Uniform1i(p.u.colorUv, static_cast<int>(m.desc.colorUv));
      drawIndicesBounded(run.first, run.count, sinceWait);
      shadow.triangles += run.count / 3;
    }
  }
  gl.Disable(GL_POLYGON_OFFSET_FILL);
  gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.BindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  gl.Viewport(viewport[0], viewport[1], viewport[2], viewport[3]);
  shadow.valid = true;
  shadow.lightDir = toLight;
  shadow.alphaTexture = s.useAlphaTexture;
  return true;
}

}  // namespace pteryla::render
