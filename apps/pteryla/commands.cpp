// The pteryla subcommands. Every scene command evaluates through pipeline::Pipeline; rendering goes
// through render::SceneView on an OSMesa context, so `render --time T` and `frames` draw identically.
#include "commands.hpp"

#include <sys/resource.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/feather/mesh_io.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/scene_view.hpp"

namespace pteryla::cli {
namespace {

using pipeline::Pipeline;
using pipeline::Stage;

struct Loaded {
  std::unique_ptr<Pipeline> pipeline;
  int width = 0, height = 0;
};

// Bytes per rendered pixel: OSMesa colour + depth buffers, the read-back, the flipped Image and the
// encoder's copy.
constexpr double kBytesPerPixel = 24.0;

uint64_t parseSeed(const std::string& text) {
  uint64_t v = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size())
    throw Error("expected an integer in [0, 18446744073709551615], got '" + text + "'", "", "--seed");
  return v;
}

Loaded load(const Common& c, const SceneArgs& a) {
  Loaded l;
  if (!a.size.empty()) parseSize(a.size, "--size", l.width, l.height);
  if (a.lod && !(*a.lod > 0 && *a.lod <= 1)) throw Error("expected a fraction in (0, 1], got " + std::to_string(*a.lod), "", "--lod");
  if (a.time && !std::isfinite(*a.time)) throw Error("expected a finite time", "", "--time");
  const std::optional<uint64_t> seed = a.seed.empty() ? std::nullopt : std::optional<uint64_t>(parseSeed(a.seed));
  if (l.width)
    requireMemory(double(l.width) * l.height * kBytesPerPixel, "a " + a.size + " image", "", "--size");
  pipeline::Scene s = pipeline::loadScene(a.scene);
  if (seed) s.seed = *seed;
  if (!l.width) {
    l.width = s.render.width;
    l.height = s.render.height;
    requireMemory(double(l.width) * l.height * kBytesPerPixel,
                  "a " + std::to_string(l.width) + "x" + std::to_string(l.height) + " image", s.file, "render.size");
  }
  l.pipeline = std::make_unique<Pipeline>(std::move(s), makeProgress(c));
  if (a.time) l.pipeline->setTime(*a.time);
  if (a.lod) l.pipeline->setLod(*a.lod);
  return l;
}

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

std::string jsonNumberOrNull(const std::optional<double>& v) {
  if (!v || !std::isfinite(*v)) return "null";
  std::ostringstream os;
  os.precision(6);
  os << *v;
  return os.str();
}
std::string jsonEscape(const std::string& in) {
  std::string out;
  for (const char ch : in) {
    if (ch == '"' || ch == '\\') out.push_back('\\');
    if (static_cast<unsigned char>(ch) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", ch);
      out += buf;
    } else {
      out.push_back(ch);
    }
  }
  return out;
}

std::string jsonCountOrNull(const std::optional<size_t>& v) { return v ? std::to_string(*v) : "null"; }

}  // namespace

int cmdRender(const Common& c, const RenderArgs& a) {
  checkOutExtension(a.out, {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr"}, "an image");
  Loaded l = load(c, a);
  render::OsMesaContext ctx(l.width, l.height);
  render::SceneView view(ctx);
  const render::Image img = view.render(*l.pipeline, l.width, l.height, a.style);
  // Directories are created only once the scene has evaluated: a failing scene leaves no trace.
  ensureParentDir(a.out);
  render::saveImage(a.out, img);
  endProgress(c);
  info(c, "wrote " + a.out + " (" + std::to_string(l.width) + "x" + std::to_string(l.height) + ", " +
              std::to_string(l.pipeline->coatMesh().ranges.size()) + " feathers, " +
              std::to_string(l.pipeline->coatMesh().mesh.triangleCount()) + " feather triangles)");
  return 0;
}

int cmdCheck(const Common& c, const SceneArgs& a) {
  Loaded l = load(c, a);
  const pipeline::QualityMetrics m = l.pipeline->check();
  endProgress(c);
  std::printf(
      "{\"follicles\": %s, \"hex_fraction\": %s, \"nn_cv\": %s, \"feathers\": %s, \"intersecting_pairs\": %s, "
      "\"intersecting_pairs_unpacked\": %s, \"intersecting_pairs_proxy\": %s, \"skin_penetrations\": %s, \"coverage\": %s, "
      "\"elevation_p50\": %s, \"elevation_p90\": %s, \"fixed_feathers\": %s, \"hidden_feathers\": %s}\n",
      jsonCountOrNull(m.follicles).c_str(), jsonNumberOrNull(m.hexFraction).c_str(), jsonNumberOrNull(m.nnCv).c_str(),
      jsonCountOrNull(m.feathers).c_str(), jsonCountOrNull(m.intersectingPairs).c_str(),
      jsonCountOrNull(m.intersectingPairsUnpacked).c_str(), jsonCountOrNull(m.intersectingPairsProxy).c_str(),
      jsonCountOrNull(m.skinPenetrations).c_str(), jsonNumberOrNull(m.coverage).c_str(),
      jsonNumberOrNull(m.elevationP50).c_str(), jsonNumberOrNull(m.elevationP90).c_str(),
      jsonCountOrNull(m.fixedFeathers).c_str(), jsonCountOrNull(m.hiddenFeathers).c_str());
  return 0;
}

int cmdBench(const Common& c, const SceneArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  Loaded l = load(c, a);
  Pipeline& p = *l.pipeline;
  const double parse = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  p.coatMesh();  // evaluates every stage once
  render::OsMesaContext ctx(l.width, l.height);
  render::SceneView view(ctx);
  view.render(p, l.width, l.height);  // warm-up: shader compile, uploads
  const auto r0 = std::chrono::steady_clock::now();
  view.render(p, l.width, l.height);
  const double renderSecs = std::chrono::duration<double>(std::chrono::steady_clock::now() - r0).count();
  // First-evaluation seconds per stage, read before the scrub below resets the timings.
  auto& g = p.graph();
  auto secs = [&](Stage s) { return g.lastSeconds(g.find(pipeline::stageName(s))); };
  const double load = parse + secs(Stage::Skin) + secs(Stage::Tracts);
  const double distribute = secs(Stage::Distribute);
  const double interpolate = secs(Stage::Interpolate) + secs(Stage::Directions);
  const double packSecs = secs(Stage::Pack) + secs(Stage::Controls);
  const double meshSecs = secs(Stage::Mesh);
  // A full pack again with warm memory (best of 3): what repacking the coat costs after an edit.
  const double packRepeat = p.timeFullPack(3);
  // A second frame at a new time: what a timeline scrub costs (pose, ages, controls, pack, mesh).
  const double t = p.time();
  p.setTime(t + 1e-3);
  const auto f0 = std::chrono::steady_clock::now();
  p.coatMesh();
  const double frameSecs = std::chrono::duration<double>(std::chrono::steady_clock::now() - f0).count();
  p.setTime(t);
  p.coatMesh();
  endProgress(c);
  std::printf(
      "{\"load\": %.6f, \"distribute\": %.6f, \"interpolate\": %.6f, \"pack\": %.6f, \"pack_repeat\": %.6f, "
      "\"mesh\": %.6f, \"render\": %.6f, "
      "\"frame\": %.6f, \"triangles\": %zu, \"feathers\": %zu, \"width\": %d, \"height\": %d, \"lod\": %.4f, "
      "\"peak_rss_mb\": %.1f}\n",
      load, distribute, interpolate, packSecs, packRepeat, meshSecs, renderSecs, frameSecs, p.coatMesh().mesh.triangleCount(), p.coatMesh().ranges.size(),
      l.width, l.height, p.lod(), peakRssMb());
  return 0;
}

int cmdExport(const Common& c, const ExportArgs& a) {
  checkOutExtension(a.out, {".obj", ".ply"}, "a mesh");
  Loaded l = load(c, a);
  TriMesh all = l.pipeline->skinTriMesh();
  all.append(l.pipeline->coatMesh().mesh);
  ensureParentDir(a.out);  // after evaluation: a failing scene leaves no trace
  feather::writeMesh(a.out, all);
  endProgress(c);
  info(c, "wrote " + a.out + " (" + std::to_string(all.triangleCount()) + " triangles)");
  return 0;
}

int cmdFeather(const Common& c, const FeatherArgs& a) {
  checkOutExtension(a.out, {".obj", ".ply", ".png"}, "a mesh or an image");
  if (!(a.lod > 0 && a.lod <= 1)) throw Error("expected a fraction in (0, 1]", "", "--lod");
  const feather::FeatherParams p = feather::loadFeather(a.file);
  int w = 0, h = 0;
  if (extensionOf(a.out) == ".png") {
    parseSize(a.size, "--size", w, h);
    requireMemory(double(w) * h * kBytesPerPixel, "a " + a.size + " image", "", "--size");
  }
  const TriMesh mesh = feather::buildFeatherMesh(p, a.age, a.lod);
  if (extensionOf(a.out) != ".png") {
    ensureParentDir(a.out);
    feather::writeMesh(a.out, mesh);
    info(c, "wrote " + a.out + " (" + std::to_string(mesh.triangleCount()) + " triangles)");
    return 0;
  }
  render::OsMesaContext ctx(w, h);
  const render::Image img = render::renderFeatherImage(ctx, p, mesh, w, h);
  ensureParentDir(a.out);
  render::saveImage(a.out, img);
  info(c, "wrote " + a.out + " (" + std::to_string(mesh.triangleCount()) + " triangles)");
  return 0;
}

namespace {

// frame_0000.png, frame_0001.png, ...: the name pattern `frames` owns in its directory.
std::string frameName(uint64_t k) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%04llu.png", static_cast<unsigned long long>(k));
  return name;
}
bool isFrameName(const std::string& n, uint64_t& index) {
  if (n.size() < 14 || n.compare(0, 6, "frame_") != 0 || n.compare(n.size() - 4, 4, ".png") != 0) return false;
  const std::string digits = n.substr(6, n.size() - 10);
  if (digits.size() < 4 || digits.find_first_not_of("0123456789") != std::string::npos) return false;
  const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), index);
  return r.ec == std::errc() && frameName(index) == n;
}

}  // namespace

int cmdFrames(const Common& c, const FramesArgs& a) {
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
  const auto count = static_cast<uint64_t>(countD);
  Loaded l = load(c, a);
  render::OsMesaContext ctx(l.width, l.height);
  render::SceneView view(ctx);
  l.pipeline->setProgress({});
  const ProgressFn bar = makeProgress(c);
  // The first frame is rendered before the directory exists: a scene that fails creates nothing.
  l.pipeline->setTime(a.from);
  render::Image frame = view.render(*l.pipeline, l.width, l.height, a.style);
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(a.out, ec);
  if (ec) throw Error("cannot create output directory: " + ec.message(), a.out, "--out");
  for (uint64_t k = 0; k < count; ++k) {
    const double t = a.from + double(k) / a.fps;
    if (k > 0) {
      l.pipeline->setTime(t);
      frame = view.render(*l.pipeline, l.width, l.height, a.style);
    }
    render::saveImage((fs::path(a.out) / frameName(k)).string(), frame);
    report(bar, "frames", double(k + 1) / double(count));
  }
  // Frames of an earlier, longer run would look like part of this sequence: remove them.
  size_t removed = 0;
  for (const auto& entry : fs::directory_iterator(a.out, ec)) {
    uint64_t index = 0;
    if (entry.is_regular_file() && isFrameName(entry.path().filename().string(), index) && index >= count) {
      std::error_code rm;
      if (fs::remove(entry.path(), rm)) ++removed;
    }
  }
  // Manifest: what this directory holds and how it was made.
  std::ostringstream m;
  m.precision(17);
  m << "{\n  \"scene\": \"" << jsonEscape(a.scene) << "\",\n  \"from\": " << a.from << ",\n  \"to\": " << a.to
    << ",\n  \"fps\": " << a.fps << ",\n  \"width\": " << l.width << ",\n  \"height\": " << l.height
    << ",\n  \"count\": " << count << ",\n  \"frames\": [";
  for (uint64_t k = 0; k < count; ++k) {
    m << (k ? ", " : "") << "{\"file\": \"" << frameName(k) << "\", \"time\": " << a.from + double(k) / a.fps << "}";
  }
  m << "]\n}\n";
  writeFileAtomic((fs::path(a.out) / "frames.json").string(), m.str());
  endProgress(c);
  info(c, "wrote " + std::to_string(count) + " frames to " + a.out +
              (removed ? " (removed " + std::to_string(removed) + " stale frames of an earlier run)" : ""));
  return 0;
}

}  // namespace pteryla::cli
