#pragma once
// Shared CLI plumbing: progress bar on stderr, size parsing, output-file policy.
#include <optional>
#include <string>

#include "pteryla/core/progress.hpp"

namespace pteryla::cli {

struct Common {
  bool quiet = false;
  std::optional<double> maxMemoryGb;  // --max-memory
};

// A ProgressFn drawing "stage [#####     ] 42%" on stderr (only when not quiet and stderr is a TTY or
// PTERYLA_PROGRESS=1; otherwise one line per stage so logs stay readable).
ProgressFn makeProgress(const Common& c);
// Finishes the current progress line.
void endProgress(const Common& c);
// "WxH" -> width, height; throws pteryla::Error naming the option.
void parseSize(const std::string& s, const std::string& option, int& w, int& h);
// Creates the parent directory of `path` if needed; throws Error when impossible.
void ensureParentDir(const std::string& path);
void info(const Common& c, const std::string& msg);  // stderr line unless quiet

}  // namespace pteryla::cli
