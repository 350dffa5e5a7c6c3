#include "cli_support.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "pteryla/core/error.hpp"

namespace pteryla::cli {
namespace {
std::string g_stage;
int g_lastPercent = -1;
bool g_open = false;
}  // namespace

ProgressFn makeProgress(const Common& c) {
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
      if (pct == 100) { std::fputc('\n', stderr); g_open = false; }
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

}  // namespace pteryla::cli
