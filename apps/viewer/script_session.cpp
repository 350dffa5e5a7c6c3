// --script sessions (script_session.hpp): one command per frame, each once the previous evaluation is
// complete, so the window keeps drawing (and the result is the same however long a stage takes). Any
// error ends the session with exit code 2.
#include <imgui.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "actions.hpp"
#include "script_session.hpp"
#include "overlays.hpp"
#include "paint.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::viewer {

void ScriptSession::load() {
  if (!file_.empty()) script_ = loadScript(file_);
}

void ScriptSession::feedInput() {
  if (fakeMouseNext_ < fakeMouse_.size()) {
    // Scripted mouse: overrides what the GLFW backend read from the (headless) pointer.
    const FakeMouse& m = fakeMouse_[fakeMouseNext_++];
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(view_.viewOrigin.x + m.pos.x, view_.viewOrigin.y + m.pos.y);
    for (int b = 0; b < 3; ++b) io.MouseDown[b] = m.down[b];
    if (fakeMouseNext_ == fakeMouse_.size()) {
      fakeMouse_.clear();
      fakeMouseNext_ = 0;
    }
  }
  if (fakeKeysNext_ < fakeKeys_.size()) {
    const auto [key, down] = fakeKeys_[fakeKeysNext_++];
    ImGui::GetIO().KeysDown[key] = down;
    if (fakeKeysNext_ == fakeKeys_.size()) {
      fakeKeys_.clear();
      fakeKeysNext_ = 0;
    }
  }
}

void ScriptSession::queueMouse(const glm::vec2& a, const glm::vec2& b, int button, int steps) {
  FakeMouse m;
  m.pos = a;
  fakeMouse_.push_back(m);  // hover
  m.down[button] = true;
  fakeMouse_.push_back(m);  // press
  for (int i = 1; i <= steps; ++i) {
    m.pos = a + (b - a) * (float(i) / float(steps));
    fakeMouse_.push_back(m);
  }
  m.down[button] = false;
  fakeMouse_.push_back(m);  // release
  fakeMouse_.push_back(m);
  fakeMouseNext_ = 0;
}

glm::vec2 ScriptSession::scriptPoint(const ScriptCommand& c, size_t arg) const {
  glm::vec2 p;
  for (int k = 0; k < 2; ++k) {
    std::string s = c.args.at(arg + size_t(k));
    const bool percent = !s.empty() && s.back() == '%';
    if (percent) s.pop_back();
    ScriptCommand one = c;
    one.args = {s};
    const double v = scriptNumber(one, 0, file_);
    p[k] = percent ? float(v / 100.0) * float(k == 0 ? view_.viewSize.x : view_.viewSize.y) : float(v);
  }
  return p;
}

// A positive number argument (a brush radius).
static double positiveArg(const ScriptCommand& c, size_t arg, const std::string& file) {
  const double v = scriptNumber(c, arg, file);
  if (!(v > 0))
    throw Error("argument " + std::to_string(arg + 1) + " of '" + c.verb + "' must be positive", file,
                "line " + std::to_string(c.line));
  return v;
}

void ScriptSession::step() {
  if (!fakeMouse_.empty()) return;                 // a scripted click or drag is being played
  if (!fakeKeys_.empty()) return;                  // a scripted key is being pressed
  if (doc_.failed()) return;                       // frame() reports the error and fails the script
  if (host_.viewport.screenshotPending()) return;  // a screenshot is waiting for its frame
  if (view_.ui.pending) {
    // A `ui` command waits for its panel to take the request (the header opens on the same frame).
    view_.panelRequests[view_.ui.panel] = 1;
    if (++view_.ui.frames > 30)
      host_.fail(file_ + ": ui: no widget '" + view_.ui.widget + (view_.ui.value.empty() ? "" : " " + view_.ui.value) +
                     "' in the panel '" + view_.ui.panel + "'",
                 2);
    return;
  }
  if (std::chrono::steady_clock::now() < sleepUntil_) return;
  if (host_.timeline.scriptedPlayRunning()) return;                   // `play S` runs
  if (view_.cacheRangeRequested || host_.timeline.filling()) return;  // `cache-range` runs
  if (view_.frameRequest || view_.framesRunning) {                    // render-frames: wait until they are written
    if (cancelFramesAfter_ >= 0 && view_.framesRunning && view_.framesDone >= size_t(cancelFramesAfter_)) {
      // `cancel-after N`: press the Scene panel's Cancel once N frames are written.
      cancelFramesAfter_ = -1;
      view_.ui = UiRequest{"Scene", "cancel frames", "", true, 0};
      view_.panelRequests["Scene"] = 1;
      view_.hidePanels = false;
    }
    return;
  }
  if (awaitingFrames_) {
    awaitingFrames_ = false;
    std::cout << Json{{"frames_written", view_.framesDone},
                      {"frames_total", view_.framesTotal},
                      {"frames_status", view_.framesStatus}}
                     .dump()
              << std::endl;
  }
  if (waitFrames_ > 0) {
    --waitFrames_;
    return;
  }
  if (doc_.hasScene() && !doc_.upToDate()) {
    if (doc_.halted()) host_.fail("script: the evaluation was stopped", 2);
    return;
  }
  if (awaitingMetrics_) {
    awaitingMetrics_ = false;
    if (!doc_.metrics()) {
      host_.fail(file_ + ": the checker produced no metrics", 2);
      return;
    }
    std::cout << metricsJson(*doc_.metrics()) << std::endl;
  }
  if (next_ >= script_.size()) return;  // done: stay open (interactive) unless the script quit
  run(script_[next_++]);
}

void ScriptSession::run(const ScriptCommand& c) {
  const std::string& file = file_;
  auto positive = [&](const ScriptCommand& cmd, size_t arg) { return positiveArg(cmd, arg, file); };
  try {
    if (c.verb == "quit") {
      needArgs(c, 0, 0, "quit", file);
      host_.quit();
    } else if (c.verb == "screenshot" || c.verb == "screenshot-window") {
      needArgs(c, 1, 1, c.verb + " PATH", file);
      host_.viewport.requestScreenshot(c.args[0], c.verb == "screenshot-window");
    } else if (c.verb == "orbit") {
      needArgs(c, 2, 2, "orbit YAW_DEG PITCH_DEG", file);
      camera_.orbit(float(scriptNumber(c, 0, file)) * 0.01745329252f, float(scriptNumber(c, 1, file)) * 0.01745329252f);
      host_.viewport.noteCameraMoved();
    } else if (c.verb == "zoom") {
      needArgs(c, 1, 1, "zoom FACTOR", file);
      const double f = scriptNumber(c, 0, file);
      if (!(f > 0)) throw Error("zoom factor must be positive", file, "line " + std::to_string(c.line));
      camera_.zoom(float(f));
      host_.viewport.noteCameraMoved();
    } else if (c.verb == "panel") {
      needArgs(c, 2, 2, "panel NAME|* open|closed", file);
      if (c.args[1] != "open" && c.args[1] != "closed")
        throw Error("usage: panel NAME|* open|closed", file, "line " + std::to_string(c.line));
      view_.panelRequests[c.args[0]] = c.args[1] == "open" ? 1 : 0;
      waitFrames_ = 1;
    } else if (c.verb == "show") {
      needArgs(c, 2, 2, "show WHAT on|off", file);
      const std::string& w = c.args[0];
      if (c.args[1] != "on" && c.args[1] != "off")
        throw Error("usage: show WHAT on|off", file, "line " + std::to_string(c.line));
      const bool on = c.args[1] == "on";
      bool* flag = w == "designer"        ? &view_.showDesigner
                   : w == "json"          ? &view_.showJsonInspector
                   : w == "help"          ? &view_.showHelp
                   : w == "panels"        ? nullptr
                   : w == "follicles"     ? &view_.showFollicles
                   : w == "directions"    ? &view_.showDirections
                   : w == "tract"         ? &view_.showTract
                   : w == "wireframe"     ? &view_.wireframe
                   : w == "coat"          ? &view_.showCoat
                   : w == "skin"          ? &view_.showSkin
                   : w == "navigation"    ? &view_.forceNavigation
                   : w == "problems"      ? &view_.showProblems
                   : w == "keys"          ? &view_.showKeys
                   : w == "vectors"       ? &view_.showVectors
                   : w == "brushes"       ? &view_.showBrushes
                   : w == "controls"      ? &view_.showControls
                   : w == "joints"        ? &view_.showJoints
                   : w == "fast-playback" ? &view_.fastPlayback
                                          : nullptr;
      if (w == "panels")
        view_.hidePanels = !on;
      else if (!flag)
        throw Error("unknown view item '" + w +
                        "' (designer, json, help, panels, follicles, directions, tract, wireframe, coat, skin, "
                        "navigation, problems, keys, vectors, brushes, controls, joints, fast-playback)",
                    file, "line " + std::to_string(c.line));
      else
        *flag = on;
      waitFrames_ = 1;
    } else if (c.verb == "dialog") {
      needArgs(c, 1, 2, "dialog open|save-as [PATH]", file);
      const std::string path = c.args.size() > 1 ? c.args[1] : "";
      if (c.args[0] == "open") {
        host_.dialogs.showOpen(path);
      } else if (c.args[0] == "save-as") {
        if (!doc_.hasScene()) throw Error("dialog save-as: no scene is open", file, "line " + std::to_string(c.line));
        host_.dialogs.requestSaveAs(path);
      } else {
        throw Error("usage: dialog open|save-as [PATH]", file, "line " + std::to_string(c.line));
      }
      waitFrames_ = 2;
    } else if (c.verb == "key") {
      needArgs(c, 1, 1, "key enter|escape|tab|delete|k", file);
      const std::string& k = c.args[0];
      const ImGuiKey key = k == "enter"    ? ImGuiKey_Enter
                           : k == "escape" ? ImGuiKey_Escape
                           : k == "tab"    ? ImGuiKey_Tab
                           : k == "delete" ? ImGuiKey_Delete
                                           : ImGuiKey_COUNT;
      if (key == ImGuiKey_COUNT && k != "k")
        throw Error("usage: key enter|escape|tab|delete|k", file, "line " + std::to_string(c.line));
      // Letters are indexed by their upper-case code in io.KeysDown (the GLFW backend's key codes).
      const int index = k == "k" ? int('K') : ImGui::GetKeyIndex(key);
      fakeKeys_ = {{index, true}, {index, false}};
      fakeKeysNext_ = 0;
      waitFrames_ = 2;
    } else if (c.verb == "click" || c.verb == "drag") {
      // View pixels from the view's top-left corner, or percentages of the view ("50%").
      if (c.verb == "click")
        needArgs(c, 2, 2, "click X Y", file);
      else
        needArgs(c, 4, 6, "drag X1 Y1 X2 Y2 [left|right|middle [STEPS]]", file);
      const glm::vec2 a = scriptPoint(c, 0), b = c.verb == "drag" ? scriptPoint(c, 2) : a;
      int button = 0;
      if (c.args.size() > 4) {
        const std::string& bn = c.args[4];
        button = bn == "left" ? 0 : bn == "right" ? 1 : bn == "middle" ? 2 : -1;
        if (button < 0) throw Error("button must be left, right or middle", file, "line " + std::to_string(c.line));
      }
      const int steps = c.args.size() > 5 ? int(scriptNumber(c, 5, file)) : 8;
      queueMouse(a, b, button, c.verb == "drag" ? std::max(steps, 1) : 0);
    } else if (c.verb == "gizmo-drag") {
      // A drag on the gizmo as a user makes it: press on the offset's axis handle (or on the selected
      // joint's ring, where it is widest on screen) and release AMOUNT scene units (or degrees) further.
      needArgs(c, 3, 3, "gizmo-drag offset|joint x|y|z AMOUNT", file);
      const std::string& what = c.args[0];
      const std::string& ax = c.args[1];
      if ((what != "offset" && what != "joint") || ax.size() != 1 || ax[0] < 'x' || ax[0] > 'z')
        throw Error("usage: gizmo-drag offset|joint x|y|z AMOUNT", file, "line " + std::to_string(c.line));
      glm::vec2 a, b;
      if (!host_.input.gizmoDragPoints(what == "joint", ax[0] - 'x', scriptNumber(c, 2, file), a, b))
        throw Error(what == "joint" ? "gizmo-drag: no joint is selected (ui Skeleton select NAME)"
                                    : "gizmo-drag: no control is selected (ui \"Expressive controls\" select NAME)",
                    file, "line " + std::to_string(c.line));
      queueMouse(a, b, 0, 8);
    } else if (c.verb == "tool" && !c.args.empty() && c.args[0] == "paint-faces") {
      needArgs(c, 1, 3, "tool paint-faces [add|remove|select|deselect [RADIUS]]", file);
      if (c.args.size() > 1) {
        const std::string& m = c.args[1];
        if (m != "add" && m != "remove" && m != "select" && m != "deselect")
          throw Error("usage: tool paint-faces [add|remove|select|deselect [RADIUS]]", file,
                      "line " + std::to_string(c.line));
        view_.facePaint = m == "add"      ? FacePaint::Add
                          : m == "remove" ? FacePaint::Remove
                          : m == "select" ? FacePaint::Select
                                          : FacePaint::Deselect;
      }
      if (c.args.size() > 2) view_.paintRadius = float(positive(c, 2));
      view_.tool = Tool::PaintFaces;
    } else if (c.verb == "tool" && !c.args.empty() && c.args[0] == "paint-density") {
      needArgs(c, 1, 4, "tool paint-density [FACTOR [RADIUS [STRENGTH]]]", file);
      if (c.args.size() > 1) {
        const double f = scriptNumber(c, 1, file);
        if (!(f >= 0 && f <= 100))
          throw Error("a density factor must be in [0, 100]", file, "line " + std::to_string(c.line));
        view_.densityValue = float(f);
      }
      if (c.args.size() > 2) view_.paintRadius = float(positive(c, 2));
      if (c.args.size() > 3) {
        const double st = scriptNumber(c, 3, file);
        if (!(st >= 0 && st <= 1))
          throw Error("the strength must be in [0, 1]", file, "line " + std::to_string(c.line));
        view_.densityStrength = float(st);
      }
      view_.tool = Tool::PaintDensity;
    } else if (c.verb == "render-frames") {
      // The Scene panel's Render frames: DIR, range and rate; the next command waits until they are done.
      needArgs(c, 4, 6, "render-frames DIR FROM TO FPS [cancel-after N]", file);
      if (c.args.size() != 4 && (c.args.size() != 6 || c.args[4] != "cancel-after"))
        throw Error("usage: render-frames DIR FROM TO FPS [cancel-after N]", file, "line " + std::to_string(c.line));
      cancelFramesAfter_ = c.args.size() == 6 ? int(scriptNumber(c, 5, file)) : -1;
      awaitingFrames_ = true;
      ViewState::FrameRequest rq;
      rq.dir = c.args[0];
      rq.from = scriptNumber(c, 1, file);
      rq.to = scriptNumber(c, 2, file);
      rq.fps = scriptNumber(c, 3, file);
      if (!(rq.fps > 0) || rq.to < rq.from)
        throw Error("render-frames needs FPS > 0 and TO >= FROM", file, "line " + std::to_string(c.line));
      view_.frameRequest = rq;
    } else if (c.verb == "box-select") {
      // What Ctrl + drag from (X1, Y1) to (X2, Y2) boxes.
      needArgs(c, 4, 4, "box-select X1 Y1 X2 Y2", file);
      host_.input.boxSelect(scriptPoint(c, 0), scriptPoint(c, 2));
    } else if (c.verb == "box-selection") {
      needArgs(c, 0, 0, "box-selection", file);
      Json handles = Json::array();
      for (const Handle& h : view_.boxHandles)
        handles.push_back({{"kind", handleKindName(h.kind)}, {"index", h.index}, {"tract", h.tract}});
      std::cout << Json{{"feathers", view_.boxFeathers}, {"follicles", view_.boxFollicles}, {"handles", handles}}.dump()
                << std::endl;
    } else if (c.verb == "select-faces") {
      // The face brush in select (or remove: deselect) mode at a point, as one click of the tool.
      if (c.args.size() == 1 && c.args[0] == "clear") {
        view_.faceSelection.clear();
      } else {
        needArgs(c, 4, 5, "select-faces X Y Z RADIUS [remove] | select-faces clear", file);
        if (c.args.size() == 5 && c.args[4] != "remove")
          throw Error("usage: select-faces X Y Z RADIUS [remove] | select-faces clear", file,
                      "line " + std::to_string(c.line));
        const Snapshot& snap = doc_.snapshot();
        if (!snap.restSkin) throw Error("the skin is not loaded", file, "line " + std::to_string(c.line));
        const glm::vec3 at(float(scriptNumber(c, 0, file)), float(scriptNumber(c, 1, file)),
                           float(scriptNumber(c, 2, file)));
        const std::vector<uint32_t> faces = facesInBrush(*snap.restSkin, snap.posedVertex, at, float(positive(c, 3)));
        view_.faceSelection =
            c.args.size() == 5 ? faceDifference(view_.faceSelection, faces) : faceUnion(view_.faceSelection, faces);
      }
    } else if (c.verb == "tract-from-selection") {
      needArgs(c, 1, 1, "tract-from-selection NAME", file);
      actions::addTractFromFaces(doc_, c.args[0], view_.faceSelection);
      view_.selectedTract = int(doc_.scene().tracts.size()) - 1;
      view_.faceSelection.clear();
    } else if (c.verb == "tool") {
      needArgs(c, 1, 2, "tool orbit|key|vector|edit-vectors|bias|brush|control|pin [FEATHER]", file);
      static const std::pair<const char*, Tool> tools[] = {
          {"orbit", Tool::Orbit},        {"key", Tool::PlaceKey},
          {"vector", Tool::AddVector},   {"edit-vectors", Tool::EditVectors},
          {"bias", Tool::AddBias},       {"brush", Tool::Brush},
          {"control", Tool::AddControl}, {"pin", Tool::Pin}};
      bool found = false;
      for (const auto& t : tools)
        if (c.args[0] == t.first) {
          view_.tool = t.second;
          found = true;
        }
      if (!found)
        throw Error("unknown tool '" + c.args[0] +
                        "' (orbit, key, vector, edit-vectors, bias, brush, control, pin, paint-faces, paint-density)",
                    file, "line " + std::to_string(c.line));
      if (c.args.size() == 2) view_.toolFeather = c.args[1];
    } else if (c.verb == "ui") {
      needArgs(c, 2, 3, "ui PANEL WIDGET [VALUE]", file);
      if (!doc_.hasScene()) throw Error("no scene is open", file, "line " + std::to_string(c.line));
      view_.ui = UiRequest{c.args[0], c.args[1], c.args.size() > 2 ? c.args[2] : "", true, 0};
      view_.panelRequests[c.args[0]] = 1;
      if (c.args[0] == "Feather designer") view_.showDesigner = true;  // a window, not a header
      view_.hidePanels = false;
    } else if (c.verb == "sleep") {
      needArgs(c, 1, 1, "sleep SECONDS", file);
      const double secs = scriptNumber(c, 0, file);
      if (!(secs >= 0 && secs <= 3600))
        throw Error("sleep: seconds must be in [0, 3600]", file, "line " + std::to_string(c.line));
      sleepUntil_ = std::chrono::steady_clock::now() + std::chrono::milliseconds(long(secs * 1000.0));
    } else if (c.verb == "play") {
      needArgs(c, 1, 2, "play SECONDS [FPS]", file);
      const double secs = scriptNumber(c, 0, file);
      if (!(secs > 0 && secs <= 3600))
        throw Error("play: seconds must be in (0, 3600]", file, "line " + std::to_string(c.line));
      if (c.args.size() > 1) {
        const double fps = scriptNumber(c, 1, file);
        if (!(fps >= 0.1 && fps <= 240))
          throw Error("play: fps must be in [0.1, 240]", file, "line " + std::to_string(c.line));
        view_.playFps = float(fps);
      }
      if (!doc_.hasScene()) throw Error("play: no scene is open", file, "line " + std::to_string(c.line));
      host_.timeline.playFor(secs);
    } else if (c.verb == "range") {
      needArgs(c, 2, 4, "range T0 T1 [STEP [loop|once]]", file);
      const double t0 = scriptNumber(c, 0, file), t1 = scriptNumber(c, 1, file);
      const double step = c.args.size() > 2 ? scriptNumber(c, 2, file) : double(view_.timeStep);
      if (!(t1 > t0) || !(step >= 1e-4) || (t1 - t0) / step > 1e6)
        throw Error("range: needs T0 < T1 and a step of at least 1e-4 (at most a million frames)", file,
                    "line " + std::to_string(c.line));
      if (c.args.size() > 3 && c.args[3] != "loop" && c.args[3] != "once")
        throw Error("range: the fourth value is loop or once", file, "line " + std::to_string(c.line));
      view_.timeStart = float(t0);
      view_.timeEnd = float(t1);
      view_.timeStep = float(step);
      if (c.args.size() > 3) view_.loop = c.args[3] == "loop";
    } else if (c.verb == "cache-range") {
      needArgs(c, 0, 0, "cache-range", file);
      if (!doc_.hasScene()) throw Error("cache-range: no scene is open", file, "line " + std::to_string(c.line));
      view_.cacheRangeRequested = true;
      waitFrames_ = 2;
    } else if (c.verb == "autosave") {
      needArgs(c, 0, 0, "autosave", file);
      const std::string written = host_.dialogs.autosaveNow();
      std::fprintf(stderr, "pteryla-viewer: autosaved %s\n", written.c_str());
    } else if (c.verb == "crash") {
      // Test hook: the process ends at once, as in a crash (no clean-up, no save, the recovery file stays).
      needArgs(c, 0, 0, "crash", file);
      std::fflush(nullptr);
      std::_Exit(70);
    } else if (c.verb == "selection") {
      needArgs(c, 0, 0, "selection", file);
      const FeatherReadout r = featherReadout(doc_.snapshot(), view_.selectedFeather);
      const Json j = r.feather < 0 ? Json{{"feather", nullptr}}
                                   : Json{{"feather", r.feather},
                                          {"tract", r.tract},
                                          {"type", r.type},
                                          {"follicle_id", r.follicleId},
                                          {"elevation_deg", r.elevationDeg},
                                          {"age", r.age},
                                          {"present", r.present}};
      std::cout << j.dump() << std::endl;
    } else if (c.verb == "frame") {
      needArgs(c, 0, 0, "frame", file);
      host_.viewport.frameAll();
    } else if (c.verb == "frames") {
      needArgs(c, 1, 1, "frames N", file);
      waitFrames_ = int(scriptNumber(c, 0, file));
    } else if (c.verb == "check") {
      needArgs(c, 0, 0, "check", file);
      if (!doc_.hasScene()) throw Error("no scene is open", file, "line " + std::to_string(c.line));
      doc_.requestCheck();
      awaitingMetrics_ = true;
    } else if (c.verb == "load") {
      needArgs(c, 1, 1, "load PATH", file);
      host_.dialogs.openNow(c.args[0]);
      if (!host_.dialogs.errors().empty())
        throw Error(host_.dialogs.errors().back(), file, "line " + std::to_string(c.line));
    } else {
      runDocumentCommand(doc_, c, file, std::cout);
    }
  } catch (const std::exception& e) {
    host_.fail(e.what(), 2);
  }
}

}  // namespace pteryla::viewer
