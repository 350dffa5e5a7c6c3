#pragma once
// A --script session (docs/viewer.md, "Scripts"; script_session.cpp): one command per frame, each once the
// previous evaluation is complete, so the window keeps drawing (and the result is the same however long a
// stage takes). Commands drive the viewer as a user does: the camera, the panels' widgets (`ui`, taken by
// the panel's own code), scripted clicks, drags and keys fed to ImGui, dialogs, playback, frames, and
// the document commands of script.hpp. Any error ends the session with exit code 2.
#include <chrono>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

#include "camera_controller.hpp"
#include "dialogs.hpp"
#include "document.hpp"
#include "input.hpp"
#include "panels.hpp"
#include "script.hpp"
#include "timeline.hpp"
#include "viewport.hpp"

namespace pteryla::viewer {

// What a script drives, and how it ends the run.
struct ScriptHost {
  Document& doc;
  ViewState& view;
  CameraController& camera;
  Viewport& viewport;
  Timeline& timeline;
  Dialogs& dialogs;
  ViewportInput& input;
  std::function<void(const std::string& message, int exitCode)> fail;  // ends the run
  std::function<void()> quit;
};

class ScriptSession {
 public:
  ScriptSession(std::string file, ScriptHost host)
      : file_(std::move(file)), host_(std::move(host)), doc_(host_.doc), view_(host_.view), camera_(host_.camera) {}
  // Reads the script (throws Error); a session without a file does nothing.
  void load();
  bool active() const { return !script_.empty(); }
  // Once per frame: runs the next command when the previous one is done.
  void step();
  // Before ImGui::NewFrame: the scripted mouse (click, drag) and keys of this frame replace what the
  // GLFW backend read from the (headless) pointer and keyboard.
  void feedInput();
  // A scripted click, drag or key is being played (each needs drawn frames).
  bool feedingInput() const { return !fakeMouse_.empty() || !fakeKeys_.empty(); }

 private:
  void run(const ScriptCommand& c);
  glm::vec2 scriptPoint(const ScriptCommand& c, size_t arg) const;
  // A hover and a press at a, `steps` moves to b (0: a click), a release: one mouse state a frame.
  void queueMouse(const glm::vec2& a, const glm::vec2& b, int button, int steps);

  std::string file_;
  ScriptHost host_;
  Document& doc_;
  ViewState& view_;
  CameraController& camera_;
  std::vector<ScriptCommand> script_;
  size_t next_ = 0;
  int waitFrames_ = 0;
  std::chrono::steady_clock::time_point sleepUntil_{};  // `sleep S`: keep drawing until then
  bool awaitingMetrics_ = false;
  bool awaitingFrames_ = false;  // render-frames: print what was written when the frames end
  int cancelFramesAfter_ = -1;   // render-frames ... cancel-after N: Cancel once N frames are written
  // Scripted mouse input (click / drag commands): one state per frame, in view pixels.
  struct FakeMouse {
    glm::vec2 pos{0};
    bool down[3] = {false, false, false};
  };
  std::vector<FakeMouse> fakeMouse_;
  size_t fakeMouseNext_ = 0;
  // Scripted keys (`key` command): (ImGui key index, down) per frame.
  std::vector<std::pair<int, bool>> fakeKeys_;
  size_t fakeKeysNext_ = 0;
};

}  // namespace pteryla::viewer
