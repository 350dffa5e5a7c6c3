#pragma once
// pteryla has two error channels (see docs/architecture.md):
//  - bad input (scene, mesh, feather file, texture, parameter) -> pteryla::Error, carrying the file and
//    the element (JSON key path, face index, ...) so the user can find it. The CLI exits 2.
//  - broken invariants inside the library -> PTERYLA_CHECK, which throws InternalError. The CLI exits 1.
//    PTERYLA_CHECK_EQ/_NE/_LT/_LE/_GT/_GE print the two values they compared. PTERYLA_DCHECK(_EQ) is for
//    hot loops: compiled in without NDEBUG and with PTERYLA_DEBUG_CHECKS (the sanitized build, fuzzing).
// The library never calls exit().
// Part of the installed host API (include/pteryla/pteryla.hpp): standard headers only.
#include <stdexcept>
#include <string>
#include <type_traits>

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

// "(3 vs 4): msg", the message of a failed comparison check.
template <class A, class B>
std::string comparedValuesMessage(const A& a, const B& b, const std::string& msg) {
  auto text = [](const auto& v) -> std::string {
    using V = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<V, bool>)
      return v ? "true" : "false";
    else if constexpr (std::is_arithmetic_v<V>)
      return std::to_string(v);
    else if constexpr (std::is_null_pointer_v<V>)
      return "null";
    else if constexpr (std::is_pointer_v<V>)
      return v ? "non-null" : "null";
    else
      return "?";
  };
  return "(" + text(a) + " vs " + text(b) + "): " + msg;
}

}  // namespace pteryla

#define PTERYLA_CHECK(cond, msg)                                           \
  do {                                                                     \
    if (!(cond)) ::pteryla::checkFailed(#cond, __FILE__, __LINE__, (msg)); \
  } while (0)

#define PTERYLA_CHECK_OP(a, op, b, msg)                                                                    \
  do {                                                                                                     \
    const auto& pteryla_check_a_ = (a);                                                                    \
    const auto& pteryla_check_b_ = (b);                                                                    \
    if (!(pteryla_check_a_ op pteryla_check_b_))                                                           \
      ::pteryla::checkFailed(#a " " #op " " #b, __FILE__, __LINE__,                                        \
                             ::pteryla::comparedValuesMessage(pteryla_check_a_, pteryla_check_b_, (msg))); \
  } while (0)
#define PTERYLA_CHECK_EQ(a, b, msg) PTERYLA_CHECK_OP(a, ==, b, msg)
#define PTERYLA_CHECK_NE(a, b, msg) PTERYLA_CHECK_OP(a, !=, b, msg)
#define PTERYLA_CHECK_LT(a, b, msg) PTERYLA_CHECK_OP(a, <, b, msg)
#define PTERYLA_CHECK_LE(a, b, msg) PTERYLA_CHECK_OP(a, <=, b, msg)
#define PTERYLA_CHECK_GT(a, b, msg) PTERYLA_CHECK_OP(a, >, b, msg)
#define PTERYLA_CHECK_GE(a, b, msg) PTERYLA_CHECK_OP(a, >=, b, msg)

#if !defined(NDEBUG) || defined(PTERYLA_DEBUG_CHECKS)
#define PTERYLA_DCHECK(cond, msg) PTERYLA_CHECK(cond, msg)
#define PTERYLA_DCHECK_EQ(a, b, msg) PTERYLA_CHECK_EQ(a, b, msg)
#else
#define PTERYLA_DCHECK(cond, msg) \
  do {                            \
    (void)sizeof(cond);           \
  } while (0)
#define PTERYLA_DCHECK_EQ(a, b, msg) \
  do {                               \
    (void)sizeof((a) == (b));        \
  } while (0)
#endif
