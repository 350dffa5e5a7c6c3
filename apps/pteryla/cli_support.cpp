#include "cli_support.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <charconv>
#include <sstream>

#include "commands.hpp"
#include "pteryla/pteryla.hpp"

namespace pteryla::cli {
namespace {
std::string g_stage;
int g_lastPercent = -1;
bool g_open = false;
}  // namespace

Progress makeProgress(const Common& c) {
  if (c.quiet) return {};
  const bool tty = isatty(fileno(stderr)) || std::getenv("PTERYLA_PROGRESS");
  return [tty](const std::string& stage, double f) {
    const int pct = static_cast<int>(std::lround(std::clamp(f, 0.0, 1.0) * 100));
    if (stage != g_stage) {
      if (g_open) std::fputc('\n', stderr);
      g_stage = stage;
      g_lastPercent = -1;
      g_open = false;
    }
    if (pct == g_lastPercent) return true;
    g_lastPercent = pct;
    if (tty) {
      const int filled = pct / 5;
      std::fprintf(stderr, "\r%-12s [%.*s%*s] %3d%%", stage.c_str(), filled, "####################", 20 - filled, "",
                   pct);
      g_open = true;
      if (pct == 100) {
        std::fputc('\n', stderr);
        g_open = false;
      }
    } else if (pct == 0 || pct == 100 || pct % 25 == 0) {
      std::fprintf(stderr, "%s %d%%\n", stage.c_str(), pct);
    }
    std::fflush(stderr);
    return true;
  };
}

void endProgress(const Common& c) {
  if (g_open && !c.quiet) std::fputc('\n', stderr);
  g_open = false;
  g_stage.clear();
}

void parseSize(const std::string& s, const std::string& option, int& w, int& h) {
  int a = 0, b = 0;
  char x = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &a, &x, &b, &extra) != 3 || (x != 'x' && x != 'X') || a < 16 || b < 16 ||
      a > 16384 || b > 16384)
    throw Error("expected WxH with both sides in [16, 16384] (e.g. 1280x720), got '" + s + "'", "", option);
  w = a;
  h = b;
}

void ensureParentDir(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw Error("cannot create output directory '" + parent.string() + "': " + ec.message(), path);
}

void info(const Common& c, const std::string& msg) {
  if (!c.quiet) std::fprintf(stderr, "%s\n", msg.c_str());
}

uint64_t parseSeed(const std::string& text) {
  uint64_t v = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size())
    throw Error("expected an integer in [0, 18446744073709551615], got '" + text + "'", "", "--seed");
  return v;
}

Loaded load(const Common& c, const SceneArgs& a) {
  int width = 0, height = 0;
  if (!a.size.empty()) parseSize(a.size, "--size", width, height);
  if (a.lod && !(*a.lod > 0 && *a.lod <= 1))
    throw Error("expected a fraction in (0, 1], got " + std::to_string(*a.lod), "", "--lod");
  if (a.time && !std::isfinite(*a.time)) throw Error("expected a finite time", "", "--time");
  SceneFileOptions options;
  if (!a.seed.empty()) options.seed = parseSeed(a.seed);
  if (a.fixedLod) options.lodByScreenSize = false;
  if (a.instanceTolerance) {
    if (!(*a.instanceTolerance >= 0 && *a.instanceTolerance <= 0.1))
      throw Error("expected a fraction in [0, 0.1], got " + std::to_string(*a.instanceTolerance), "",
                  "--instance-tolerance");
    options.instanceTolerance = *a.instanceTolerance;
  }
  if (width) requireMemory(double(width) * height * kBytesPerPixel, "a " + a.size + " image", "", "--size");
  options.progress = makeProgress(c);
  Loaded l{Session::fromSceneFile(a.scene, options), width, height};
  if (!l.width) {
    const std::array<int, 2> size = l.session.sceneImageSize();
    l.width = size[0];
    l.height = size[1];
    requireMemory(double(l.width) * l.height * kBytesPerPixel,
                  "a " + std::to_string(l.width) + "x" + std::to_string(l.height) + " image", a.scene, "render.size");
  }
  if (a.time) l.session.setTime(*a.time);
  if (a.lod) l.session.setLod(*a.lod);
  return l;
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

std::string perCent(double f) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g%%", 100.0 * f);
  return b;
}

}  // namespace pteryla::cli
