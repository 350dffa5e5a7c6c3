// `pteryla frames` (a frame range, or one chunk of it, rendered or exported, with sidecar checksums and
// assembly) and `pteryla farm slurm` (the same range as a Slurm job array). docs/farm.md.
#include "commands.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
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

// ------------------------------------------------------------------ frames, chunks and the farm
//
// A frame is a pure function of (scene, time), so a range can be split into chunks rendered anywhere.
// Contract (docs/farm.md): frame k of `--from A --to B --fps N` is at time A + k / N and is written to
// DIR/frame_NNNN.png (k global, whatever the chunking), or with `--export .glb|.gltf|.usda` exported to
// DIR/frame_NNNN.glb (...). Its sidecar DIR/frame_NNNN.png.json is written atomically after the frame and
// records the frame file's SHA-256, the seconds, the host and the parameters that made it; a frame counts
// as complete only when its sidecar parses, its parameters match this run and the file's digest matches.
// `--chunk K --task I` makes frames [I*K, min((I+1)*K, count)) and touches nothing else; `--assemble`
// checks every frame and writes DIR/frames.json (and, for PNG frames, DIR/contact_sheet.png).

namespace {

namespace fs = std::filesystem;

// frame_0000.png, frame_0001.png, ... (or .glb, .gltf, .usda with --export): the name pattern `frames`
// owns in its directory.
std::string frameName(uint64_t k, const std::string& ext) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%04llu", static_cast<unsigned long long>(k));
  return name + ext;
}
std::string sidecarName(uint64_t k, const std::string& ext) { return frameName(k, ext) + ".json"; }
// frame_NNNN<ext> or its sidecar frame_NNNN<ext>.json.
bool isFrameName(std::string n, uint64_t& index, const std::string& ext) {
  if (n.size() > 5 && n.compare(n.size() - 5, 5, ".json") == 0) n.resize(n.size() - 5);
  if (n.size() < 10 + ext.size() || n.compare(0, 6, "frame_") != 0 ||
      n.compare(n.size() - ext.size(), ext.size(), ext) != 0)
    return false;
  const std::string digits = n.substr(6, n.size() - 6 - ext.size());
  if (digits.size() < 4 || digits.find_first_not_of("0123456789") != std::string::npos) return false;
  const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), index);
  return r.ec == std::errc() && frameName(index, ext) == n;
}
// The extension of a run's frame files: ".png", or the --export format's.
std::string frameExt(const FramesArgs& a) { return a.exportExt.empty() ? ".png" : a.exportExt; }

// Shortest decimal that reads back as exactly `v` (so a farm node computes the same frame times).
std::string fmt17(double v) {
  char buf[40];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string hostName() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

uint64_t frameCount(const FramesArgs& a) {
  if (!std::isfinite(a.from)) throw Error("expected a finite time", "", "--from");
  if (!std::isfinite(a.to)) throw Error("expected a finite time", "", "--to");
  if (!(a.to >= a.from)) throw Error("--to must not be before --from", "", "--to");
  // Counted in double: (to - from) * fps can exceed any integer type (--to 3e9).
  const double countD = std::floor((a.to - a.from) * a.fps + 1e-9) + 1;
  constexpr double kMaxFrames = 100000;
  if (!(countD <= kMaxFrames)) {
    std::ostringstream os;
    os << "too many frames (" << countD << ", at most " << kMaxFrames << "); lower --fps or the range";
    throw Error(os.str(), "", "--to");
  }
  return static_cast<uint64_t>(countD);
}

// Number of chunks of `chunk` frames; throws naming --chunk / --task when they are out of range.
uint64_t checkChunking(const FramesArgs& a, uint64_t count) {
  if (a.chunk.has_value() != a.task.has_value())
    throw Error("--chunk and --task go together (render chunk TASK of CHUNK frames)", "",
                a.chunk ? "--task" : "--chunk");
  if (!a.chunk) return 1;
  if (*a.chunk < 1) throw Error("expected a number of frames >= 1, got " + std::to_string(*a.chunk), "", "--chunk");
  const uint64_t tasks = (count + uint64_t(*a.chunk) - 1) / uint64_t(*a.chunk);
  if (*a.task < 0 || uint64_t(*a.task) >= tasks)
    throw Error("expected a 0-based chunk index in [0, " + std::to_string(tasks - 1) + "] (" + std::to_string(count) +
                    " frames in chunks of " + std::to_string(*a.chunk) + "), got " + std::to_string(*a.task),
                "", "--task");
  return tasks;
}

// What made a frame; a sidecar whose params differ (another scene file, size, LOD, style, seed or time)
// does not count as complete.
// An exported frame has no image size or style; its format, --as and --meters-per-unit made it instead.
nlohmann::json frameParams(const FramesArgs& a, const std::string& sceneDigest, int w, int h, double t) {
  nlohmann::json p;
  p["scene"] = fs::absolute(a.scene).lexically_normal().string();
  p["scene_sha256"] = sceneDigest;
  p["time"] = t;
  if (a.exportExt.empty()) {
    p["width"] = w;
    p["height"] = h;
    p["style"] = a.style;
  } else {
    p["export"] = a.exportExt;
    p["as"] = a.as;
    p["meters_per_unit"] = a.metersPerUnit;
  }
  p["lod"] = a.lod ? nlohmann::json(*a.lod) : nlohmann::json(nullptr);
  if (a.exportExt.empty()) p["fixed_lod"] = a.fixedLod;  // exports mesh at --lod either way
  if (a.instanceTolerance) p["instance_tolerance"] = *a.instanceTolerance;
  p["seed"] = a.seed;
  return p;
}

struct FrameStatus {
  bool complete = false;
  std::string problem;  // why not: "missing", "no sidecar", "checksum mismatch", ...
  nlohmann::json sidecar;
};

FrameStatus checkFrame(const std::string& dir, uint64_t k, const std::string& ext, const nlohmann::json& params) {
  FrameStatus s;
  const fs::path png = fs::path(dir) / frameName(k, ext);
  std::error_code ec;
  if (!fs::is_regular_file(png, ec)) return s.problem = "missing", s;
  std::ifstream in(fs::path(dir) / sidecarName(k, ext), std::ios::binary);
  if (!in) return s.problem = "no sidecar", s;
  s.sidecar = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  const nlohmann::json& j = s.sidecar;
  if (!j.is_object() || !j.contains("sha256") || !j["sha256"].is_string() || !j.contains("seconds") ||
      !j["seconds"].is_number() || !j.contains("host") || !j["host"].is_string())
    return s.problem = "unreadable sidecar", s;
  if (s.sidecar.value("params", nlohmann::json()) != params) return s.problem = "made with other parameters", s;
  if (sha256File(png.string()) != s.sidecar["sha256"].get<std::string>()) return s.problem = "checksum mismatch", s;
  s.complete = true;
  return s;
}

// Removes frames (and sidecars) with an index >= count: an earlier, longer run's frames would look like
// part of this sequence.
size_t removeFramesFrom(const std::string& dir, uint64_t count, const std::string& ext) {
  size_t removed = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    uint64_t index = 0;
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && isFrameName(name, index, ext) && index >= count) {
      std::error_code rm;
      if (fs::remove(entry.path(), rm) && name.size() > ext.size() &&
          name.compare(name.size() - ext.size(), ext.size(), ext) == 0)
        ++removed;
    }
  }
  return removed;
}

// DIR/frames.json from the sidecars of frames [0, count) (all complete).
void writeManifest(const FramesArgs& a, int w, int h, uint64_t count, const std::vector<nlohmann::json>& sidecars,
                   const std::string& contactSheet, const nlohmann::json& golden = nullptr) {
  std::ostringstream m;
  m.precision(17);
  m << "{\n  \"scene\": \"" << jsonEscape(a.scene) << "\",\n  \"from\": " << a.from << ",\n  \"to\": " << a.to
    << ",\n  \"fps\": " << a.fps;
  if (a.exportExt.empty())
    m << ",\n  \"width\": " << w << ",\n  \"height\": " << h;
  else
    m << ",\n  \"export\": \"" << a.exportExt << "\",\n  \"as\": \"" << jsonEscape(a.as) << "\"";
  m << ",\n  \"count\": " << count;
  if (!contactSheet.empty()) m << ",\n  \"contact_sheet\": \"" << jsonEscape(contactSheet) << "\"";
  if (!golden.is_null()) m << ",\n  \"golden\": " << golden.dump();
  m << ",\n  \"frames\": [";
  for (uint64_t k = 0; k < count; ++k) {
    const nlohmann::json& s = sidecars[k];
    m << (k ? ",\n    " : "\n    ") << "{\"file\": \"" << frameName(k, frameExt(a))
      << "\", \"time\": " << a.from + double(k) / a.fps << ", \"sha256\": \"" << jsonEscape(s.value("sha256", ""))
      << "\", \"seconds\": " << jsonNumberOrNull(s.value("seconds", 0.0)) << ", \"host\": \""
      << jsonEscape(s.value("host", "")) << "\"}";
  }
  m << "\n  ]\n}\n";
  writeFileAtomic((fs::path(a.out) / "frames.json").string(), m.str());
}

// A grid of downscaled frames (at most kMaxTiles, evenly sampled), tiles at most 160 px on a side.
void writeContactSheet(const std::string& path, const std::string& dir, uint64_t count) {
  constexpr uint64_t kMaxTiles = 64;
  constexpr int kTile = 160, kGap = 4;
  const uint64_t n = std::min(count, kMaxTiles);
  std::vector<render::Image> tiles;
  int tw = 0, th = 0;
  for (uint64_t i = 0; i < n; ++i) {
    const uint64_t k = n == 1 ? 0 : i * (count - 1) / (n - 1);
    tiles.push_back(render::fitImage(render::loadImage((fs::path(dir) / frameName(k, ".png")).string()), kTile));
    tw = std::max(tw, tiles.back().width);
    th = std::max(th, tiles.back().height);
  }
  const int cols = int(std::ceil(std::sqrt(double(n))));
  const int rows = int((n + cols - 1) / cols);
  render::Image sheet(cols * (tw + kGap) + kGap, rows * (th + kGap) + kGap, 32, 32, 32, 255);
  for (uint64_t i = 0; i < n; ++i) {
    const int x0 = kGap + int(i % cols) * (tw + kGap), y0 = kGap + int(i / cols) * (th + kGap);
    const render::Image& t = tiles[i];
    for (int y = 0; y < t.height; ++y) std::copy(t.pixel(0, y), t.pixel(0, y) + 4 * t.width, sheet.pixel(x0, y0 + y));
  }
  render::saveImage(path, sheet);
}

// --golden: frames [lo, hi) of a.out against GOLDEN/frame_NNNN.png. A difference is pictured in
// a.out/golden_diff/frame_NNNN.png. Returns the manifest's "golden" object.
struct GoldenReport {
  size_t compared = 0, failed = 0;
  std::vector<std::string> problems;  // the first few, for the message
  nlohmann::json json;
};

GoldenReport compareWithGolden(const Common& c, const FramesArgs& a, uint64_t lo, uint64_t hi) {
  GoldenReport r;
  std::error_code ec;
  if (!fs::is_directory(a.golden, ec)) throw Error("expected a directory of golden frames", a.golden, "--golden");
  r.json["dir"] = fs::absolute(a.golden).lexically_normal().string();
  r.json["tolerance"] = {{"pixel", a.goldenTolerance.pixel},
                         {"fraction", a.goldenTolerance.fraction},
                         {"max_error", a.goldenTolerance.maxError}};
  nlohmann::json failures = nlohmann::json::array();
  for (uint64_t k = lo; k < hi; ++k) {
    const std::string name = frameName(k, frameExt(a));
    const fs::path golden = fs::path(a.golden) / name;
    nlohmann::json f;
    f["file"] = name;
    std::string problem;
    if (!fs::is_regular_file(golden, ec)) {
      problem = "no golden";
    } else if (!a.exportExt.empty()) {
      // Exports are deterministic: an exported frame matches its golden byte for byte.
      if (sha256File((fs::path(a.out) / name).string()) != sha256File(golden.string()))
        problem = "the file differs from the golden";
    } else {
      const render::Image actual = render::loadImage((fs::path(a.out) / name).string());
      const render::Image expected = render::loadImage(golden.string());
      const render::ImageDiff d = render::diffImages(actual, expected, a.goldenTolerance);
      if (!d.sameSize) {
        problem = std::to_string(actual.width) + "x" + std::to_string(actual.height) + ", golden " +
                  std::to_string(expected.width) + "x" + std::to_string(expected.height);
      } else if (!d.matches) {
        problem = perCent(d.changedFraction) + " of pixels changed, max error " +
                  std::to_string(int(std::lround(d.maxError * 255))) + "/255";
        fs::create_directories(fs::path(a.out) / "golden_diff", ec);
        render::saveImage((fs::path(a.out) / "golden_diff" / name).string(),
                          render::differenceImage(actual, expected, a.goldenTolerance));
      }
      if (d.sameSize) {
        f["max_error"] = d.maxError;
        f["changed_fraction"] = d.changedFraction;
      }
    }
    ++r.compared;
    if (!problem.empty()) {
      ++r.failed;
      f["problem"] = problem;
      failures.push_back(f);
      if (r.problems.size() < 5) r.problems.push_back(name + " (" + problem + ")");
    }
  }
  r.json["compared"] = r.compared;
  r.json["failed"] = failures;
  if (r.failed) {
    std::string list;
    for (const auto& p : r.problems) list += (list.empty() ? "" : ", ") + p;
    if (r.failed > r.problems.size()) list += ", ...";
    std::fprintf(stderr, "pteryla: %zu of %zu frames differ from the goldens in %s: %s%s\n", r.failed, r.compared,
                 a.golden.c_str(), list.c_str(),
                 fs::exists(fs::path(a.out) / "golden_diff", ec)
                     ? ("; differences pictured in " + (fs::path(a.out) / "golden_diff").string() + "/").c_str()
                     : "");
  } else {
    info(c, "all " + std::to_string(r.compared) + " frames match the goldens in " + a.golden);
  }
  return r;
}

int assembleFrames(const Common& c, const FramesArgs& a, uint64_t count, const Loaded& l,
                   const std::string& sceneDigest) {
  std::vector<nlohmann::json> sidecars(count);
  std::vector<std::string> problems;
  size_t bad = 0;
  for (uint64_t k = 0; k < count; ++k) {
    FrameStatus s =
        checkFrame(a.out, k, frameExt(a), frameParams(a, sceneDigest, l.width, l.height, a.from + double(k) / a.fps));
    if (!s.complete) {
      if (problems.size() < 10) problems.push_back(frameName(k, frameExt(a)) + " (" + s.problem + ")");
      ++bad;
    }
    sidecars[k] = std::move(s.sidecar);
  }
  if (bad) {
    std::string list;
    for (const auto& p : problems) list += (list.empty() ? "" : ", ") + p;
    if (bad > problems.size()) list += ", ...";
    throw Error(std::to_string(bad) + " of " + std::to_string(count) + " frames are missing or invalid: " + list +
                    "; rerun their tasks (a rerun renders only these)",
                a.out, "--assemble");
  }
  const size_t removed = removeFramesFrom(a.out, count, frameExt(a));
  const bool images = a.exportExt.empty();  // a contact sheet of exported files would need a renderer
  if (images) writeContactSheet((fs::path(a.out) / "contact_sheet.png").string(), a.out, count);
  GoldenReport golden;
  if (!a.golden.empty()) golden = compareWithGolden(c, a, 0, count);
  writeManifest(a, l.width, l.height, count, sidecars, images ? "contact_sheet.png" : "", golden.json);
  if (golden.failed) return 1;
  info(c, "assembled " + std::to_string(count) + " frames in " + a.out + ": every checksum matches; wrote frames.json" +
              (images ? " and contact_sheet.png" : "") +
              (removed ? " (removed " + std::to_string(removed) + " stale frames of an earlier run)" : ""));
  return 0;
}

}  // namespace

namespace {

// --export and what goes with it: refused before the scene is evaluated. Returns the settings each
// frame's export uses (one frame, at the session's time).
ExportSettings checkFramesExport(FramesArgs& a) {
  ExportSettings settings;
  if (a.exportExt.empty()) {
    if (a.asGiven) throw Error("--as chooses how --export .usda carries the coat; PNG frames take no --as", "", "--as");
    if (a.metersGiven) throw Error("--meters-per-unit applies to --export only", "", "--meters-per-unit");
    return settings;
  }
  std::string ext = a.exportExt;
  if (ext.front() != '.') ext.insert(ext.begin(), '.');
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
  if (ext != ".glb" && ext != ".gltf" && ext != ".usda")
    throw Error(
        "expected .glb, .gltf or .usda (a frame sequence of OBJ or PLY files is not offered: export one "
        "frame with `pteryla export --time T`), got '" +
            a.exportExt + "'",
        "", "--export");
  a.exportExt = ext;
  settings.coatAs = a.as;
  checkExportSettings("frame" + ext, settings);  // the coat form's name
  if (a.asGiven && ext != ".usda" && a.as != "cards")
    throw Error("--as " + a.as + " needs --export .usda: glTF carries the coat as cards", "", "--as");
  if (ext != ".usda") a.as = "cards";  // what the file holds, in the sidecars and the manifest
  if (!(a.metersPerUnit > 0 && std::isfinite(a.metersPerUnit)))
    throw Error("expected a positive number", "", "--meters-per-unit");
  settings.metersPerUnit = a.metersPerUnit;
  settings.fps = a.fps;
  if (!a.style.empty()) throw Error("--style applies to rendered frames, not to --export", "", "--style");
  if (!a.size.empty()) throw Error("--size applies to rendered frames, not to --export", "", "--size");
  return settings;
}

}  // namespace

int cmdFrames(const Common& c, const FramesArgs& args) {
  FramesArgs a = args;
  const ExportSettings exportSettings = checkFramesExport(a);
  const bool exporting = !a.exportExt.empty();
  const std::string ext = frameExt(a);
  const uint64_t count = frameCount(a);
  const uint64_t tasks = checkChunking(a, count);
  if (a.assemble && a.chunk)
    throw Error("--assemble checks the whole range; it takes no --chunk/--task", "", "--assemble");
  if (!a.golden.empty()) {
    std::error_code ec;
    if (!fs::is_directory(a.golden, ec)) throw Error("expected a directory of golden frames", a.golden, "--golden");
  }
  Loaded l = load(c, a);
  const std::string sceneDigest = sha256File(a.scene);
  if (a.assemble) return assembleFrames(c, a, count, l, sceneDigest);

  const uint64_t lo = a.chunk ? uint64_t(*a.task) * uint64_t(*a.chunk) : 0;
  const uint64_t hi = a.chunk ? std::min(count, lo + uint64_t(*a.chunk)) : count;
  auto timeOf = [&](uint64_t k) { return a.from + double(k) / a.fps; };
  std::vector<uint64_t> todo;
  std::vector<nlohmann::json> sidecars(count);
  for (uint64_t k = lo; k < hi; ++k) {
    FrameStatus s;
    if (!a.force) s = checkFrame(a.out, k, ext, frameParams(a, sceneDigest, l.width, l.height, timeOf(k)));
    if (s.complete)
      sidecars[k] = std::move(s.sidecar);
    else
      todo.push_back(k);
  }
  const std::string host = hostName();
  if (!todo.empty()) {
    // The session keeps one renderer for every frame (exported frames never make one); its progress
    // bar reported the first evaluation, and the frames get one bar of their own.
    l.session.setProgress({});
    RenderSettings look;
    look.width = l.width;
    look.height = l.height;
    look.style = a.style;
    const Progress bar = makeProgress(c);
    for (size_t i = 0; i < todo.size(); ++i) {
      const uint64_t k = todo[i];
      const auto t0 = std::chrono::steady_clock::now();
      l.session.setTime(timeOf(k));
      render::Image frame;
      if (!exporting)
        frame = l.session.renderImage(look);
      else if (!l.session.evaluate())
        throw InternalError("a frame's evaluation was cancelled");  // before the directory exists
      // The first frame is made before the directory exists: a scene that fails creates nothing.
      if (i == 0) {
        std::error_code ec;
        fs::create_directories(a.out, ec);
        if (ec) throw Error("cannot create output directory: " + ec.message(), a.out, "--out");
      }
      const std::string png = (fs::path(a.out) / frameName(k, ext)).string();
      const std::string side = (fs::path(a.out) / sidecarName(k, ext)).string();
      std::error_code rm;
      fs::remove(side, rm);  // a crash between the frame and its new sidecar must not leave an old, matching one
      if (exporting) {
        // The session is already at this frame's time: exportTo samples it there (the same file as
        // `pteryla export --time T`).
        l.session.exportTo(png, exportSettings);
      } else {
        render::saveImage(png, frame);
      }
      nlohmann::json s;
      s["file"] = frameName(k, ext);
      s["frame"] = k;
      s["time"] = timeOf(k);
      s["sha256"] = sha256File(png);
      s["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      s["host"] = host;
      s["params"] = frameParams(a, sceneDigest, l.width, l.height, timeOf(k));
      writeFileAtomic(side, s.dump(2) + "\n");
      sidecars[k] = std::move(s);
      if (bar) bar("frames", double(i + 1) / double(todo.size()));
    }
  }
  const uint64_t skipped = (hi - lo) - todo.size();
  const std::string skippedText = skipped ? ", skipped " + std::to_string(skipped) + " complete" : "";
  if (a.chunk) {
    // A chunk touches only its own frames: no stale-frame removal, no manifest (that is --assemble's job).
    endProgress(c);
    if (!a.golden.empty() && compareWithGolden(c, a, lo, hi).failed) return 1;
    info(c, "chunk " + std::to_string(*a.task) + " of " + std::to_string(tasks) + " (frames " + std::to_string(lo) +
                "-" + std::to_string(hi - 1) + "): " + (exporting ? "exported " : "rendered ") +
                std::to_string(todo.size()) + skippedText + " in " + a.out);
    return 0;
  }
  std::error_code ec;
  fs::create_directories(a.out, ec);  // every frame may have been skipped; the directory then exists already
  const size_t removed = removeFramesFrom(a.out, count, ext);
  endProgress(c);
  GoldenReport golden;
  if (!a.golden.empty()) golden = compareWithGolden(c, a, 0, count);
  writeManifest(a, l.width, l.height, count, sidecars, "", golden.json);
  info(c, std::string(exporting ? "exported " : "wrote ") + std::to_string(todo.size()) + " frames to " + a.out +
              skippedText +
              (removed ? " (removed " + std::to_string(removed) + " stale frames of an earlier run)" : ""));
  return golden.failed ? 1 : 0;
}

namespace {

// 'text' for a POSIX shell.
std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (const char ch : s) out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return out + "'";
}

std::string findOnPath(const std::string& exe) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string d;
  while (std::getline(dirs, d, ':')) {
    const fs::path p = fs::path(d.empty() ? "." : d) / exe;
    if (access(p.c_str(), X_OK) == 0) return p.string();
  }
  return {};
}

// Runs `cmd` through the shell; stdout, or throws Error naming what failed.
std::string runCapture(const std::string& cmd, const std::string& what) {
  std::FILE* p = popen(cmd.c_str(), "r");
  if (!p) throw Error("cannot run " + what);
  std::string out;
  char buf[512];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int status = pclose(p);
  if (status != 0) throw Error(what + " failed (" + cmd + "): " + out);
  return out;
}

}  // namespace

int cmdFarmSlurm(const Common& c, const FarmArgs& args) {
  FarmArgs a = args;
  checkFramesExport(a);  // normalises a.exportExt
  const uint64_t count = frameCount(a);
  if (a.farmChunk < 1)
    throw Error("expected a number of frames >= 1, got " + std::to_string(a.farmChunk), "", "--chunk");
  if (a.lod && !(*a.lod > 0 && *a.lod <= 1))
    throw Error("expected a fraction in (0, 1], got " + std::to_string(*a.lod), "", "--lod");
  if (!a.seed.empty()) parseSeed(a.seed);
  int w = 0, h = 0;
  if (!a.size.empty()) parseSize(a.size, "--size", w, h);
  if (a.partition.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.,-") !=
      std::string::npos)
    throw Error("expected a partition name (letters, digits, _ . , -), got '" + a.partition + "'", "", "--partition");
  if (!a.mem.empty() &&
      (a.mem.find_first_not_of("0123456789KMGTkmgt") != std::string::npos || a.mem.find_first_of("0123456789") != 0))
    throw Error("expected a Slurm memory size such as 2G or 4000M, got '" + a.mem + "'", "", "--mem");
  if (!a.dryRun && findOnPath("sbatch").empty())
    throw Error(
        "sbatch not found on PATH: run on a Slurm login node (Debian: slurm-client), or use --dry-run to only "
        "write the scripts",
        "", "farm slurm");
  Session::fromSceneFile(a.scene);  // a scene that does not load fails here, not on every node
  const uint64_t tasks = (count + uint64_t(a.farmChunk) - 1) / uint64_t(a.farmChunk);
  const std::string exe = fs::read_symlink("/proc/self/exe").string();
  const std::string scene = fs::absolute(a.scene).lexically_normal().string();
  const std::string out = fs::absolute(a.out).lexically_normal().string();
  const std::string dir = (fs::path(out) / "slurm").string();

  // The arguments both scripts share: the same range and parameters make the same frame parameters.
  std::string common = shellQuote(exe) + " frames " + shellQuote(scene) + " --from " + fmt17(a.from) + " --to " +
                       fmt17(a.to) + " --fps " + fmt17(a.fps) + " --out " + shellQuote(out);
  if (a.lod) common += " --lod " + fmt17(*a.lod);
  if (a.fixedLod) common += " --fixed-lod";
  if (a.instanceTolerance) common += " --instance-tolerance " + fmt17(*a.instanceTolerance);
  if (!a.size.empty()) common += " --size " + shellQuote(a.size);
  if (!a.seed.empty()) common += " --seed " + a.seed;
  if (!a.style.empty()) common += " --style " + a.style;
  if (!a.exportExt.empty()) {
    common += " --export " + a.exportExt;
    if (a.asGiven) common += " --as " + shellQuote(a.as);
    if (a.metersGiven) common += " --meters-per-unit " + fmt17(a.metersPerUnit);
  }
  if (c.maxMemoryGb) common += " --max-memory " + fmt17(*c.maxMemoryGb);
  common += " --quiet";
  // Goldens are compared once, by the assembly job, over the whole range.
  std::string goldenArgs;
  if (!a.golden.empty()) {
    std::error_code gec;
    if (!fs::is_directory(a.golden, gec)) throw Error("expected a directory of golden frames", a.golden, "--golden");
    goldenArgs = " --golden " + shellQuote(fs::absolute(a.golden).lexically_normal().string()) +
                 " --golden-tolerance " + fmt17(a.goldenTolerance.pixel) + " --golden-fraction " +
                 fmt17(a.goldenTolerance.fraction) + " --golden-max-error " + fmt17(a.goldenTolerance.maxError);
  }
  auto header = [&](const std::string& name, const std::string& log) {
    std::string h = "#!/bin/bash\n# Written by `pteryla farm slurm` (docs/farm.md).\n#SBATCH --job-name=" + name +
                    "\n#SBATCH --output=" + dir + "/" + log + "\n#SBATCH --ntasks=1\n";
    if (!a.partition.empty()) h += "#SBATCH --partition=" + a.partition + "\n";
    if (!a.mem.empty()) h += "#SBATCH --mem=" + a.mem + "\n";
    return h;
  };
  const std::string framesScript =
      header("pteryla-frames", "frames_%A_%a.log") + "#SBATCH --array=0-" + std::to_string(tasks - 1) +
      "\n#SBATCH --requeue\n# " + std::to_string(count) + " frames in " + std::to_string(tasks) + " chunks of " +
      std::to_string(a.farmChunk) + "; a requeued task renders only its frames without a valid sidecar.\nexec " +
      common + " --chunk " + std::to_string(a.farmChunk) + " --task \"$SLURM_ARRAY_TASK_ID\"\n";
  const std::string assembleScript =
      header("pteryla-assemble", "assemble_%j.log") +
      "# Checks every frame's checksum, writes frames.json and contact_sheet.png.\nexec " + common + " --assemble" +
      goldenArgs + "\n";
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create directory: " + ec.message(), dir, "--out");
  const std::string framesPath = dir + "/frames.sbatch", assemblePath = dir + "/assemble.sbatch";
  writeFileAtomic(framesPath, framesScript);
  writeFileAtomic(assemblePath, assembleScript);
  fs::permissions(framesPath, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);
  fs::permissions(assemblePath, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);

  const std::string submit1 = "sbatch --parsable " + shellQuote(framesPath);
  auto submit2 = [&](const std::string& id) {
    return "sbatch --parsable --dependency=afterok:" + id + " --kill-on-invalid-dep=yes " + shellQuote(assemblePath);
  };
  if (a.dryRun) {
    std::printf("# %s\n%s\n# %s\n%s\n# submit (dry run: nothing was submitted):\nJOB=$(%s)\n%s\n", framesPath.c_str(),
                framesScript.c_str(), assemblePath.c_str(), assembleScript.c_str(), submit1.c_str(),
                submit2("\"${JOB%%;*}\"").c_str());
    info(c, "wrote " + framesPath + " (" + std::to_string(tasks) + " tasks) and " + assemblePath + "; not submitted");
    return 0;
  }
  auto jobId = [](const std::string& text) {
    const std::string id = text.substr(0, text.find_first_of(";\n"));
    if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
      throw Error("sbatch printed no job id: '" + text + "'", "", "farm slurm");
    return id;
  };
  const std::string arrayJob = jobId(runCapture(submit1 + " 2>&1", "sbatch"));
  const std::string assembleJob = jobId(runCapture(submit2(arrayJob) + " 2>&1", "sbatch"));
  std::printf("{\"array_job\": %s, \"tasks\": %llu, \"assemble_job\": %s}\n", arrayJob.c_str(),
              static_cast<unsigned long long>(tasks), assembleJob.c_str());
  info(c, "submitted job array " + arrayJob + " (" + std::to_string(tasks) + " tasks) and assembly job " + assembleJob +
              "; output in " + out);
  return 0;
}

}  // namespace pteryla::cli
