#include "pteryla/core/quiet.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <mutex>

namespace pteryla {
namespace {
std::atomic<bool> g_quiet{false};
std::mutex g_mutex;  // nested / concurrent scopes: only the outermost redirects
int g_depth = 0;
int g_saved = -1;
}  // namespace

void setQuiet(bool q) { g_quiet.store(q); }
bool quiet() { return g_quiet.load(); }

QuietThirdParty::QuietThirdParty() {
  if (!quiet()) return;
  std::lock_guard<std::mutex> lock(g_mutex);
  saved_ = 1;
  if (g_depth++ > 0) return;
  std::fflush(stderr);
  const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null < 0) return;
  g_saved = ::dup(2);
  if (g_saved >= 0) ::dup2(null, 2);
  ::close(null);
}

QuietThirdParty::~QuietThirdParty() {
  if (saved_ < 0) return;
  std::lock_guard<std::mutex> lock(g_mutex);
  if (--g_depth > 0) return;
  std::fflush(stderr);
  if (g_saved >= 0) {
    ::dup2(g_saved, 2);
    ::close(g_saved);
    g_saved = -1;
  }
}

}  // namespace pteryla
