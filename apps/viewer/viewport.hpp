#pragma once
// The 3D view of the viewer: the results uploaded to the renderers (the skin as soon as a job publishes
// it, the coat and its materials once the evaluation is complete), the navigation coat drawn while the
// camera moves (navigation.hpp), the colour-by modes (colour_by.hpp), and the last image of the view kept
// in a texture that App draws behind the panels. The view is re-rendered only when what it shows changes
// (viewKey). It also frames the camera (initial framing, F, A) and captures screenshots.
//   viewport.cpp         layout, sync and uploads, the navigation coat, rendering, camera framing, capture
//   viewport_colour.cpp  colour-by: flat palette materials, per-feather ranges and the legend window
// It calls no GL itself: textures are render::ImageTexture, the renderers render::Renderer.
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "camera_controller.hpp"
#include "colour_by.hpp"
#include "document.hpp"
#include "panels.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/image_texture.hpp"
#include "pteryla/render/renderer.hpp"

namespace pteryla::viewer {

class GlfwContext;

// Layout of the window: menu bar, panel column on the left, status bar, the 3D view in the rest.
inline constexpr float kStatusHeight = 30.0f;

class Viewport {
 public:
  Viewport(Document& doc, ViewState& view, CameraController& camera);
  ~Viewport();
  // Once the window's GL context exists; releaseGl deletes every GL object in it (before the window goes).
  void attach(GlfwContext& context);
  void releaseGl();

  // The view rectangle from the window and framebuffer sizes and the panel column (ViewState::viewOrigin,
  // viewSize) and its size in framebuffer pixels.
  void layout(glm::ivec2 windowSize, glm::ivec2 fbSize, float menuHeight);
  glm::ivec2 pixels() const { return viewPixels_; }
  glm::ivec2 framebufferSize() const { return fbSize_; }
  // Results to the renderers; frames the camera when the skin (then the coat) first arrives.
  void sync();
  // Forgets the previous scene's uploads and camera (a scene was opened).
  void forgetScene();

  // Renders the 3D view into its texture when what it shows changed. `moving`: the camera moves (draw at
  // lower cost); `benchPass` fixes the coat drawn (orbit benchmark: 0 navigation, 1 full coat, else the
  // usual choice); `playing`: the timeline plays (with ViewState::fastPlayback, every feather at the moving
  // view's resolution and without multisampling). Returns what it drew.
  enum class Drawn {
    Nothing,   // the view was up to date
    Reduced,   // a moving view (the navigation coat or fewer pixels)
    Playback,  // every feather, at the fast playback quality
    Full,      // every feather at rest at full resolution and quality
  };
  Drawn render(bool moving, int benchPass, bool playing = false);
  // Shows an image instead (a flipbook frame); the live view is rendered again when asked next.
  void showImage(const render::Image& image);
  const render::Image& image() const { return viewImage_; }
  const render::ImageTexture* texture() const { return viewTexture_.get(); }
  double lastRenderSeconds() const { return lastRenderSeconds_; }
  // Everything the 3D image depends on besides the coat's time (viewKey; index 14 is the upload counter).
  std::vector<float> viewKey() const;
  static constexpr size_t kUploadKeyIndex = 14;
  // The document's result version the renderers hold, and the one the view last showed.
  uint64_t syncedResult() const { return syncedResult_; }
  uint64_t drawnResult() const { return drawnResult_; }
  // The evaluation is complete and uploaded (what a capture or the benchmark waits for).
  bool resultOnScreen() const;

  // The navigation coat (navigation.hpp): built, pending a rebuild, its triangles and stride.
  bool navigationReady() const { return navReady_; }
  bool navigationPending() const { return navNeeded_; }
  size_t navigationTriangles() const { return navTriangles_; }
  size_t navigationStride() const { return navStride_; }
  const render::Renderer& renderer() const { return *renderer_; }
  // Clears the window (ImGui draws over it).
  void clearWindow(int fbw, int fbh, const glm::vec3& colour);

  // Camera: ready once the skin arrived; moved by the user (then the coat is not framed on arrival).
  bool cameraReady() const { return cameraReady_; }
  void noteCameraMoved() { cameraMoved_ = true; }
  void frameAll();
  // Frames a box (the box selection) or the selected feather, else everything.
  void frameBox(const glm::vec3& lo, const glm::vec3& hi);
  void frameSelection();

  // Screenshots: the 3D view (or the whole window) written once the evaluation is complete and drawn.
  void requestScreenshot(const std::string& path, bool withUi);
  bool screenshotPending() const { return shot_.wanted; }
  struct Capture {
    enum Status { None, Written, NotEvaluated, Failed } status = None;
    std::string message;  // Written: what was written; Failed: the error
  };
  // Called after the 3D view (afterUi false) and after the panels (true) are drawn; `waitFrames`: a
  // --screenshot still waiting for its frame count.
  Capture capture(int fbw, int fbh, bool afterUi, bool waitFrames);

  // The colour mode's legend, bottom left of the 3D view (viewport_colour.cpp).
  void legendWindow();

 private:
  void initCamera();
  void uploadResults();
  void buildNavigationCoat(const pipeline::CoatMesh& coat);
  // Colour-by modes (viewport_colour.cpp): the draw ranges of `ranges` with each feather's material
  // replaced by its colour entry when a mode is on; the palette as render materials. updateColouring
  // recomputes colouring_ when the mode, the result or the check changed.
  std::vector<render::FeatherDrawRange> drawRangesFor(const std::vector<pipeline::CoatDrawRange>& ranges) const;
  std::vector<render::FeatherMaterial> paletteMaterials() const;
  bool updateColouring();

  Document& doc_;
  ViewState& view_;
  CameraController& camera_;
  GlfwContext* context_ = nullptr;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<render::Renderer> navRenderer_;  // the navigation coat (navigation.hpp)
  bool navReady_ = false, navNeeded_ = false;
  size_t navTriangles_ = 0, navStride_ = 1;
  glm::vec3 navSkinColor_{-1.0f};  // mean colour of the last full view, for the skin while navigating

  // View sync: results uploaded to the renderer, and the 3D view cached in a texture (re-rendered only
  // when the camera, the uploads or the look change, so panels stay fast over a heavy coat).
  uint64_t syncedResult_ = ~0ull, uploadedSkin_ = 0, meshEvals_ = ~0ull, uploadVersion_ = 0;
  uint64_t drawnResult_ = ~0ull;  // the result version (syncedResult_) the 3D view last showed
  std::vector<float> lastViewKey_;
  render::Image viewImage_;
  std::unique_ptr<render::ImageTexture> viewTexture_;
  double lastRenderSeconds_ = 0;
  // Adaptive navigation: smoothed full-coat render time while moving (< 0: not measured since the
  // last upload or view resize) and what it was measured for.
  double movingFullMs_ = -1.0;
  float movingFullKey_[3] = {-1.0f, -1.0f, -1.0f};  // upload version, view width, height
  bool cameraReady_ = false, cameraFramedCoat_ = false, cameraMoved_ = false;
  bool materialsStale_ = true;
  FeatherColouring colouring_;  // of view_.colourBy, for the uploaded coat
  std::vector<uint64_t> colourKey_;
  double lastBrdfD_ = -1, lastBrdfH_ = -1;
  std::vector<pipeline::CoatMaterial> lastMaterials_;      // the materials last set (blends follow the rest coat)
  std::vector<pipeline::CoatMaterial> uploadedMaterials_;  // those of the coat last given to the renderer
  glm::ivec2 windowSize_{0}, fbSize_{0};
  glm::ivec2 viewPixels_{0};  // the 3D view in framebuffer pixels

  struct Screenshot {
    std::string path;
    bool wanted = false, withUi = false;
  } shot_;
};

}  // namespace pteryla::viewer
