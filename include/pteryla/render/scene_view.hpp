#pragma once
// SceneView: draws what a Pipeline evaluated (posed skin + packed coat) with the Renderer, using the
// scene's camera, lights, materials and render settings. Shared by the CLI (OSMesa), the viewer (GLFW)
// and the golden tests, so a frame looks the same everywhere. Owns no model state: it re-uploads the
// meshes when the pipeline's results change.
#include <memory>
#include <string>

#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/render/camera.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/renderer.hpp"

namespace pteryla::feather {
struct FeatherParams;
}

namespace pteryla::render {

// Camera for the scene: explicit eye/target, or framing the bounds of the posed skin and the coat mesh
// (auto_frame).
Camera sceneCamera(const pipeline::Scene& scene, const TriMesh& skin, const TriMesh& coat, int width, int height);
// The same from given bounds (lo, hi are read only for auto_frame).
Camera sceneCameraForBounds(const pipeline::Scene& scene, const glm::vec3& lo, const glm::vec3& hi, int width,
                            int height);
// Bounds of the posed skin grown by the coat's reach, without meshing the coat: every present feather of
// p.feathers() placed at its packed elevation from a coarse copy of its parameters (its shaft, and 12
// barbs a vane as control polygons, which contain the barb curves). Pulls the pack stage, never the mesh
// stage. What SceneView::render frames with screen-size levels of detail, so choosing the levels costs
// no mesh of the coat at a uniform level. False when there is neither skin nor coat.
bool coatReachBounds(pipeline::Pipeline& p, glm::vec3& lo, glm::vec3& hi);
std::vector<Light> sceneLights(const pipeline::Scene& scene);
RenderSettings sceneSettings(const pipeline::Scene& scene, int width, int height);
// Renderer materials for the coat's feather types: colour texture from the feather file, else the
// pattern named in it (data/textures/<pattern>.png or a synthesized one), barb alpha mask, BRDF d/h.
std::vector<FeatherMaterial> sceneMaterials(const pipeline::Scene& scene, const pipeline::CoatMesh& coat);
std::vector<FeatherDrawRange> drawRanges(const pipeline::CoatMesh& coat);

// Screen-size level of detail (Streit 2003, 7.1.3; scene render.lod_by_screen_size): per feather of
// p.feathers(), the fraction of its barbs that keeps the kept barbs about `pixelsPerBarb` apart on
// screen: clamp(L / (pixelsPerBarb x n), minFraction, 1), where L is the projected length in pixels of
// the packed rachis (the screen diameter of the sphere around it) and n = rachis length / mean barb
// spacing is the number of barbs along one vane. Barbs closer than that merge into polygons whose
// alpha mask repeats the barbs they stand for, so the look is kept. Hand the result to
// Pipeline::setFeatherLods, which multiplies it with the scene's lod. Absent feathers get 1.
std::vector<double> screenSizeLods(pipeline::Pipeline& p, const Camera& camera, int width, int height,
                                   double pixelsPerBarb = 2.0, double minFraction = pipeline::kMinScreenLodFraction);

Image renderFeatherImage(RenderContext& context, const feather::FeatherParams& params, const TriMesh& mesh, int width,
                         int height);

class SceneView {
 public:
  explicit SceneView(RenderContext& context);
  ~SceneView();
  // Uploads the pipeline's current skin and coat (when they changed) and renders an image. The renderer
  // reads the coat mesh's positions and indices where the pipeline keeps them
  // (Renderer::CoatStorage::Reference): render and draw bring it up to date first, so draw only through
  // them, from the thread that evaluates the pipeline.
  // style: "" (the scene's), "shaded" or "scratchboard". With the scene's render.lod_by_screen_size
  // (the default), first sets the pipeline's per-feather levels of detail from the scene camera
  // (screenSizeLods; an auto-framed camera frames coatReachBounds), so the coat is meshed once, at those
  // levels; without it, clears them and an auto-framed camera frames the coat's mesh.
  Image render(pipeline::Pipeline& p, int width, int height, const std::string& style = "");
  // Draws into the current framebuffer (viewer); `camera` overrides the scene camera.
  void draw(pipeline::Pipeline& p, const Camera& camera, int width, int height);
  Renderer& renderer();
  // Forces a re-upload on the next render (after edits the view cannot detect).
  void markDirty();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pteryla::render
