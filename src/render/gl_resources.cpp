// The renderer's GL resources: shader programs (uniform locations resolved at link time), textures
// (images, the per-material BRDF tables of brdf_table.hpp), vertex and index buffers, off-screen
// framebuffers.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "pteryla/core/error.hpp"
#include "renderer_impl.hpp"

namespace pteryla::render {
using namespace detail;

void Renderer::Impl::setFastFilter(bool fast) {
  if (fast == fastFilter) return;
  fastFilter = fast;
  for (const GpuMaterial& m : materials) {
    for (GLuint t : {m.colorTex, m.alphaTex}) {
      if (t == white) continue;
      gl.BindTexture(GL_TEXTURE_2D, t);
      gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, minFilter());
    }
  }
}

GLuint Renderer::Impl::compile(GLenum type, std::initializer_list<const char*> parts) {
  GLuint s = gl.CreateShader(type);
  const std::vector<const char*> src(parts);
  gl.ShaderSource(s, static_cast<GLsizei>(src.size()), src.data(), nullptr);
  gl.CompileShader(s);
  GLint ok = 0;
  gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    gl.GetShaderInfoLog(s, sizeof log, nullptr, log);
    gl.DeleteShader(s);
    PTERYLA_CHECK(false, std::string("shader compilation failed: ") + log);
  }
  return s;
}

Program Renderer::Impl::link(GLuint v, GLuint f) {
  Program p;
  p.id = gl.CreateProgram();
  gl.AttachShader(p.id, v);
  gl.AttachShader(p.id, f);
  gl.LinkProgram(p.id);
  gl.DeleteShader(v);
  gl.DeleteShader(f);
  GLint ok = 0;
  gl.GetProgramiv(p.id, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    gl.GetProgramInfoLog(p.id, sizeof log, nullptr, log);
    PTERYLA_CHECK(false, std::string("shader link failed: ") + log);
  }
#define PTERYLA_UNIFORM_LOCATION(member, name) p.u.member = gl.GetUniformLocation(p.id, name);
  PTERYLA_UNIFORMS(PTERYLA_UNIFORM_LOCATION)
#undef PTERYLA_UNIFORM_LOCATION
  return p;
}

void Renderer::Impl::setSampling(GLint minification, GLint wrapS, GLint wrapT) {
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, minification);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrapS);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrapT);
}

void Renderer::Impl::bindTextures(std::initializer_list<GLuint> textures) {
  GLenum unit = GL_TEXTURE0;
  for (GLuint t : textures) {
    gl.ActiveTexture(unit++);
    gl.BindTexture(GL_TEXTURE_2D, t);
  }
}

GLuint Renderer::Impl::makeTexture(const Image& source, bool mipmap, GLint wrapS, GLint wrapT) {
  // Larger than the GL implementation allows (a 20000x1 strip): scaled down to fit instead of a GL error.
  GLint maxSide = 0;
  gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &maxSide);
  const bool tooLarge = maxSide > 0 && (source.width > maxSide || source.height > maxSide);
  const Image fitted = tooLarge ? fitImage(source, maxSide) : Image();
  const Image& img = tooLarge ? fitted : source;
  // Image rows are top-first; texture t = 0 is the bottom row.
  std::vector<uint8_t> flipped(img.rgba.size());
  const size_t row = static_cast<size_t>(img.width) * 4;
  for (int y = 0; y < img.height; ++y)
    std::memcpy(flipped.data() + row * (img.height - 1 - y), img.rgba.data() + row * y, row);
  GLuint t = 0;
  gl.GenTextures(1, &t);
  gl.BindTexture(GL_TEXTURE_2D, t);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, img.width, img.height, 0, GL_RGBA, GL_UNSIGNED_BYTE, flipped.data());
  setSampling(mipmap ? minFilter() : GL_LINEAR, wrapS, wrapT);
  if (mipmap) gl.GenerateMipmap(GL_TEXTURE_2D);
  return t;
}

GLuint Renderer::Impl::brdfTexture(const BarbuleParams& b) {
  const auto key = std::make_tuple(b.d, b.h, b.sigma);
  auto it = brdfCache.find(key);
  if (it != brdfCache.end()) return it->second;
  const BrdfTable table = buildBrdfTable(b, 128);
  GLuint t = 0;
  gl.GenTextures(1, &t);
  gl.BindTexture(GL_TEXTURE_2D, t);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, table.size, table.size, 0, GL_RG, GL_FLOAT, table.data.data());
  setSampling(GL_LINEAR, GL_CLAMP_TO_EDGE, GL_CLAMP_TO_EDGE);
  brdfCache[key] = t;
  return t;
}

void Renderer::Impl::releaseMaterials() {
  for (auto& [path, t] : fileTextures) gl.DeleteTextures(1, &t);
  fileTextures.clear();
  for (auto& m : materials) {
    // Textures from files are shared through fileTextures; in-memory ones are owned here.
    if (m.desc.colorTexture.empty() && m.colorTex != white) gl.DeleteTextures(1, &m.colorTex);
    if (m.desc.alphaTexture.empty() && m.alphaTex != white) gl.DeleteTextures(1, &m.alphaTex);
  }
  materials.clear();
}

void Renderer::Impl::releaseMesh(GpuMesh& m) {
  if (m.vao) gl.DeleteVertexArrays(1, &m.vao);
  gl.DeleteBuffers(kAttrCount, m.vbo);
  if (m.ebo) gl.DeleteBuffers(1, &m.ebo);
  m = GpuMesh();
}

void Renderer::Impl::releaseTarget() {
  Target& t = target;
  if (t.fbo) gl.DeleteFramebuffers(1, &t.fbo);
  if (t.msFbo) gl.DeleteFramebuffers(1, &t.msFbo);
  GLuint rbs[3] = {t.color, t.depth, t.msColor};
  for (GLuint rb : rbs)
    if (rb) gl.DeleteRenderbuffers(1, &rb);
  if (t.msDepthTex) gl.DeleteTextures(1, &t.msDepthTex);
  t = Target();
}

namespace {

// The arrays are uploaded as TriMesh holds them (core/packed.hpp), with no converted copy: float
// positions and texture coordinates, unit vectors as three signed normalized 16-bit integers (the shaders
// read floats; error under 2e-5), alpha, sheath and barb count as half floats. Texture coordinates stay
// float: quantized to 16 bits, the nearest-texel look-ups of fastTextureFiltering flipped at texel borders
// (up to 28/255 on 15 pixels of the bird), where packed normals change at most 2/255 on a few pixels.
template <class T>
struct GpuFormat;
template <>
struct GpuFormat<glm::vec3> {
  static constexpr GLint comps = 3;
  static constexpr GLenum type = GL_FLOAT;
  static constexpr GLboolean normalized = GL_FALSE;
};
template <>
struct GpuFormat<glm::vec2> {
  static constexpr GLint comps = 2;
  static constexpr GLenum type = GL_FLOAT;
  static constexpr GLboolean normalized = GL_FALSE;
};
template <>
struct GpuFormat<PackedDir> {
  static constexpr GLint comps = 3;
  static constexpr GLenum type = GL_SHORT;
  static constexpr GLboolean normalized = GL_TRUE;
};
template <>
struct GpuFormat<Half> {
  static constexpr GLint comps = 1;
  static constexpr GLenum type = GL_HALF_FLOAT;
  static constexpr GLboolean normalized = GL_FALSE;
};

}  // namespace

template <class T>
void Renderer::Impl::syncAttr(GpuMesh& m, Attr a, const std::vector<T>& data, size_t vertexCount, const char* name) {
  if (data.empty()) {
    m.present[a] = false;
    gl.DisableVertexAttribArray(a);
    return;
  }
  if (data.size() != vertexCount)
    throw Error(std::string("mesh attribute '") + name + "' has " + std::to_string(data.size()) + " entries for " +
                    std::to_string(vertexCount) + " vertices",
                {}, name);
  const size_t bytes = data.size() * sizeof(T);
  if (!m.vbo[a]) gl.GenBuffers(1, &m.vbo[a]);
  gl.BindBuffer(GL_ARRAY_BUFFER, m.vbo[a]);
  if (bytes == m.vboBytes[a])
    gl.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), data.data());
  else
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes), data.data(), GL_STATIC_DRAW);
  gl.VertexAttribPointer(a, GpuFormat<T>::comps, GpuFormat<T>::type, GpuFormat<T>::normalized,
                         static_cast<GLsizei>(sizeof(T)), nullptr);
  m.vboBytes[a] = bytes;
  gl.EnableVertexAttribArray(a);
  m.present[a] = true;
}

void Renderer::Impl::applyDefaults(const GpuMesh& m) {
  if (!m.present[kNormal]) gl.VertexAttrib3f(kNormal, 0, 0, 1);
  if (!m.present[kTangent]) gl.VertexAttrib3f(kTangent, 1, 0, 0);
  if (!m.present[kUvGlobal]) gl.VertexAttrib2f(kUvGlobal, 0, 0);
  if (!m.present[kUvBarb]) gl.VertexAttrib2f(kUvBarb, 0.5f, 0.5f);
  if (!m.present[kUvGrowth]) gl.VertexAttrib2f(kUvGrowth, 0, 0);
  if (!m.present[kAlpha]) gl.VertexAttrib1f(kAlpha, 1.0f);
  if (!m.present[kSheath]) gl.VertexAttrib1f(kSheath, 0.0f);
  if (!m.present[kBarbCount]) gl.VertexAttrib1f(kBarbCount, 1.0f);
}

void Renderer::Impl::upload(GpuMesh& m, const TriMesh& mesh, const std::vector<PackedDir>* normalsOverride,
                            bool staticIndices) {
  if (mesh.indices.size() % 3 != 0) throw Error("mesh index count is not a multiple of 3", {}, "indices");
  const size_t nv = mesh.vertexCount();
  for (size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= nv)
      throw Error(
          "mesh index " + std::to_string(mesh.indices[i]) + " out of range (" + std::to_string(nv) + " vertices)", {},
          "face " + std::to_string(i / 3));
  if (!m.vao) gl.GenVertexArrays(1, &m.vao);
  gl.BindVertexArray(m.vao);
  syncAttr(m, kPos, mesh.positions, nv, "positions");
  syncAttr(m, kNormal, normalsOverride ? *normalsOverride : mesh.normals, nv, "normals");
  syncAttr(m, kTangent, mesh.tangents, nv, "tangents");
  syncAttr(m, kUvGlobal, mesh.uvGlobal, nv, "uvGlobal");
  syncAttr(m, kUvBarb, mesh.uvBarb, nv, "uvBarb");
  syncAttr(m, kUvGrowth, mesh.uvGrowth, nv, "uvGrowth");
  syncAttr(m, kAlpha, mesh.alpha, nv, "alpha");
  syncAttr(m, kSheath, mesh.sheath, nv, "sheath");
  syncAttr(m, kBarbCount, mesh.barbCount, nv, "barbCount");
  // Static indices (skin), or none here: the coat's are written every frame (streamIndices).
  const size_t n = mesh.indices.size();
  if (!m.ebo) gl.GenBuffers(1, &m.ebo);
  if (staticIndices) streamIndices(m, mesh.indices.data(), mesh.indices.size(), GL_STATIC_DRAW);
  m.indexCount = n;
  gl.BindVertexArray(0);
}

void Renderer::Impl::streamIndices(GpuMesh& m, const uint32_t* indices, size_t count, GLenum usage) {
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
  const size_t bytes = count * sizeof(uint32_t);
  if (bytes <= m.eboBytes && bytes > 0 && usage == GL_STREAM_DRAW) {
    gl.BufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), indices);
  } else {
    gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes), count ? indices : nullptr, usage);
    m.eboBytes = bytes;
  }
}

void Renderer::Impl::drawIndices(size_t first, size_t count) {
  if (count == 0) return;
  gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                  reinterpret_cast<const void*>(first * sizeof(uint32_t)));
}

void Renderer::Impl::drawIndicesBounded(size_t first, size_t count, size_t& since) {
  for (const size_t end = first + count; first < end;) {
    const size_t n = std::min(kWaitIndices - since, end - first);
    drawIndices(first, n);
    first += n;
    since += n;
    if (since == kWaitIndices) {
      gl.Finish();
      since = 0;
    }
  }
}

void Renderer::Impl::ensureTarget(int w, int h, int samples) {
  Target& t = target;
  if (t.fbo && t.width == w && t.height == h && t.samples == samples) return;
  releaseTarget();
  t.width = w;
  t.height = h;
  t.samples = samples;
  // `depthTex`: the multisampled depth as a texture (the occlusion pass reads its samples), else a
  // renderbuffer.
  auto makeFbo = [&](GLuint& fbo, GLuint& color, GLuint* depth, GLuint* depthTex, int s) {
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    // One renderbuffer of `format` with `s` samples (0: single-sampled) at `attachment`.
    auto attach = [&](GLuint& rb, GLenum format, GLenum attachment) {
      gl.GenRenderbuffers(1, &rb);
      gl.BindRenderbuffer(GL_RENDERBUFFER, rb);
      if (s > 0)
        gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, s, format, w, h);
      else
        gl.RenderbufferStorage(GL_RENDERBUFFER, format, w, h);
      gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, rb);
    };
    attach(color, GL_RGBA8, GL_COLOR_ATTACHMENT0);
    if (depthTex) {
      gl.GenTextures(1, depthTex);
      gl.BindTexture(GL_TEXTURE_2D_MULTISAMPLE, *depthTex);
      gl.TexImage2DMultisample(GL_TEXTURE_2D_MULTISAMPLE, s, GL_DEPTH24_STENCIL8, w, h, GL_TRUE);
      gl.BindTexture(GL_TEXTURE_2D_MULTISAMPLE, 0);
      gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D_MULTISAMPLE, *depthTex, 0);
    } else {
      attach(*depth, GL_DEPTH24_STENCIL8, GL_DEPTH_STENCIL_ATTACHMENT);
    }
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("cannot create an off-screen framebuffer of " + std::to_string(w) + "x" + std::to_string(h) +
                  (s > 0 ? " with " + std::to_string(s) + " samples" : std::string()));
  };
  makeFbo(t.fbo, t.color, &t.depth, nullptr, 0);
  if (samples > 0) makeFbo(t.msFbo, t.msColor, nullptr, &t.msDepthTex, samples);
}

}  // namespace pteryla::render
