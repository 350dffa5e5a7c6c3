#pragma once
// pteryla has two error channels (see docs/architecture.md):
//  - bad input (scene, mesh, feather file, texture, parameter) -> pteryla::Error, carrying the file and
//    the element (JSON key path, face index, ...) so the user can find it. The CLI exits 2.
//  - broken invariants inside the library -> PTERYLA_CHECK, which throws InternalError. The CLI exits 1.
// The library never calls exit().
// Part of the installed host API (include/pteryla/pteryla.hpp): standard headers only.
#include <stdexcept>
#include <string>

#include "pteryla/export.hpp"

namespace pteryla {

class PTERYLA_API Error : public std::runtime_error {
 public:
  // what: what was wrong and what was expected; file: input file (may be empty);
  // element: where inside the file (JSON key path like "tracts[2].density", "face 17").
  explicit Error(const std::string& what, const std::string& file = {}, const std::string& element = {});

  const std::string& file() const { return file_; }
  const std::string& element() const { return element_; }
  const std::string& detail() const { return detail_; }

  // Returns a copy with file context filled in if it was empty.
  Error withFile(const std::string& file) const;

 private:
  std::string detail_, file_, element_;
};

class PTERYLA_API InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

[[noreturn]] PTERYLA_API void checkFailed(const char* expr, const char* file, int line, const std::string& msg);

}  // namespace pteryla

#define PTERYLA_CHECK(cond, msg)                                               \
  do {                                                                         \
    if (!(cond)) ::pteryla::checkFailed(#cond, __FILE__, __LINE__, (msg));     \
  } while (0)
