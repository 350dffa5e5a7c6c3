#pragma once
// Renderer::Impl, the GL state behind Renderer, shared by renderer.cpp (set-up and frames),
// gl_resources.cpp (programs, textures, meshes, framebuffers) and shadow_pass.cpp (the key light's
// shadow map). Private to src/render.
#include <initializer_list>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "gl_api.hpp"
#include "pteryla/core/trimesh.hpp"
#include "pteryla/render/draw_plan.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/renderer.hpp"

namespace pteryla::render {
namespace detail {

enum Attr : GLuint { kPos, kNormal, kTangent, kUvGlobal, kUvBarb, kUvGrowth, kAlpha, kSheath, kBarbCount, kAttrCount };

// Every uniform of the four programs (shaders.hpp). Each program resolves all of them once, when it is
// linked; one it lacks stays -1, which glUniform* ignores.
#define PTERYLA_UNIFORMS(X)                    \
  X(viewProj, "uViewProj")                     \
  X(colorUv, "uColorUv")                       \
  X(isCoat, "uIsCoat")                         \
  X(eye, "uEye")                               \
  X(ambient, "uAmbient")                       \
  X(lightCount, "uLightCount")                 \
  X(lightDir, "uLightDir")                     \
  X(lightColor, "uLightColor")                 \
  X(lightViewProj, "uLightViewProj")           \
  X(shadowLightDir, "uShadowLightDir")         \
  X(shadowNormalOffset, "uShadowNormalOffset") \
  X(shadowMap, "uShadowMap")                   \
  X(shadows, "uShadows")                       \
  X(shadowStrength, "uShadowStrength")         \
  X(shadowTexel, "uShadowTexel")               \
  X(exposureScale, "uExposureScale")           \
  X(filmic, "uFilmic")                         \
  X(skinColor, "uSkinColor")                   \
  X(colorTex, "uColorTex")                     \
  X(alphaTex, "uAlphaTex")                     \
  X(brdfTex, "uBrdfTex")                       \
  X(useAlphaTex, "uUseAlphaTex")               \
  X(useBrdf, "uUseBrdf")                       \
  X(baseColor, "uBaseColor")                   \
  X(sheathColor, "uSheathColor")               \
  X(barbuleCosSin, "uBarbuleCosSin")           \
  X(specular, "uSpecular")                     \
  X(coneInv2s2, "uConeInv2s2")                 \
  X(translucency, "uTranslucency")             \
  X(alphaCut, "uAlphaCut")                     \
  X(depthMS, "uDepthMS")                       \
  X(samples, "uSamples")
struct Uniforms {
#define PTERYLA_UNIFORM_MEMBER(member, name) GLint member = -1;
  PTERYLA_UNIFORMS(PTERYLA_UNIFORM_MEMBER)
#undef PTERYLA_UNIFORM_MEMBER
};

struct Program {
  GLuint id = 0;
  Uniforms u;
};

struct GpuMesh {
  GLuint vao = 0;
  GLuint vbo[kAttrCount] = {};
  size_t vboBytes[kAttrCount] = {};
  bool present[kAttrCount] = {};
  GLuint ebo = 0;
  size_t eboBytes = 0;
  size_t indexCount = 0;
};

struct GpuMaterial {
  GLuint colorTex = 0, alphaTex = 0, brdfTex = 0;
  FeatherMaterial desc;
};

struct Target {
  GLuint fbo = 0, color = 0, depth = 0;
  GLuint msFbo = 0, msColor = 0;
  GLuint msDepthTex = 0;  // multisampled depth as a texture (the occlusion pass reads its samples)
  int width = 0, height = 0, samples = 0;
};

}  // namespace detail

struct Renderer::Impl {
  using Attr = detail::Attr;
  using Program = detail::Program;
  using GpuMesh = detail::GpuMesh;
  using GpuMaterial = detail::GpuMaterial;
  using Target = detail::Target;

  RenderContext& ctx;
  GlApi gl;
  Program skinProg, coatVertexProg, coatFragmentProg, depthProg, resolveProg;
  GpuMesh skin, coat, ground;
  std::vector<float> groundKey;  // what the ground quad was built from
  // The key light's shadow map (RenderSettings::shadows) and what it was drawn from: it is drawn again
  // only when one of these changes. It draws every coat index, streamed into the coat's element buffer
  // (which each frame then rewrites with the camera's surviving triangles).
  struct Shadow {
    GLuint fbo = 0, depthTex = 0;
    int size = 0;
    bool valid = false;  // the map matches skin, coat and materials (cleared when they change)
    glm::vec3 lightDir{0.0f};
    bool alphaTexture = true;
    glm::mat4 viewProj{1.0f};
    float texelWorld = 0.0f;  // scene units per texel
    size_t triangles = 0;     // coat triangles drawn into the map when it was last drawn
  } shadow;
  glm::vec3 skinLo{0.0f}, skinHi{0.0f};
  bool hasSkinBounds = false;
  // The coat's CPU mirror and each frame's plan (culling, draw order, material runs): the frame's
  // surviving indices are streamed into the coat's element buffer and drawn one call per run.
  DrawPlan plan;
  std::vector<float> depth;  // skin depth read back for occlusion culling
  DepthTiles occluders;      // the same, reduced to tiles
  std::vector<GpuMaterial> materials;
  std::map<std::string, GLuint> fileTextures;  // path -> texture, per setMaterials
  std::map<std::tuple<double, double, double>, GLuint> brdfCache;
  GLuint white = 0;
  bool fastFilter = true;  // minification filter of colour / alpha textures (RenderSettings)
  Target target;

  explicit Impl(RenderContext& c) : ctx(c) {}

  GLint minFilter() const { return fastFilter ? GL_NEAREST_MIPMAP_NEAREST : GL_LINEAR_MIPMAP_NEAREST; }

  // gl_resources.cpp
  void setFastFilter(bool fast);
  GLuint compile(GLenum type, std::initializer_list<const char*> parts);
  Program link(GLuint v, GLuint f);
  // Filtering (magnification bilinear) and wrapping of the texture bound to GL_TEXTURE_2D.
  void setSampling(GLint minification, GLint wrapS, GLint wrapT);
  // Binds `textures` to texture units 0, 1, ... in order.
  void bindTextures(std::initializer_list<GLuint> textures);
  GLuint makeTexture(const Image& source, bool mipmap, GLint wrapS, GLint wrapT);
  GLuint brdfTexture(const BarbuleParams& b);
  void releaseMaterials();
  void releaseMesh(GpuMesh& m);
  void releaseTarget();
  template <class T>
  void syncAttr(GpuMesh& m, Attr a, const std::vector<T>& data, size_t vertexCount, const char* name);
  // Generic attribute values are context state, not VAO state: set them before each mesh's draw.
  void applyDefaults(const GpuMesh& m);
  void upload(GpuMesh& m, const TriMesh& mesh, const std::vector<PackedDir>* normalsOverride, bool staticIndices);
  void streamIndices(GpuMesh& m, const uint32_t* indices, size_t count, GLenum usage);
  // drawIndices in pieces, waiting for llvmpipe after every kWaitIndices indices (`since` counts the
  // indices drawn since the last wait, across calls): llvmpipe keeps each binned triangle (about 400
  // bytes with 4x multisampling) until the rasterizer is done with it, and a flush alone frees none, so
  // a coat of millions of triangles held gigabytes. A wait per 131,072 triangles bounds that at about
  // 55 MB and costs no time (measured against waits per 65k and 524k triangles).
  static constexpr size_t kWaitIndices = 3 * (size_t(1) << 17);
  void drawIndicesBounded(size_t first, size_t count, size_t& since);
  void drawIndices(size_t first, size_t count);
  void ensureTarget(int w, int h, int samples);

  // shadow_pass.cpp
  void releaseShadow();
  // Bounds of everything that casts or receives shadows: the skin and the coat's feathers.
  bool shadowBounds(glm::vec3& lo, glm::vec3& hi) const;
  // Draws the depth map of the skin and the alpha-tested coat seen from the key light (unit direction
  // toward the light), orthographic over the bounding sphere of both; keeps the previous map when
  // nothing it depends on changed. Leaves the caller's framebuffer and viewport bound.
  bool updateShadowMap(const glm::vec3& toLight, const RenderSettings& s);
};

}  // namespace pteryla::render
