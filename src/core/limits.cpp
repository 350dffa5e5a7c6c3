#include "pteryla/core/limits.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>

#include "pteryla/core/error.hpp"

namespace pteryla {
namespace {
std::atomic<double> g_limit{kDefaultMemoryLimitGb * 1e9};

std::string gb(double bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g GB", bytes / 1e9);
  return buf;
}
}  // namespace

double memoryLimitBytes() { return g_limit.load(); }

void setMemoryLimitBytes(double bytes) {
  PTERYLA_CHECK(bytes > 0, "memory limit must be positive");
  g_limit.store(bytes);
}

void requireMemory(double bytes, const std::string& what, const std::string& file, const std::string& element) {
  if (!(bytes <= memoryLimitBytes()))
    throw Error(what + " needs about " + (std::isfinite(bytes) ? gb(bytes) : std::string("unbounded memory")) +
                    ", above the memory ceiling of " + gb(memoryLimitBytes()) + " (raise it with --max-memory GB)",
                file, element);
}

}  // namespace pteryla
