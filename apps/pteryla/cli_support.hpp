#pragma once
// Shared CLI plumbing: progress bar on stderr, size parsing, output-file policy.
#include <optional>
#include <string>

#include <cstdint>
#include <memory>

#include "pteryla/pteryla.hpp"

namespace pteryla::cli {

struct Common {
  bool quiet = false;
  std::optional<double> maxMemoryGb;  // --max-memory
};

// A ProgressFn drawing "stage [#####     ] 42%" on stderr (only when not quiet and stderr is a TTY or
// PTERYLA_PROGRESS=1; otherwise one line per stage so logs stay readable).
Progress makeProgress(const Common& c);
// Finishes the current progress line.
void endProgress(const Common& c);
// "WxH" -> width, height; throws pteryla::Error naming the option.
void parseSize(const std::string& s, const std::string& option, int& w, int& h);
// Creates the parent directory of `path` if needed; throws Error when impossible.
void ensureParentDir(const std::string& path);
void info(const Common& c, const std::string& msg);  // stderr line unless quiet

struct SceneArgs;
// Bytes per rendered pixel: OSMesa colour + depth buffers, the read-back, the flipped Image and the
// encoder's copy.
inline constexpr double kBytesPerPixel = 24.0;
// A scene's session (the host API, include/pteryla/pteryla.hpp) with the command's --seed, --time,
// --lod applied and its progress reported on stderr, and the image size (--size or the scene's
// render.size), checked against the memory ceiling.
struct Loaded {
  Session session;
  int width = 0, height = 0;
};
Loaded load(const Common& c, const SceneArgs& a);
// --seed: an integer in [0, 2^64-1]; throws Error naming the option.
uint64_t parseSeed(const std::string& text);
// A JSON number (6 significant digits) or null when absent or not finite.
std::string jsonNumberOrNull(const std::optional<double>& v);
// "1.23%": a fraction as a percentage, 3 significant digits.
std::string perCent(double f);
// `in` escaped for a JSON string.
std::string jsonEscape(const std::string& in);

}  // namespace pteryla::cli
