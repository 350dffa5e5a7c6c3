#include "pteryla/core/error.hpp"

namespace pteryla {
namespace {
std::string compose(const std::string& what, const std::string& file, const std::string& element) {
  std::string out;
  if (!file.empty()) out += file + ": ";
  if (!element.empty()) out += element + ": ";
  return out + what;
}
}  // namespace

Error::Error(const std::string& what, const std::string& file, const std::string& element)
    : std::runtime_error(compose(what, file, element)), detail_(what), file_(file), element_(element) {}

Error Error::withFile(const std::string& file) const {
  if (!file_.empty()) return *this;
  return Error(detail_, file, element_);
}

void checkFailed(const char* expr, const char* file, int line, const std::string& msg) {
  throw InternalError(std::string("internal check failed: ") + expr + " at " + file + ":" + std::to_string(line) +
                      (msg.empty() ? "" : " (" + msg + ")"));
}

}  // namespace pteryla
