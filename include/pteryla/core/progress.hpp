#pragma once
// Progress reporting for long steps. The library reports; the CLI draws a bar on stderr, the viewer a
// progress widget. A callback returning false asks the step to stop early (cooperative cancel).
#include <functional>
#include <string>

namespace pteryla {

// stage: short name ("relax", "pack"); fraction in [0,1].
using ProgressFn = std::function<bool(const std::string& stage, double fraction)>;

// Calls fn if set; returns false when the callback asked to cancel.
inline bool report(const ProgressFn& fn, const std::string& stage, double fraction) {
  return fn ? fn(stage, fraction) : true;
}

}  // namespace pteryla
