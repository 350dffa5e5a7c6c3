// OpenGL 3.3 core renderer for skins and feather coats (Streit 2003, chapter 7): textured, alpha
// blended feathers with the Poulin-Fournier barbule reflection (7.1.1-7.1.3), drawn after the skin
// with depth test but no depth writes, in layer order, each feather in view-dependent order (7.1.2,
// 7.2).
#include "pteryla/render/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "pteryla/core/error.hpp"
#include "renderer_impl.hpp"
#include "shaders.hpp"

namespace pteryla::render {
using namespace detail;

Renderer::Renderer(RenderContext& context) : impl_(std::make_unique<Impl>(context)) {
  Impl& r = *impl_;
  context.makeCurrent();
  r.gl.load(context);
  GLint major = 0, minor = 0;
  r.gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  r.gl.GetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 33)
    throw Error("OpenGL 3.3 is required, the context offers " + std::to_string(major) + "." + std::to_string(minor));
  const char* perVertex = "#version 330 core\n#define PER_FRAGMENT 0\n";
  const char* perFragment = "#version 330 core\n#define PER_FRAGMENT 1\n";
  using namespace shaders;
  r.skinProg = r.link(r.compile(GL_VERTEX_SHADER, {perFragment, kMeshAttributes, kMeshVertex}),
                      r.compile(GL_FRAGMENT_SHADER, {perFragment, kShadowLookup, kSkinFragment}));
  r.coatVertexProg = r.link(r.compile(GL_VERTEX_SHADER, {perVertex, kCoatShading, kMeshAttributes, kMeshVertex}),
                            r.compile(GL_FRAGMENT_SHADER, {perVertex, kShadowLookup, kFeatherAlpha, kCoatFragment}));
  r.coatFragmentProg =
      r.link(r.compile(GL_VERTEX_SHADER, {perFragment, kMeshAttributes, kMeshVertex}),
             r.compile(GL_FRAGMENT_SHADER, {perFragment, kCoatShading, kShadowLookup, kFeatherAlpha, kCoatFragment}));
  r.depthProg = r.link(r.compile(GL_VERTEX_SHADER, {perVertex, kMeshAttributes, kDepthVertex}),
                       r.compile(GL_FRAGMENT_SHADER, {perVertex, kFeatherAlpha, kDepthFragment}));
  r.resolveProg = r.link(r.compile(GL_VERTEX_SHADER, {perVertex, kResolveVertex}),
                         r.compile(GL_FRAGMENT_SHADER, {perVertex, kResolveFragment}));
  r.white = r.makeTexture(Image(1, 1, 255, 255, 255, 255), false, GL_REPEAT, GL_REPEAT);
  setMaterials({});
}

Renderer::~Renderer() {
  Impl& r = *impl_;
  try {
    r.ctx.makeCurrent();
  } catch (...) {
    return;  // the context is gone: nothing can be released
  }
  r.releaseMaterials();
  for (auto& [k, t] : r.brdfCache) r.gl.DeleteTextures(1, &t);
  r.gl.DeleteTextures(1, &r.white);
  r.releaseMesh(r.skin);
  r.releaseMesh(r.coat);
  r.releaseMesh(r.ground);
  r.releaseTarget();
  r.releaseShadow();
  r.gl.DeleteProgram(r.depthProg.id);
  r.gl.DeleteProgram(r.resolveProg.id);
  r.gl.DeleteProgram(r.skinProg.id);
  r.gl.DeleteProgram(r.coatVertexProg.id);
  r.gl.DeleteProgram(r.coatFragmentProg.id);
}

void Renderer::setSkin(const TriMesh& skin) {
  Impl& r = *impl_;
  r.ctx.makeCurrent();
  r.shadow.valid = false;
  r.hasSkinBounds = skin.bounds(r.skinLo, r.skinHi);
  if (!skin.normals.empty() || skin.positions.empty()) {
    r.upload(r.skin, skin, nullptr, true);
    return;
  }
  // Area-weighted vertex normals when the skin has none.
  std::vector<glm::vec3> normals(skin.positions.size(), glm::vec3(0.0f));
  const size_t nv = skin.positions.size();
  for (size_t t = 0; t + 2 < skin.indices.size(); t += 3) {
    const uint32_t a = skin.indices[t], b = skin.indices[t + 1], c = skin.indices[t + 2];
    if (a >= nv || b >= nv || c >= nv) continue;  // reported by upload()
    const glm::vec3 n = glm::cross(skin.positions[b] - skin.positions[a], skin.positions[c] - skin.positions[a]);
    normals[a] += n;
    normals[b] += n;
    normals[c] += n;
  }
  for (auto& n : normals) {
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::vec3(0, 0, 1);
  }
  const std::vector<PackedDir> packed(normals.begin(), normals.end());
  r.upload(r.skin, skin, &packed, true);
}

void Renderer::setCoat(const TriMesh& coat, const std::vector<FeatherDrawRange>& ranges) {
  setCoat(coat, ranges, CoatStorage::Copy);
}

void Renderer::setCoat(const TriMesh& coat, const std::vector<FeatherDrawRange>& ranges, CoatStorage storage) {
  const size_t n = coat.indices.size();
  DrawPlan::validateRanges(ranges, n);
  Impl& r = *impl_;
  r.ctx.makeCurrent();
  r.upload(r.coat, coat, nullptr, false);
  r.shadow.valid = false;
  if (storage == CoatStorage::Reference)
    r.plan.setCoatReference(coat.positions, coat.indices, ranges);
  else
    r.plan.setCoat(coat.positions, coat.indices, ranges);
}

void Renderer::setMaterials(const std::vector<FeatherMaterial>& materials) {
  Impl& r = *impl_;
  // Read and validate everything on the CPU first so a bad file leaves the renderer unchanged.
  std::map<std::string, Image> files;
  for (size_t i = 0; i < materials.size(); ++i) {
    const FeatherMaterial& m = materials[i];
    const std::string el = "materials[" + std::to_string(i) + "]";
    try {
      validate(m.barbules);
    } catch (const Error& e) {
      throw Error(e.detail(), {}, el + ".barbules." + e.element());
    }
    for (const auto& [path, field] : {std::pair{m.colorTexture, ".colorTexture"}, {m.alphaTexture, ".alphaTexture"}}) {
      if (path.empty() || files.count(path)) continue;
      try {
        files[path] = loadImage(path);
      } catch (const Error& e) {
        throw Error("cannot load texture" + (m.name.empty() ? std::string() : " of material '" + m.name + "'") + ": " +
                        e.detail(),
                    path, el + field);
      }
    }
  }
  r.ctx.makeCurrent();
  r.releaseMaterials();
  r.shadow.valid = false;
  for (const auto& file : files) {
    const std::string& path = file.first;
    const bool isAlpha = std::any_of(materials.begin(), materials.end(),
                                     [&](const FeatherMaterial& m) { return m.alphaTexture == path; });
    r.fileTextures[path] = r.makeTexture(file.second, true, isAlpha ? GL_REPEAT : GL_CLAMP_TO_EDGE, GL_CLAMP_TO_EDGE);
  }
  std::vector<FeatherMaterial> list = materials;
  if (list.empty()) list.emplace_back();
  for (const FeatherMaterial& m : list) {
    GpuMaterial g;
    g.desc = m;
    g.desc.colorImage = Image();
    g.desc.alphaImage = Image();
    if (!m.colorTexture.empty())
      g.colorTex = r.fileTextures.at(m.colorTexture);
    else if (!m.colorImage.empty())
      g.colorTex = r.makeTexture(m.colorImage, true, GL_CLAMP_TO_EDGE, GL_CLAMP_TO_EDGE);
    else
      g.colorTex = r.white;
    if (!m.alphaTexture.empty())
      g.alphaTex = r.fileTextures.at(m.alphaTexture);
    else if (!m.alphaImage.empty())
      g.alphaTex = r.makeTexture(m.alphaImage, true, GL_REPEAT, GL_CLAMP_TO_EDGE);
    else
      g.alphaTex = r.white;
    g.brdfTex = r.brdfTexture(m.barbules);
    r.materials.push_back(std::move(g));
  }
}

void Renderer::render(const Camera& camera, const std::vector<Light>& lights, const RenderSettings& s) {
  if (s.width <= 0 || s.height <= 0) throw Error("render size must be positive", {}, "width/height");
  Impl& r = *impl_;
  GlApi& gl = r.gl;
  r.ctx.makeCurrent();
  stats_ = RenderStats();

  const glm::mat4 view = camera.view(), proj = camera.projection(float(s.width) / float(s.height));
  const glm::mat4 viewProj = proj * view;
  const int lightCount = static_cast<int>(std::min<size_t>(lights.size(), 4));
  glm::vec3 dirs[4], colors[4];
  for (int i = 0; i < lightCount; ++i) {
    const float len = glm::length(lights[i].direction);
    dirs[i] = len > 0.0f ? lights[i].direction / len : glm::vec3(0.0f, 0.0f, 1.0f);
    colors[i] = lights[i].color;
  }
  bool shadowsOn = false;
  auto setCommon = [&](const Program& p) {
    gl.UseProgram(p.id);
    gl.UniformMatrix4fv(p.u.viewProj, 1, GL_FALSE, glm::value_ptr(viewProj));
    gl.Uniform3f(p.u.eye, camera.eye.x, camera.eye.y, camera.eye.z);
    gl.Uniform3f(p.u.ambient, s.ambient.x, s.ambient.y, s.ambient.z);
    gl.Uniform1i(p.u.lightCount, lightCount);
    if (lightCount > 0) {
      gl.Uniform3fv(p.u.lightDir, lightCount, glm::value_ptr(dirs[0]));
      gl.Uniform3fv(p.u.lightColor, lightCount, glm::value_ptr(colors[0]));
    }
    gl.Uniform1i(p.u.colorUv, 0);
    gl.Uniform1i(p.u.isCoat, &p == &r.skinProg ? 0 : 1);
    gl.Uniform1i(p.u.shadows, shadowsOn ? 1 : 0);
    gl.Uniform1f(p.u.exposureScale, std::exp2(std::clamp(s.exposure, -16.0f, 16.0f)));
    gl.Uniform1i(p.u.filmic, s.filmic ? 1 : 0);
    gl.Uniform1i(p.u.shadowMap, 3);
    if (shadowsOn) {
      gl.UniformMatrix4fv(p.u.lightViewProj, 1, GL_FALSE, glm::value_ptr(r.shadow.viewProj));
      gl.Uniform3f(p.u.shadowLightDir, dirs[0].x, dirs[0].y, dirs[0].z);
      gl.Uniform1f(p.u.shadowNormalOffset, 1.5f * r.shadow.texelWorld);
      gl.Uniform1f(p.u.shadowStrength, std::clamp(s.shadowStrength, 0.0f, 1.0f));
      gl.Uniform1f(p.u.shadowTexel, 1.0f / float(r.shadow.size));
    } else {
      const glm::mat4 identity(1.0f);
      gl.UniformMatrix4fv(p.u.lightViewProj, 1, GL_FALSE, glm::value_ptr(identity));
      gl.Uniform3f(p.u.shadowLightDir, 0.0f, 0.0f, 1.0f);
      gl.Uniform1f(p.u.shadowNormalOffset, 0.0f);
    }
  };

  // The key light's shadow map first (it binds its own framebuffer and restores the caller's).
  if (s.shadows && !s.wireframe && lightCount > 0 && (s.drawCoat || s.drawSkin)) {
    gl.Viewport(0, 0, s.width, s.height);
    stats_.shadowMapRendered = r.updateShadowMap(dirs[0], s);
    if (stats_.shadowMapRendered) stats_.shadowTriangles = r.shadow.triangles;
    shadowsOn = r.shadow.valid;
  }
  gl.ActiveTexture(GL_TEXTURE3);
  gl.BindTexture(GL_TEXTURE_2D, shadowsOn ? r.shadow.depthTex : 0);
  gl.ActiveTexture(GL_TEXTURE0);

  gl.Viewport(0, 0, s.width, s.height);
  // Wireframe: every draw below in lines, back to filled triangles whichever way this returns.
  struct PolygonModeScope {
    GlApi& gl;
    bool lines;
    ~PolygonModeScope() {
      if (lines) gl.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }
  } polygonMode{gl, s.wireframe};
  if (s.wireframe) gl.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl.DepthMask(GL_TRUE);
  gl.ClearColor(s.background.r, s.background.g, s.background.b, s.background.a);
  gl.ClearDepth(1.0);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LEQUAL);
  gl.Disable(GL_CULL_FACE);
  gl.Disable(GL_BLEND);
  gl.Disable(GL_DITHER);

  // Opaque, Lambert, writing depth: the skin and the ground.
  auto drawOpaque = [&](const GpuMesh& mesh, const glm::vec3& colour) {
    setCommon(r.skinProg);
    gl.Uniform3f(r.skinProg.u.skinColor, colour.r, colour.g, colour.b);
    gl.BindVertexArray(mesh.vao);
    r.applyDefaults(mesh);
    r.drawIndices(0, mesh.indexCount);
    ++stats_.drawCalls;
    stats_.triangles += mesh.indexCount / 3;
  };
  // Skin first, writing depth (7.2).
  if (s.drawSkin && r.skin.indexCount > 0) drawOpaque(r.skin, s.skinColor);
  // The ground: a square 8 model radii wide centred under the model, drawn like the skin (it takes the
  // key light's shadow; it is not in the shadow map, so it casts none).
  glm::vec3 modelLo(0.0f), modelHi(0.0f);
  if (s.ground && r.shadowBounds(modelLo, modelHi) && glm::length(s.groundNormal) > 0.0f) {
    const glm::vec3 n = glm::normalize(s.groundNormal);
    const glm::vec3 c = 0.5f * (modelLo + modelHi);
    const float radius = std::max(0.5f * glm::length(modelHi - modelLo), 1e-6f);
    float lowest = std::numeric_limits<float>::max();
    for (int k = 0; k < 8; ++k)
      lowest = std::min(lowest, glm::dot(glm::vec3(k & 1 ? modelHi.x : modelLo.x, k & 2 ? modelHi.y : modelLo.y,
                                                   k & 4 ? modelHi.z : modelLo.z),
                                         n));
    const glm::vec3 centre = c - (glm::dot(c, n) - lowest) * n;
    const std::vector<float> key = {centre.x, centre.y, centre.z, n.x, n.y, n.z, radius};
    if (key != r.groundKey) {
      const glm::vec3 a =
          glm::normalize(std::abs(n.x) < 0.9f ? glm::cross(n, glm::vec3(1, 0, 0)) : glm::cross(n, glm::vec3(0, 1, 0)));
      const glm::vec3 b = glm::cross(n, a);
      TriMesh g;
      const float h = 4.0f * radius;
      for (const glm::vec2 q : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
        g.positions.push_back(centre + h * (q.x * a + q.y * b));
        g.normals.push_back(n);
      }
      g.indices = {0, 1, 2, 0, 2, 3};
      r.upload(r.ground, g, nullptr, true);
      r.groundKey = key;
    }
    drawOpaque(r.ground, s.groundColor);
  }
  // The skin's depth, reduced to a grid of per-tile maxima, lets whole feathers hidden behind the
  // body skip rasterisation (conservative: a feather is dropped only if its bounding sphere's nearest
  // point lies behind the farthest skin depth over its screen rectangle).
  bool occlusion = false;
  GLint sampleBuffers = 0, drawFbo = 0;
  gl.GetIntegerv(GL_SAMPLE_BUFFERS, &sampleBuffers);
  gl.GetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &drawFbo);
  // Sub-pixel culling tests the points where the rasterizer samples coverage: the pixel centres, or with
  // multisampling the implementation's sample positions.
  const bool subpixel = s.subpixelCulling && !s.wireframe;
  std::vector<glm::vec2> samplePositions;
  if (sampleBuffers != 0) {
    GLint samples = 0;
    gl.GetIntegerv(GL_SAMPLES, &samples);
    for (GLint i = 0; i < samples; ++i) {
      GLfloat v[2] = {0.5f, 0.5f};
      gl.GetMultisamplefv(GL_SAMPLE_POSITION, static_cast<GLuint>(i), v);
      samplePositions.emplace_back(v[0], v[1]);
    }
  }
  // The occluders' depth: read back as is without multisampling; with it (renderImage's own target),
  // the farthest of each pixel's samples, resolved by a shader into the single-sample target first.
  const bool msTarget =
      sampleBuffers != 0 && r.target.msDepthTex != 0 && drawFbo == GLint(r.target.msFbo) && !s.wireframe;
  if (s.occlusionCulling && s.drawSkin && r.skin.indexCount > 0 && s.drawCoat && (sampleBuffers == 0 || msTarget)) {
    r.depth.resize(static_cast<size_t>(s.width) * s.height);
    gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
    if (msTarget) {
      gl.BindFramebuffer(GL_FRAMEBUFFER, r.target.fbo);
      gl.UseProgram(r.resolveProg.id);
      gl.ActiveTexture(GL_TEXTURE4);
      gl.BindTexture(GL_TEXTURE_2D_MULTISAMPLE, r.target.msDepthTex);
      gl.Uniform1i(r.resolveProg.u.depthMS, 4);
      gl.Uniform1i(r.resolveProg.u.samples, static_cast<GLint>(samplePositions.size()));
      gl.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      gl.DepthFunc(GL_ALWAYS);
      gl.BindVertexArray(r.skin.vao);
      gl.DrawArrays(GL_TRIANGLES, 0, 3);
      gl.ReadPixels(0, 0, s.width, s.height, GL_DEPTH_COMPONENT, GL_FLOAT, r.depth.data());
      gl.BindTexture(GL_TEXTURE_2D_MULTISAMPLE, 0);
      gl.ActiveTexture(GL_TEXTURE0);
      gl.DepthFunc(GL_LEQUAL);
      gl.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      gl.BindFramebuffer(GL_FRAMEBUFFER, r.target.msFbo);
    } else {
      gl.ReadPixels(0, 0, s.width, s.height, GL_DEPTH_COMPONENT, GL_FLOAT, r.depth.data());
    }
    r.occluders.build(r.depth.data(), s.width, s.height);
    occlusion = true;
  }

  // Feathers: depth test on, depth writes off, blended in layer order (7.2).
  if (s.drawCoat && r.coat.indexCount > 0 && !r.plan.ranges().empty()) {
    const Program& p = s.brdfPerFragment ? r.coatFragmentProg : r.coatVertexProg;
    r.setFastFilter(s.fastTextureFiltering);
    setCommon(p);
    gl.Uniform1i(p.u.colorTex, 0);
    gl.Uniform1i(p.u.alphaTex, 1);
    gl.Uniform1i(p.u.brdfTex, 2);
    gl.Uniform1i(p.u.useAlphaTex, s.useAlphaTexture ? 1 : 0);
    gl.Enable(GL_BLEND);
    gl.BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    gl.DepthMask(GL_FALSE);
    gl.BindVertexArray(r.coat.vao);
    r.applyDefaults(r.coat);

    const std::vector<FeatherDrawRange>& ranges = r.plan.ranges();
    for (size_t i = 0; i < ranges.size(); ++i)
      if (ranges[i].indexCount > 0 && ranges[i].material >= r.materials.size())
        throw Error("feather draw range uses material " + std::to_string(ranges[i].material) + " but " +
                        std::to_string(r.materials.size()) + " materials are set",
                    {}, "ranges[" + std::to_string(i) + "].material");
    DrawOptions options;
    options.viewDependentOrder = s.viewDependentOrder;
    options.subpixelCulling = subpixel;
    options.samplePositions = samplePositions;
    r.plan.build(camera, s.width, s.height, options, occlusion ? &r.occluders : nullptr);
    const DrawCounts& counts = r.plan.counts();
    stats_.triangles += counts.triangles;
    stats_.backwardParts += counts.backwardParts;
    stats_.culledFeathers += counts.culledFeathers;
    stats_.occludedFeathers += counts.occludedFeathers;
    stats_.occludedTriangles += counts.occludedTriangles;
    stats_.subpixelTriangles += counts.subpixelTriangles;

    // The plan's indices uploaded once, one draw call per material run.
    r.streamIndices(r.coat, r.plan.indices().data(), r.plan.indices().size(), GL_STREAM_DRAW);
    size_t sinceWait = 0;
    for (const DrawRun& run : r.plan.runs()) {
      const GpuMaterial& mat = r.materials[run.material];
      const FeatherMaterial& d = mat.desc;
      r.bindTextures({mat.colorTex, mat.alphaTex, mat.brdfTex});
      gl.Uniform1i(p.u.colorUv, static_cast<int>(d.colorUv));
      gl.Uniform1i(p.u.useBrdf, (s.useBrdf && d.useBrdf) ? 1 : 0);
      gl.Uniform3f(p.u.baseColor, d.baseColor.r, d.baseColor.g, d.baseColor.b);
      gl.Uniform3f(p.u.sheathColor, d.sheathColor.r, d.sheathColor.g, d.sheathColor.b);
      gl.Uniform2f(p.u.barbuleCosSin, std::cos(d.barbuleAngle), std::sin(d.barbuleAngle));
      gl.Uniform1f(p.u.specular, d.specular);
      const float cone = std::max(d.coneSigma, 1e-3f);
      gl.Uniform1f(p.u.coneInv2s2, 1.0f / (2.0f * cone * cone));
      gl.Uniform1f(p.u.translucency, d.translucency);
      r.drawIndicesBounded(run.first, run.count, sinceWait);
      ++stats_.drawCalls;
      ++stats_.drawRanges;
    }
    gl.DepthMask(GL_TRUE);
    gl.Disable(GL_BLEND);
  }
  gl.BindVertexArray(0);
  gl.UseProgram(0);
  const GLenum err = gl.GetError();
  PTERYLA_CHECK(err == GL_NO_ERROR, "OpenGL error " + std::to_string(err) + " while rendering");
}

Image Renderer::renderImage(const Camera& camera, const std::vector<Light>& lights, const RenderSettings& s) {
  if (s.width <= 0 || s.height <= 0) throw Error("render size must be positive", {}, "width/height");
  Impl& r = *impl_;
  r.ctx.makeCurrent();
  GLint maxSamples = 0;
  r.gl.GetIntegerv(GL_MAX_SAMPLES, &maxSamples);
  const int samples = std::clamp(s.msaaSamples, 0, std::max(0, int(maxSamples)));
  // Remember the caller's framebuffer before ensureTarget, which binds the target while creating it.
  GLint previous = 0;
  r.gl.GetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  r.ensureTarget(s.width, s.height, samples);
  r.gl.BindFramebuffer(GL_FRAMEBUFFER, samples > 0 ? r.target.msFbo : r.target.fbo);
  render(camera, lights, s);
  if (samples > 0) {
    r.gl.BindFramebuffer(GL_READ_FRAMEBUFFER, r.target.msFbo);
    r.gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, r.target.fbo);
    r.gl.BlitFramebuffer(0, 0, s.width, s.height, 0, 0, s.width, s.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  r.gl.BindFramebuffer(GL_FRAMEBUFFER, r.target.fbo);
  Image img = readPixels(s.width, s.height);
  r.gl.BindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  return img;
}

void Renderer::clearWindow(int width, int height, const glm::vec3& color) {
  if (width <= 0 || height <= 0) throw Error("window size must be positive", {}, "width/height");
  Impl& r = *impl_;
  r.ctx.makeCurrent();
  r.gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  r.gl.Viewport(0, 0, width, height);
  r.gl.ClearColor(color.r, color.g, color.b, 1.0f);
  r.gl.Clear(GL_COLOR_BUFFER_BIT);
}

Image Renderer::readPixels(int width, int height) {
  if (width <= 0 || height <= 0) throw Error("readback size must be positive");
  Impl& r = *impl_;
  r.ctx.makeCurrent();
  Image img(width, height);
  std::vector<uint8_t> raw(img.rgba.size());
  r.gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  r.gl.Finish();
  r.gl.ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, raw.data());
  const size_t row = static_cast<size_t>(width) * 4;
  for (int y = 0; y < height; ++y) std::memcpy(img.rgba.data() + row * y, raw.data() + row * (height - 1 - y), row);
  const GLenum err = r.gl.GetError();
  PTERYLA_CHECK(err == GL_NO_ERROR, "OpenGL error " + std::to_string(err) + " while reading pixels");
  return img;
}

std::string Renderer::glVersion() const {
  Impl& r = *impl_;
  r.ctx.makeCurrent();
  auto str = [&](GLenum e) {
    const GLubyte* s = r.gl.GetString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_VERSION) + " / " + str(GL_RENDERER);
}

}  // namespace pteryla::render
