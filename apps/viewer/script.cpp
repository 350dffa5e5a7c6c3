#include "script.hpp"

#include <cmath>

#include <glm/geometric.hpp>
#include <fstream>
#include <ostream>
#include <sstream>

#include "actions.hpp"
#include "gizmo.hpp"
#include "mirror.hpp"
#include "paint.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

namespace {

std::string where(const ScriptCommand& c) { return "line " + std::to_string(c.line); }

std::string jsonOrNull(const std::optional<double>& v) {
  if (!v || !std::isfinite(*v)) return "null";
  std::ostringstream os;
  os.precision(6);
  os << *v;
  return os.str();
}
std::string countOrNull(const std::optional<size_t>& v) { return v ? std::to_string(*v) : "null"; }

}  // namespace

std::string metricsJson(const pipeline::QualityMetrics& m) {
  std::ostringstream out;
  out << "{\"follicles\": " << countOrNull(m.follicles) << ", \"hex_fraction\": " << jsonOrNull(m.hexFraction)
      << ", \"nn_cv\": " << jsonOrNull(m.nnCv) << ", \"feathers\": " << countOrNull(m.feathers)
      << ", \"intersecting_pairs\": " << countOrNull(m.intersectingPairs)
      << ", \"intersecting_pairs_unpacked\": " << countOrNull(m.intersectingPairsUnpacked)
      << ", \"intersecting_pairs_proxy\": " << countOrNull(m.intersectingPairsProxy)
      << ", \"skin_penetrations\": " << countOrNull(m.skinPenetrations) << ", \"coverage\": " << jsonOrNull(m.coverage)
      << "}";
  return out.str();
}

std::vector<ScriptCommand> parseScript(const std::string& text, const std::string& file) {
  std::vector<ScriptCommand> out;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    std::vector<std::string> tok;
    std::string cur;
    bool inQuote = false, have = false;
    for (size_t i = 0; i < line.size(); ++i) {
      const char ch = line[i];
      if (inQuote) {
        if (ch == '"')
          inQuote = false;
        else
          cur += ch;
      } else if (ch == '"') {
        inQuote = true;
        have = true;
      } else if (ch == '#') {
        break;
      } else if (ch == ' ' || ch == '\t' || ch == '\r') {
        if (have) tok.push_back(cur);
        cur.clear();
        have = false;
      } else {
        cur += ch;
        have = true;
      }
    }
    if (inQuote) throw Error("unterminated quote", file, "line " + std::to_string(n));
    if (have) tok.push_back(cur);
    if (tok.empty()) continue;
    ScriptCommand c;
    c.line = n;
    c.verb = tok[0];
    c.args.assign(tok.begin() + 1, tok.end());
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<ScriptCommand> loadScript(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw Error("cannot open script", path);
  std::stringstream ss;
  ss << f.rdbuf();
  return parseScript(ss.str(), path);
}

bool isViewCommand(const std::string& v) {
  return v == "screenshot" || v == "screenshot-window" || v == "panel" || v == "show" || v == "click" || v == "drag" ||
         v == "ui" || v == "autosave" || v == "crash" || v == "sleep" || v == "tool" || v == "orbit" || v == "zoom" ||
         v == "frame" || v == "frames" || v == "quit" || v == "dialog" || v == "key" || v == "selection" ||
         v == "select-faces" || v == "tract-from-selection" || v == "box-select" || v == "box-selection" ||
         v == "gizmo-drag";
}

double scriptNumber(const ScriptCommand& c, size_t arg, const std::string& file) {
  const std::string& s = c.args.at(arg);
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size() || s.empty() || !std::isfinite(v))
    throw Error("argument " + std::to_string(arg + 1) + " of '" + c.verb + "': expected a number, got '" + s + "'",
                file, where(c));
  return v;
}

void needArgs(const ScriptCommand& c, size_t min, size_t max, const std::string& usage, const std::string& file) {
  if (c.args.size() < min || c.args.size() > max) throw Error("usage: " + usage, file, where(c));
}

namespace {

size_t count(const ScriptCommand& c, size_t arg, const std::string& file) {
  const double v = scriptNumber(c, arg, file);
  if (v < 0 || v != std::floor(v) || v > 1e15)
    throw Error("argument " + std::to_string(arg + 1) + " of '" + c.verb + "': expected a non-negative integer", file,
                where(c));
  return static_cast<size_t>(v);
}

glm::dvec3 vec(const ScriptCommand& c, size_t arg, const std::string& file) {
  return {scriptNumber(c, arg, file), scriptNumber(c, arg + 1, file), scriptNumber(c, arg + 2, file)};
}

void run(Document& doc, const ScriptCommand& c, const std::string& file, std::ostream& out) {
  const std::string& v = c.verb;
  auto tracts = [&](size_t arg) {
    actions::ensureTracts(doc);
    return resolveTracts(doc.scene(), arg < c.args.size() ? c.args[arg] : "*", where(c));
  };
  if (v == "load") {
    needArgs(c, 1, 1, "load PATH", file);
    doc.open(c.args[0]);
  } else if (v == "save") {
    needArgs(c, 1, 2, "save PATH [overwrite]", file);
    if (c.args.size() == 2 && c.args[1] != "overwrite") throw Error("usage: save PATH [overwrite]", file, where(c));
    if (!doc.saveAs(c.args[0], c.args.size() == 2))
      throw Error("file exists (add 'overwrite' to replace it): " + c.args[0], file, where(c));
  } else if (v == "undo" || v == "redo") {
    needArgs(c, 0, 0, v, file);
    if (!(v == "undo" ? doc.undo() : doc.redo())) throw Error("nothing to " + v, file, where(c));
  } else if (v == "time") {
    needArgs(c, 1, 1, "time T", file);
    doc.setTime(scriptNumber(c, 0, file));
  } else if (v == "lod") {
    needArgs(c, 1, 1, "lod FRACTION", file);
    const double f = scriptNumber(c, 0, file);
    if (!(f > 0 && f <= 1)) throw Error("lod must be in (0, 1]", file, where(c));
    doc.setLod(f);
  } else if (v == "render-lod") {
    needArgs(c, 1, 1, "render-lod FRACTION", file);
    actions::setRenderLod(doc, scriptNumber(c, 0, file));
  } else if (v == "seed") {
    needArgs(c, 1, 1, "seed N", file);
    const size_t s = count(c, 0, file);
    doc.edit("seed", [&](pipeline::Scene& sc) { sc.seed = s; });
  } else if (v == "count") {
    needArgs(c, 2, 2, "count TRACT N", file);
    for (size_t t : tracts(0)) actions::setTractCount(doc, t, count(c, 1, file));
  } else if (v == "density") {
    needArgs(c, 2, 2, "density TRACT D", file);
    for (size_t t : tracts(0)) actions::setTractDensity(doc, t, scriptNumber(c, 1, file));
  } else if (v == "relax") {
    needArgs(c, 1, 2, "relax ITERATIONS [TRACT]", file);
    const size_t n = count(c, 0, file);
    for (size_t t : tracts(1)) actions::setRelaxIterations(doc, t, static_cast<int>(n));
  } else if (v == "bias") {
    needArgs(c, 7, 9, "bias TRACT X Y Z DX DY DZ [SIGMA [STRETCH]]", file);
    const double sigma = c.args.size() > 7 ? scriptNumber(c, 7, file) : 0.0;
    const double stretch = c.args.size() > 8 ? scriptNumber(c, 8, file) : 1.5;
    for (size_t t : tracts(0)) actions::addBias(doc, t, vec(c, 1, file), vec(c, 4, file), sigma, stretch);
  } else if (v == "pin") {
    needArgs(c, 4, 4, "pin TRACT X Y Z", file);
    for (size_t t : tracts(0)) actions::addPinned(doc, t, vec(c, 1, file));
  } else if (v == "feather") {
    needArgs(c, 2, 2, "feather NAME PATH", file);
    actions::setFeatherFile(doc, c.args[0], c.args[1]);
  } else if (v == "key") {
    needArgs(c, 3, 3, "key TRACT FEATHER FOLLICLE_ID", file);
    for (size_t t : tracts(0)) actions::addKeyFeather(doc, t, c.args[1], count(c, 2, file));
  } else if (v == "key-at") {
    needArgs(c, 5, 5, "key-at TRACT FEATHER X Y Z", file);
    for (size_t t : tracts(0)) actions::addKeyFeatherAt(doc, t, c.args[1], vec(c, 2, file));
  } else if (v == "vector") {
    needArgs(c, 6, 7, "vector X Y Z DX DY DZ [RADIUS]", file);
    actions::addStylingVector(doc, vec(c, 0, file), vec(c, 3, file),
                              c.args.size() > 6 ? scriptNumber(c, 6, file) : 0.0);
  } else if (v == "axis") {
    if (c.args.size() < 6 || c.args.size() % 3 != 0) throw Error("usage: axis X1 Y1 Z1 X2 Y2 Z2 [...]", file, where(c));
    std::vector<glm::dvec3> pts;
    for (size_t i = 0; i < c.args.size(); i += 3) pts.push_back(vec(c, i, file));
    actions::setBodyAxis(doc, pts);
  } else if (v == "brush") {
    needArgs(c, 5, 6, "brush X Y Z RADIUS ELEVATION_DEG [fixed|lift]", file);
    if (c.args.size() > 5 && c.args[5] != "fixed" && c.args[5] != "lift")
      throw Error("usage: brush X Y Z RADIUS ELEVATION_DEG [fixed|lift]", file, where(c));
    actions::addBrush(doc, vec(c, 0, file), scriptNumber(c, 3, file), scriptNumber(c, 4, file),
                      c.args.size() > 5 && c.args[5] == "lift");
  } else if (v == "paint-faces") {
    // The face brush at a point (what a click of the viewport tool paints): add to or remove from a tract.
    needArgs(c, 6, 6, "paint-faces TRACT add|remove X Y Z RADIUS", file);
    if (c.args[1] != "add" && c.args[1] != "remove")
      throw Error("usage: paint-faces TRACT add|remove X Y Z RADIUS", file, where(c));
    const auto rest = doc.snapshot().restSkin;
    if (!rest) throw Error("the skin is not loaded", file, where(c));
    const std::vector<uint32_t> faces =
        facesInBrush(*rest, doc.snapshot().posedVertex, glm::vec3(vec(c, 2, file)), float(scriptNumber(c, 5, file)));
    for (size_t t : tracts(0)) actions::paintTractFaces(doc, *rest, t, faces, c.args[1] == "add");
  } else if (v == "paint-density") {
    needArgs(c, 5, 6, "paint-density X Y Z RADIUS FACTOR [STRENGTH]", file);
    const auto rest = doc.snapshot().restSkin;
    if (!rest) throw Error("the skin is not loaded", file, where(c));
    const double value = scriptNumber(c, 4, file), strength = c.args.size() > 5 ? scriptNumber(c, 5, file) : 1.0;
    if (!(value >= 0 && value <= 100)) throw Error("a density factor must be in [0, 100]", file, where(c));
    if (!(strength >= 0 && strength <= 1)) throw Error("the strength must be in [0, 1]", file, where(c));
    std::vector<float> f = doc.scene().densityFactor ? *doc.scene().densityFactor : std::vector<float>{};
    if (f.size() != rest->positions.size()) f.assign(rest->positions.size(), 1.0f);
    densityDab(f, *rest, doc.snapshot().posedVertex, glm::vec3(vec(c, 0, file)), float(scriptNumber(c, 3, file)),
               float(value), float(strength));
    actions::setDensityFactors(doc, std::move(f));
  } else if (v == "density-map") {
    needArgs(c, 1, 1, "density-map clear", file);
    if (c.args[0] != "clear") throw Error("usage: density-map clear", file, where(c));
    actions::clearDensityMap(doc);
  } else if (v == "mirror") {
    // mirror x|y|z[=OFFSET]|symmetry ITEM...   ITEM: tract TRACT | brushes | controls | vectors
    const std::string usage = "mirror x|y|z[=OFFSET]|symmetry [tract TRACT]... [brushes] [controls] [vectors]";
    if (c.args.size() < 2) throw Error("usage: " + usage, file, where(c));
    const auto rest = doc.snapshot().restSkin;
    if (!rest) throw Error("the skin is not loaded", file, where(c));
    MirrorRequest q;
    const std::string& plane = c.args[0];
    if (plane == "symmetry") {
      q.plane = symmetryPlane(*rest);
    } else if (!plane.empty() && (plane[0] == 'x' || plane[0] == 'y' || plane[0] == 'z') &&
               (plane.size() == 1 || plane[1] == '=')) {
      q.plane.axis = plane[0] - 'x';
      if (plane.size() > 1) {
        ScriptCommand one = c;
        one.args = {plane.substr(2)};
        q.plane.offset = scriptNumber(one, 0, file);
      }
    } else {
      throw Error("usage: " + usage, file, where(c));
    }
    for (size_t i = 1; i < c.args.size(); ++i) {
      const std::string& a = c.args[i];
      if (a == "tract" && i + 1 < c.args.size()) {
        for (size_t t : tracts(++i)) q.tracts.push_back(t);
      } else if (a == "brushes") {
        q.brushes = true;
      } else if (a == "controls") {
        q.controls = true;
      } else if (a == "vectors") {
        q.vectors = true;
      } else {
        throw Error("usage: " + usage, file, where(c));
      }
    }
    const MirrorResult r = mirrorScene(doc, *rest, q);
    out << "{\"mirrored\": {\"tracts\": " << r.tracts << ", \"brushes\": " << r.brushes
        << ", \"controls\": " << r.controls << ", \"vectors\": " << r.vectors << "}}" << std::endl;
  } else if (v == "pack" || v == "wait") {
    needArgs(c, 0, 0, v, file);  // the runner waits for the evaluation before the next command
  } else if (v == "check") {
    needArgs(c, 0, 0, "check", file);
    doc.requestCheck();
    if (!doc.waitIdle()) throw Error("evaluation failed: " + doc.takeError().value_or("?"), file, where(c));
    if (!doc.metrics()) throw Error("the checker produced no metrics", file, where(c));
    out << metricsJson(*doc.metrics()) << std::endl;
  } else if (v == "control") {
    needArgs(c, 4, 4, "control X Y Z RADIUS", file);
    actions::addControl(doc, vec(c, 0, file), scriptNumber(c, 3, file));
  } else if (v == "lift" || v == "aim" || v == "direction" || v == "random" || v == "dynamic" || v == "blend") {
    needArgs(c, 2, 2, v + " CONTROL VALUE", file);
    actions::setControlValue(doc, count(c, 0, file), v == "blend" ? "dynamic" : v, scriptNumber(c, 1, file),
                             doc.time());
  } else if (v == "offset") {
    needArgs(c, 4, 4, "offset CONTROL DX DY DZ", file);
    setControlOffset(doc, count(c, 0, file), vec(c, 1, file), doc.time());
  } else if (v == "key-control") {
    needArgs(c, 1, 1, "key-control CONTROL", file);
    keyControlAll(doc, count(c, 0, file), doc.time());
  } else if (v == "joint-key") {
    needArgs(c, 5, 5, "joint-key JOINT AX AY AZ DEGREES", file);
    const auto rest = doc.snapshot().restSkin;
    if (!rest) throw Error("the skin is not loaded", file, where(c));
    RigCache cache;
    const moult::SkinRig* rig = cache.get(doc.scene(), rest->vertexCount());
    if (!rig) throw Error(cache.error().empty() ? "the scene has no skeleton" : cache.error(), file, where(c));
    const int32_t j = rig->skeleton.find(c.args[0]);
    if (j < 0) throw Error("unknown joint '" + c.args[0] + "'", file, where(c));
    const glm::dvec3 axis = vec(c, 1, file);
    const double degrees = scriptNumber(c, 4, file);
    if (glm::length(axis) == 0 && degrees != 0) throw Error("a rotation needs a non-zero axis", file, where(c));
    keyJointRotation(doc, rig->skeleton, size_t(j), doc.time(), moult::rotationFromAxisAngle(axis, degrees));
  } else if (v == "keyframe") {
    needArgs(c, 2, 2, "keyframe CONTROL T", file);
    actions::addControlKeyframe(doc, count(c, 0, file), scriptNumber(c, 1, file));
  } else if (v == "set") {
    needArgs(c, 2, 2, "set /JSON/POINTER VALUE", file);
    const Json value = parseLooseValue(c.args[1]);
    doc.edit("set " + c.args[0], [&](pipeline::Scene& s) { setScenePointer(s, c.args[0], value); });
  } else if (v == "style") {
    needArgs(c, 1, 1, "style shaded|scratchboard", file);
    actions::setStyle(doc, c.args[0]);
  } else if (v == "brdf") {
    needArgs(c, 2, 2, "brdf D H", file);
    actions::setBrdf(doc, scriptNumber(c, 0, file), scriptNumber(c, 1, file));
  } else if (v == "echo") {
    for (size_t i = 0; i < c.args.size(); ++i) out << (i ? " " : "") << c.args[i];
    out << std::endl;
  } else {
    throw Error("unknown command '" + v + "'", file, where(c));
  }
}

}  // namespace

bool runDocumentCommand(Document& doc, const ScriptCommand& c, const std::string& file, std::ostream& out) {
  if (isViewCommand(c.verb)) return false;
  if (c.verb != "load" && c.verb != "echo" && !doc.hasScene())
    throw Error("no scene is open (start with 'load PATH')", file, where(c));
  try {
    run(doc, c, file, out);
  } catch (const Error& e) {
    if (e.element().rfind("line ", 0) == 0) throw;
    throw Error(e.what(), file, where(c));
  }
  return true;
}

const char* scriptHelp() {
  return R"(Script commands (one per line, '#' comments; each waits for the previous evaluation):
  load PATH                      open a scene (.json) or a bare mesh (.obj/.ply/.off/.stl)
  save PATH [overwrite]          write the scene; an existing file is only replaced with 'overwrite'
  undo | redo
  time T | lod F | seed N        timeline time, preview level of detail (0,1], master seed
  render-lod F                   the scene's render.lod (0,1] (what is saved; lod is the viewer's)
  count TRACT N | density TRACT D    follicles of a tract (TRACT: index, name or *)
  relax N [TRACT]                Lloyd iterations (0 = scattered only)
  bias TRACT X Y Z DX DY DZ [SIGMA [STRETCH]]   relaxation bias vector
  pin TRACT X Y Z                pinned follicle
  feather NAME PATH              add or replace a feather file in the library
  key TRACT FEATHER FOLLICLE_ID | key-at TRACT FEATHER X Y Z     key feathers
  vector X Y Z DX DY DZ [RADIUS] | axis X1 Y1 Z1 X2 Y2 Z2 ...    directions (over an axis, a vector combs it)
  brush X Y Z RADIUS ELEVATION_DEG [fixed|lift]   packing brush: set the angle, or lift to at least it
  paint-faces TRACT add|remove X Y Z RADIUS     tract face brush (source faces whose triangles it covers)
  paint-density X Y Z RADIUS FACTOR [STRENGTH]  density brush dab (factor per vertex, saved as SCENE.density.json)
  density-map clear              remove the painted density map
  select-faces X Y Z RADIUS [remove] | select-faces clear   the view's face selection (not saved)
  tract-from-selection NAME      new tract of the selected faces
  mirror x|y|z[=OFFSET]|symmetry [tract TRACT]... [brushes] [controls] [vectors]
                                 mirrored copies about the plane, one undo step (prints what it added)
  pack | wait                    wait for the evaluation (packing included)
  check                          print the checker's metrics as JSON
  control X Y Z RADIUS           add an expressive control
  lift|aim|direction|random|dynamic CONTROL VALUE   behaviour weight in [0,1] (keyed: at the current time)
  keyframe CONTROL T             key the control's weights at time T
  offset CONTROL DX DY DZ        the control's offset (keyed: a key at the current time; else the constant)
  key-control CONTROL            key every behaviour and the offset at the current time (the gizmo's K)
  joint-key JOINT AX AY AZ DEG   key a skeleton joint's rotation (axis, degrees) at the current time
  gizmo-drag offset|joint x|y|z AMOUNT   drag the selected control's offset handle AMOUNT scene units along
                                 the axis, or the selected joint's ring AMOUNT degrees, with the mouse
  set /JSON/POINTER VALUE        set any scene value (JSON or a plain string)
  style shaded|scratchboard | brdf D H
  echo TEXT
  screenshot PATH | screenshot-window PATH (with the panels)
  orbit YAW_DEG PITCH_DEG | zoom FACTOR | frame | frames N | sleep SECONDS | quit
  play SECONDS [FPS]             play the timeline (range, step, loop as set) for SECONDS at FPS (default
                                 24), then print what it showed as JSON (frames due, shown, evaluated,
                                 from the flipbook)
  range T0 T1 [STEP [loop|once]] the timeline's range, frame step and looping (as the Timeline panel sets them)
  cache-range                    draw every frame of the timeline range into the flipbook (then play shows them)
  panel NAME|* open|closed       open or close panel headers (names as shown)
  tool orbit|key|vector|edit-vectors|bias|brush|control|pin [FEATHER]   viewport tool
  tool paint-faces [add|remove|select|deselect [RADIUS]]   tract face brush (drag to paint)
  tool paint-density [FACTOR [RADIUS [STRENGTH]]]          density brush (drag to paint)
  click X Y | drag X1 Y1 X2 Y2 [left|right|middle [STEPS]]   mouse in the 3D view (pixels or N%)
  ui PANEL WIDGET [VALUE]        use a panel's widget as a user would (docs/viewer.md lists them)
  dialog open|save-as [PATH]     open the Open / Save As dialog (at PATH: its directory and file name)
  key enter|escape|tab|delete|k  press a key (Enter confirms a dialog's file name; Delete removes the
                                 box selection, else the selected handle, else the selected feather's
                                 follicle; K keys the selected joint or control)
  selection                      print the selected feather (click one in the view) as JSON
  render-frames DIR FROM TO FPS [cancel-after N]   render frame k at FROM + k/FPS to DIR/frame_NNNN.png
                                 (scene size, LOD, camera); the next command waits until the frames are
                                 written (cancel-after N: the panel's Cancel once N are), then prints
                                 {"frames_written", "frames_total", "frames_status"}
  box-select X1 Y1 X2 Y2         box selection (as Ctrl + drag): feathers, handles, and follicles when shown
                                 (then `key delete` removes the boxed handles and feathers as one undo step)
  box-selection                  print the boxed feathers, follicles and handles as JSON
  autosave                       write the recovery file now (the scene must have unsaved changes)
  crash                          end the process at once, without clean-up (tests recovery)
  show designer|json|help|panels|follicles|directions|tract|wireframe|coat|skin|navigation|problems|keys|vectors|brushes|controls|joints|fast-playback on|off
)";
}

}  // namespace pteryla::viewer
