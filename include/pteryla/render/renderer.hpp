#pragma once
// Renderer: draws a skin mesh and a feather coat with OpenGL 3.3 core (Streit 2003, chapter 7).
//  - 7.1.1-7.1.3 per-feather material: colour pattern texture x base colour, barb alpha texture
//    repeated barbCount times across a polygon, per-vertex alpha, and the Poulin-Fournier barbule
//    reflection looked up twice per light (barbules on each side of the barb) in a tabulated BRDF
//    texture (brdf_table.hpp), per vertex by default or per fragment (RenderSettings::brdfPerFragment);
//  - 7.1.2 / 7.2 draw order for alpha blending: the skin first writing depth, then the feathers in
//    the order of their draw ranges (layer order) with depth test on and depth writes off, each
//    feather's parts in view-dependent (octant) order.
// The renderer owns no model state: setSkin / setCoat copy the TriMesh attributes into GL buffers
// (reusing buffers when sizes match) and keep no reference to the mesh; call them again whenever
// the mesh changes. All calls need the renderer's context to be current (the renderer makes it
// current in its constructor and in each call that touches GL).
//
// Vertex attributes read from TriMesh (absent arrays take the defaults of TriMesh::append):
//  positions, normals (macro normal; the renderer flips it toward the viewer, so both sides of a
//  vane shade), tangents (barb direction, for the BRDF), uvGlobal / uvBarb / uvGrowth (colour UVs,
//  chosen per material), uvBarb also addresses the alpha mask: uvBarb.x in [0,1] across the polygon,
//  uvBarb.y in [0,1] along the barb from the rachis to the barb tip; the mask is sampled at
//  (uvBarb.x * barbCount, uvBarb.y) with repeat across. alpha multiplies opacity; sheath in [0,1]
//  blends toward the opaque sheath colour (pin feathers, 8.1). featherId is not used for drawing.
// Texture images are top row first: row 0 of a colour pattern is v = 1 (the feather tip).
// Which feathers and triangles a frame draws, in which order and in how many calls, is decided on
// the CPU by a DrawPlan (draw_plan.hpp): feathers whose bounds fall outside the view, or
// (RenderSettings::occlusionCulling) entirely behind the skin's depth, are skipped; so are, within the
// other feathers, runs of a few barbs (32 triangles) and then single triangles that lie behind the
// skin or outside the view (conservative tests against the skin depth read back once per frame: the
// image is unchanged). The surviving triangles are written into one index buffer per frame in draw
// order and drawn with one call per run of feathers sharing a material. RenderStats reports the counts.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/render/brdf_table.hpp"
#include "pteryla/render/camera.hpp"
#include "pteryla/render/context.hpp"
#include "pteryla/render/draw_plan.hpp"
#include "pteryla/render/image.hpp"

namespace pteryla::render {

enum class ColorUv { Global, Barb, Growth };  // which TriMesh uv set addresses the colour texture

// One feather type's look. A texture comes from `...Texture` (a file path; loaded with
// OpenImageIO) or, when the path is empty, from `...Image` (in memory, e.g. generatePattern()).
// Neither: the colour texture is white, the alpha mask is opaque.
struct FeatherMaterial {
  std::string name;           // for error messages
  glm::vec3 baseColor{1.0f};  // multiplies the colour texture, linear [0,1]
  std::string colorTexture;
  Image colorImage;
  ColorUv colorUv = ColorUv::Global;
  std::string alphaTexture;  // barb alpha mask, red channel used
  Image alphaImage;
  bool useBrdf = true;                    // false: Lambertian vane
  BarbuleParams barbules{1.0, 0.0, 0.2};  // Poulin-Fournier d, h, sigma
  float barbuleAngle = 0.7f;              // radians between barb and its barbules (both sides)
  float specular = 0.25f;                 // weight of the S channel
  float coneSigma = 0.35f;                // width of the glint cone exp(-(L.T+V.T)^2 / 2 s^2)
  float translucency = 0.15f;             // light passed through a vane lit from behind
  glm::vec3 sheathColor{0.55f, 0.60f, 0.68f};
};

struct RenderSettings {
  int width = 512;  // pixels
  int height = 512;
  glm::vec4 background{1.0f, 1.0f, 1.0f, 1.0f};
  glm::vec3 ambient{0.18f};  // ambient light, linear
  glm::vec3 skinColor{0.62f, 0.50f, 0.45f};
  bool drawSkin = true;
  bool drawCoat = true;
  bool useAlphaTexture = true;     // false: per-vertex alpha only (Fig. 7.2 b)
  bool useBrdf = true;             // global switch over FeatherMaterial::useBrdf
  bool viewDependentOrder = true;  // false: every range drawn forward (for comparisons)
  int msaaSamples = 0;             // renderImage only; 0 for golden images
  // Where the coat's lighting (BRDF look-ups included) is evaluated. false: per vertex, as the
  // thesis computes the projected angles per vertex (7.1.3); about twice as fast on llvmpipe and
  // indistinguishable at full geometry. true: per fragment, for close-ups of coarse LOD polygons.
  bool brdfPerFragment = false;
  // Skip feathers, runs of barbs and triangles that lie entirely behind the skin (the skin's depth is
  // read back once per frame; with renderImage's multisampling, the farthest depth of each pixel's
  // samples) or outside the view. Exact for opaque skin; turn off to measure raw throughput.
  bool occlusionCulling = true;
  // Skip feather triangles that cover no sample point (within 0.05 px): the pixel centres, or with
  // multisampling the rasterizer's sample positions (GL_SAMPLE_POSITION). They produce no fragment, but
  // llvmpipe still shades their vertices and sets them up. The same test, against the map's texel
  // centres, thins the shadow pass. The image is unchanged; off in wireframe.
  bool subpixelCulling = true;
  // Draw the triangles' edges only (a modelling view); shadows and sub-pixel culling are off with it (the
  // map would be drawn in lines too; an edge shows even where its triangle covers no pixel centre).
  bool wireframe = false;
  // Minified colour and alpha textures: true samples the nearest texel of the nearest mip level
  // (about 20% faster on llvmpipe); false filters bilinearly within it. Magnification is bilinear.
  bool fastTextureFiltering = true;
  // Coat self-shadowing: light 0 (the key light) casts shadows of the skin and the coat onto both, from
  // an orthographic depth map over their bounds (shadowMapSize texels on a side). Feathers are
  // alpha-tested into the map (the colour pass's alpha, kept above 0.5), so barbs cast barb-shaped
  // shadows. In full shadow the key light is scaled by 1 - shadowStrength (the rest stands for the
  // light the coat scatters). The map is re-rendered only when the skin, coat, materials, key light
  // direction or these settings change. Scenes turn it on by default (render.shadows).
  bool shadows = false;
  int shadowMapSize = 2048;     // [64, 8192]
  float shadowStrength = 0.8f;  // [0, 1]
  // Tone: skin and feather colours are scaled by 2^exposure, then clamped (linear) or passed through a
  // filmic curve (Narkowicz's fit of the ACES reference: a toe, and a shoulder instead of clipping),
  // before blending. The background is drawn as given.
  float exposure = 0.0f;  // stops
  bool filmic = false;
  // A ground plane (opaque, Lambert, groundColor) facing groundNormal and touching the lowest point of
  // the skin's and coat's bounding box along it, drawn around the model: it receives the key light's
  // shadow (a contact shadow under the bird) and casts none.
  bool ground = false;
  glm::vec3 groundNormal{0.0f, 1.0f, 0.0f};
  glm::vec3 groundColor{0.72f, 0.72f, 0.70f};
};

struct RenderStats {
  size_t drawCalls = 0;            // GL draw submissions (the coat: one per run of feathers of one material)
  size_t drawRanges = 0;           // index ranges in those submissions
  size_t triangles = 0;            // triangles submitted (skin + feathers not culled)
  size_t backwardParts = 0;        // feather parts drawn in reverse order (view-dependent ordering at work)
  size_t culledFeathers = 0;       // feathers outside the view frustum, skipped
  size_t occludedFeathers = 0;     // feathers hidden behind the skin, skipped
  size_t occludedTriangles = 0;    // triangles of drawn feathers skipped: behind the skin (runs of a few
                                   // barbs, then single triangles) or outside the view
  size_t subpixelTriangles = 0;    // triangles of drawn feathers skipped for covering no sample point
  bool shadowMapRendered = false;  // the shadow map was (re)drawn for this frame (false: reused or off)
  size_t shadowTriangles = 0;      // coat triangles drawn into it then (sub-pixel culling drops those
                                   // covering no texel centre of the map)
};

class Renderer {
 public:
  // Makes `context` current, loads the GL functions it needs through it, compiles the shaders.
  // Throws pteryla::Error if the context lacks OpenGL 3.3 functionality. `context` must outlive
  // the renderer.
  explicit Renderer(RenderContext& context);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Uploads the skin (drawn opaque, Lambert + ambient). An empty mesh removes it. Needs normals
  // (computed per face-vertex average if absent). Throws pteryla::Error for out-of-range indices.
  void setSkin(const TriMesh& skin);
  // Uploads the coat and its per-feather ranges in layer order (drawn first to last). An empty
  // `ranges` draws the whole mesh as one feather with material 0. Validates ranges against the
  // mesh (pteryla::Error with element "ranges[i]").
  void setCoat(const TriMesh& coat, const std::vector<FeatherDrawRange>& ranges);
  // Copy: the renderer keeps the positions and indices its per-frame culling reads (about 20 bytes a
  // triangle). Reference: it reads them from `coat` itself whenever it draws, so `coat` must stay alive
  // and unchanged until the next setCoat (a caller that draws while another thread may rewrite the
  // mesh, as the viewer's evaluation does, copies).
  enum class CoatStorage { Copy, Reference };
  void setCoat(const TriMesh& coat, const std::vector<FeatherDrawRange>& ranges, CoatStorage storage);
  // Loads textures and builds one BRDF table per material. Throws pteryla::Error naming the file
  // (and the element "materials[i].colorTexture") for a missing or unreadable texture. With no
  // materials set, a default material (white, BRDF d=1 h=0) is used.
  void setMaterials(const std::vector<FeatherMaterial>& materials);

  // Draws into the framebuffer currently bound (framebuffer 0 of the context unless the caller bound
  // another) with viewport (0, 0, settings.width, settings.height). Up to 4 lights are used.
  void render(const Camera& camera, const std::vector<Light>& lights, const RenderSettings& settings);
  // Renders into an internal off-screen framebuffer of settings.width x settings.height (MSAA when
  // settings.msaaSamples > 0) and reads it back. Independent of the context's own framebuffer size.
  Image renderImage(const Camera& camera, const std::vector<Light>& lights, const RenderSettings& settings);
  // Reads the currently bound framebuffer's [0,w) x [0,h) region as RGBA8, top row first.
  Image readPixels(int width, int height);
  // Binds the context's own framebuffer (0: the window's), sets the viewport to width x height and clears
  // it to `color` (a window's background before its UI is drawn over it).
  void clearWindow(int width, int height, const glm::vec3& color);

  const RenderStats& lastStats() const { return stats_; }
  // GL_VERSION and GL_RENDERER of the context, for logs and golden-image READMEs.
  std::string glVersion() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  RenderStats stats_;
};

}  // namespace pteryla::render
