// The pteryla subcommands. Every scene command is a client of the host API (pteryla::Session,
// include/pteryla/pteryla.hpp), the same door a DCC plug-in uses; `render --time T` and `frames` draw
// through the same kept renderer, identically.
#include "commands.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "pteryla/pteryla.hpp"

namespace pteryla::cli {
namespace {

void checkOutExtension(const std::string& out, const std::vector<std::string>& allowed, const std::string& what) {
  const std::string e = extensionOf(out);
  for (const auto& a : allowed)
    if (e == a) return;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  throw Error("unsupported output type '" + e + "': expected " + what + " (" + list + ")", out, "--out");
}

double peakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

std::string jsonCountOrNull(const std::optional<size_t>& v) { return v ? std::to_string(*v) : "null"; }
// [a, b, ...]: null when `known` is false (the metric was not computed).
std::string jsonIdsOrNull(bool known, const std::vector<uint32_t>& ids) {
  if (!known) return "null";
  std::string out = "[";
  for (size_t k = 0; k < ids.size(); ++k) out += (k ? ", " : "") + std::to_string(ids[k]);
  return out + "]";
}

}  // namespace

int cmdRender(const Common& c, const RenderArgs& a) {
  checkOutExtension(a.out, {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr"}, "an image");
  Loaded l = load(c, a);
  RenderSettings settings;
  settings.width = l.width;
  settings.height = l.height;
  settings.style = a.style;
  const render::Image image = l.session.renderImage(settings);
  // Directories are created only once the scene has evaluated: a failing scene leaves no trace.
  ensureParentDir(a.out);
  render::saveImage(a.out, image);
  endProgress(c);
  if (!l.session.evaluate())
    throw InternalError("the render's own frame could not be read back");  // no work: up to date
  const Frame& f = l.session.frame();
  info(c, "wrote " + a.out + " (" + std::to_string(l.width) + "x" + std::to_string(l.height) + ", " +
              std::to_string(f.ranges.size) + " feathers, " + std::to_string(f.indices.size / 3) +
              " feather triangles)");
  return 0;
}

int cmdCheck(const Common& c, const SceneArgs& a) {
  Loaded l = load(c, a);
  const Metrics m = l.session.metrics();
  endProgress(c);
  std::printf(
      "{\"follicles\": %s, \"hex_fraction\": %s, \"nn_cv\": %s, \"feathers\": %s, \"intersecting_pairs\": %s, "
      "\"intersecting_pairs_unpacked\": %s, \"intersecting_pairs_proxy\": %s, \"skin_penetrations\": %s, \"coverage\": "
      "%s, "
      "\"elevation_p50\": %s, \"elevation_p90\": %s, \"fixed_feathers\": %s, \"hidden_feathers\": %s, "
      "\"intersecting_feathers\": %s, \"penetrating_feathers\": %s}\n",
      jsonCountOrNull(m.follicles).c_str(), jsonNumberOrNull(m.hexFraction).c_str(), jsonNumberOrNull(m.nnCv).c_str(),
      jsonCountOrNull(m.feathers).c_str(), jsonCountOrNull(m.intersectingPairs).c_str(),
      jsonCountOrNull(m.intersectingPairsUnpacked).c_str(), jsonCountOrNull(m.intersectingPairsProxy).c_str(),
      jsonCountOrNull(m.skinPenetrations).c_str(), jsonNumberOrNull(m.coverage).c_str(),
      jsonNumberOrNull(m.elevationP50).c_str(), jsonNumberOrNull(m.elevationP90).c_str(),
      jsonCountOrNull(m.fixedFeathers).c_str(), jsonCountOrNull(m.hiddenFeathers).c_str(),
      jsonIdsOrNull(m.intersectingPairs.has_value(), m.intersectingFeathers).c_str(),
      jsonIdsOrNull(m.skinPenetrations.has_value(), m.penetratingFeathers).c_str());
  return 0;
}

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Evaluates `s` (its progress is the CLI's bar, which never cancels).
void evaluate(Session& s) {
  if (!s.evaluate()) throw InternalError("an evaluation was cancelled with no one to cancel it");
}

}  // namespace

int cmdBench(const Common& c, const BenchArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  Loaded l = load(c, a);
  Session& s = l.session;
  // Parsing the scene and reading the skin and the tracts (the session reads them when it is made).
  const double load = secondsSince(t0);
  RenderSettings size;
  size.width = l.width;
  size.height = l.height;
  // Warm-up: every stage once (the mesh at the render's levels of detail: by screen size, the default,
  // or --fixed-lod), context, shader compile, uploads. No evaluate() first: with screen-size levels it
  // would mesh the whole coat at the uniform level, which a render never needs.
  s.renderImage(size);
  const auto r0 = std::chrono::steady_clock::now();
  s.renderImage(size);
  const double renderSecs = secondsSince(r0);
  // First-evaluation seconds per stage, read before the scrub below resets the timings.
  const StageSeconds st = s.stageSeconds();
  const double distribute = st.distribute;
  const double interpolate = st.interpolate + st.directions;
  const double packSecs = st.pack + st.controls;
  const double meshSecs = st.mesh;
  // A full pack again with warm memory (best of 3): what repacking the coat costs after an edit.
  const double packRepeat = s.timeFullPack(3);
  // A second frame at a new time: what a timeline scrub costs (pose, ages, controls, pack, mesh), from a
  // published frame: the render's coat is handed to the frame's views first (the host API's float copies
  // of the 16-bit normals and half-float alphas are made once per mesh, not per step).
  evaluate(s);
  const double t = s.time();
  s.setTime(t + 1e-3);
  const auto f0 = std::chrono::steady_clock::now();
  evaluate(s);
  const double frameSecs = secondsSince(f0);
  s.setTime(t);
  // --check: what `pteryla check` adds once the scene has evaluated: the mesh at full detail, then the
  // checker on it (pairs, skin, coverage, the proxy coats' pairs).
  std::string checkJson;
  if (a.check) {
    // metrics() meshes every feather at full detail (whatever levels the render set), then checks; the
    // mesh stage's own seconds tell the two apart (no frame is pending since the time moved back, so
    // metrics() does not mesh the frame again after the check).
    const auto m0 = std::chrono::steady_clock::now();
    s.metrics();
    const double total = secondsSince(m0);
    const double checkMesh = s.stageSeconds().mesh;
    char buf[96];
    std::snprintf(buf, sizeof buf, ", \"check_mesh\": %.6f, \"check\": %.6f", checkMesh, total - checkMesh);
    checkJson = buf;
  }
  evaluate(s);
  endProgress(c);
  const Frame& f = s.frame();
  // The mesh stage's unplaced store (instancing shares it): meshes kept and megabytes, against a copy per
  // feather.
  const Session::MeshStore ms = s.meshStore();
  const double mb = 24.0 / (1024.0 * 1024.0);
  std::printf(
      "{\"load\": %.6f, \"distribute\": %.6f, \"interpolate\": %.6f, \"pack\": %.6f, \"pack_repeat\": %.6f, "
      "\"mesh\": %.6f, \"render\": %.6f, "
      "\"frame\": %.6f, \"triangles\": %zu, \"feathers\": %zu, \"width\": %d, \"height\": %d, \"lod\": %.4f, "
      "\"representatives\": %zu, \"unplaced_meshes\": %zu, \"unplaced_mb\": %.1f, \"unplaced_mb_unshared\": %.1f, "
      "\"peak_rss_mb\": %.1f%s}\n",
      load, distribute, interpolate, packSecs, packRepeat, meshSecs, renderSecs, frameSecs, f.indices.size / 3,
      f.ranges.size, l.width, l.height, s.lod(), ms.representatives, ms.distinctMeshes, ms.storedVertices * mb,
      ms.vertices * mb, peakRssMb(), checkJson.c_str());
  return 0;
}

int cmdExport(const Common& c, const ExportArgs& a) {
  // Everything that can be refused is refused before the scene is evaluated: the extension and the coat
  // form first, then what the command's options add.
  ExportSettings settings;
  settings.coatAs = a.as;
  checkExportSettings(a.out, settings);
  const std::string ext = extensionOf(a.out);
  const bool usd = ext == ".usda";
  if (a.asGiven && !usd && a.as != "cards")
    throw Error("--as " + a.as + " needs a .usda file: glTF, OBJ and PLY carry the coat as cards", a.out, "--as");
  if (a.from.has_value() != a.to.has_value())
    throw Error("--from and --to go together", "", a.from ? "--to" : "--from");
  if (a.from && a.time) throw Error("give either --time or a range --from/--to", "", "--time");
  if (a.from) settings.times = exportFrameTimes(*a.from, *a.to, a.fps);
  settings.fps = a.fps;
  if (!(a.metersPerUnit > 0 && std::isfinite(a.metersPerUnit)))
    throw Error("expected a positive number", "", "--meters-per-unit");
  settings.metersPerUnit = a.metersPerUnit;
  if ((ext == ".obj" || ext == ".ply") && settings.times.size() > 1)
    throw Error("OBJ and PLY hold one frame: export a range as .glb, .gltf or .usda", a.out, "--from");
  {
    // An existing directory we may not write into fails now, not after the evaluation.
    const std::filesystem::path parent = std::filesystem::absolute(a.out).parent_path();
    std::error_code ec;
    if (std::filesystem::is_directory(parent, ec) && access(parent.c_str(), W_OK) != 0)
      throw Error("cannot write into the directory " + parent.string(), a.out, "--out");
    if (std::filesystem::is_directory(a.out, ec)) throw Error("is a directory", a.out, "--out");
  }
  Loaded l = load(c, a);
  ensureParentDir(a.out);  // after the scene is read: a scene that fails to load leaves no trace
  const ExportSummary r = l.session.exportTo(a.out, settings);
  endProgress(c);
  std::ostringstream os;
  os.precision(3);
  os << "wrote " << a.out << " (" << r.bytes << " bytes, " << r.frames << (r.frames == 1 ? " frame, " : " frames, ")
     << r.feathers << " feathers";
  if (usd && a.as == "curves")
    os << ", " << r.curves << " curves";
  else if (usd && a.as == "instances")
    os << ", " << r.instances << " instances of " << r.prototypes << " prototypes";
  else
    os << ", " << r.triangles << " triangles";
  os << "; " << std::fixed << r.seconds << " s, of which writing " << r.writeSeconds << " s)";
  info(c, os.str());
  return 0;
}

namespace {

// --rachis "x0,y0,x1,y1[,...]": pixel coordinates, base to tip.
std::vector<std::array<double, 2>> parseRachis(const std::string& text) {
  const std::string expected =
      "expected x0,y0,x1,y1 (pixels, from the rachis base to its tip; more pairs for a polyline)";
  std::vector<double> v;
  const char* p = text.data();
  const char* end = text.data() + text.size();
  while (true) {
    double x = 0;
    const auto r = std::from_chars(p, end, x);
    if (r.ec != std::errc() || !std::isfinite(x)) throw Error(expected + ", got '" + text + "'", "", "--rachis");
    v.push_back(x);
    p = r.ptr;
    if (p == end) break;
    if (*p != ',') throw Error(expected + ", got '" + text + "'", "", "--rachis");
    ++p;
  }
  if (v.size() < 4 || v.size() % 2)
    throw Error(expected + ", got " + std::to_string(v.size()) + " numbers", "", "--rachis");
  std::vector<std::array<double, 2>> pts;
  for (size_t i = 0; i < v.size(); i += 2) pts.push_back({{v[i], v[i + 1]}});
  return pts;
}

int featherFromScan(const Common& c, const FeatherArgs& a) {
  ScanSettings settings;
  if (a.rachis) settings.rachis = parseRachis(*a.rachis);
  if (a.pixelsPerUnit) {
    if (!(*a.pixelsPerUnit > 0 && std::isfinite(*a.pixelsPerUnit)))
      throw Error("expected scan pixels per scene unit > 0", "", "--pixels-per-unit");
    settings.pixelsPerUnit = *a.pixelsPerUnit;
  }
  settings.texture = a.texture;
  settings.writeTexture = !a.noTexture;
  ScanSummary r;
  try {
    r = writeFeatherFromScan(a.fromScan, a.out, settings);
  } catch (const Error& e) {
    // The host API names its settings; the CLI names its options.
    const std::string& el = e.element();
    const std::string option = el == "scan"            ? "--from-scan"
                               : el == "rachis"        ? "--rachis"
                               : el == "texture"       ? "--texture"
                               : el == "pixelsPerUnit" ? "--pixels-per-unit"
                               : el == "out"           ? "--out"
                                                       : el;
    throw Error(e.detail(), e.file(), option);
  }
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  const std::string resolution = r.resolution == "pixelsPerUnit"     ? "--pixels-per-unit"
                                 : r.resolution == "300 dpi assumed" ? "no resolution in the image: 300 dpi assumed"
                                                                     : r.resolution;
  char line[400];
  std::snprintf(line, sizeof line,
                "measured %s (rachis %s, %.1f pixels per unit from %s): rachis %.4g, lateral curvature %.1f deg, "
                "spacing %.4g..%.4g, angles left %.1f..%.1f deg, right %.1f..%.1f deg",
                a.fromScan.c_str(), r.rachisDetected ? "found" : "marked", r.pixelsPerUnit, resolution.c_str(),
                r.rachisLength, r.lateralCurvature * kDeg, r.spacingBase, r.spacingTip, r.leftBaseAngle * kDeg,
                r.leftTipAngle * kDeg, r.rightBaseAngle * kDeg, r.rightTipAngle * kDeg);
  info(c, line);
  for (const auto& n : r.notes) info(c, "note: " + n);
  info(c, "wrote " + a.out + (r.texture.empty() ? "" : " and its texture " + r.texture));
  return 0;
}

}  // namespace

int cmdFeather(const Common& c, const FeatherArgs& a) {
  if (!a.fromScan.empty()) return featherFromScan(c, a);
  if (a.file.empty()) throw Error("expected a feather file (.json), or --from-scan IMAGE", "", "file");
  checkOutExtension(a.out, {".obj", ".ply", ".png"}, "a mesh or an image");
  if (!(a.lod > 0 && a.lod <= 1)) throw Error("expected a fraction in (0, 1]", "", "--lod");
  FeatherOutput output;
  output.age = a.age;
  output.lod = a.lod;
  if (extensionOf(a.out) == ".png") {
    parseSize(a.size, "--size", output.width, output.height);
    requireMemory(double(output.width) * output.height * kBytesPerPixel, "a " + a.size + " image", "", "--size");
  }
  const size_t triangles = writeFeather(a.file, a.out, output);
  info(c, "wrote " + a.out + " (" + std::to_string(triangles) + " triangles)");
  return 0;
}

int cmdDiff(const Common& c, const DiffArgs& a) {
  const render::Image actual = render::loadImage(a.actual);
  const render::Image expected = render::loadImage(a.expected);
  const render::ImageDiff d = render::diffImages(actual, expected, a.tolerance);
  nlohmann::json j;
  j["actual"] = a.actual;
  j["golden"] = a.expected;
  j["width"] = actual.width;
  j["height"] = actual.height;
  j["same_size"] = d.sameSize;
  if (d.sameSize) {
    j["mean_error"] = d.meanError;
    j["max_error"] = d.maxError;
    j["max_at"] = d.maxX >= 0 ? nlohmann::json::array({d.maxX, d.maxY}) : nlohmann::json(nullptr);
    j["changed_pixels"] = d.changedPixels;
    j["changed_fraction"] = d.changedFraction;
  } else {
    j["golden_width"] = expected.width;
    j["golden_height"] = expected.height;
  }
  j["match"] = d.matches;
  j["tolerance"] = {
      {"pixel", a.tolerance.pixel}, {"fraction", a.tolerance.fraction}, {"max_error", a.tolerance.maxError}};
  std::printf("%s\n", j.dump().c_str());
  if (!d.sameSize) {
    info(c, a.actual + " is " + std::to_string(actual.width) + "x" + std::to_string(actual.height) + ", " + a.expected +
                " is " + std::to_string(expected.width) + "x" + std::to_string(expected.height) + ": differ");
    return 1;
  }
  if (!a.out.empty()) {
    ensureParentDir(a.out);
    render::saveImage(a.out, render::differenceImage(actual, expected, a.tolerance));
  }
  char line[256];
  std::snprintf(line, sizeof line, "%zu pixels (%s) changed by more than %.3g/255; max error %d/255", d.changedPixels,
                perCent(d.changedFraction).c_str(), a.tolerance.pixel * 255.0, int(std::lround(d.maxError * 255.0)));
  std::string msg = line;
  if (d.maxX >= 0) msg += " at (" + std::to_string(d.maxX) + "," + std::to_string(d.maxY) + ")";
  info(c, msg + (d.matches ? ": match" : ": differ"));
  return d.matches ? 0 : 1;
}

}  // namespace pteryla::cli
