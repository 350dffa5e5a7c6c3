// The invariant checks of core/error.hpp: a failed comparison names both values, a passing one evaluates
// each operand once, and PTERYLA_DCHECK follows NDEBUG / PTERYLA_DEBUG_CHECKS.
#include <gtest/gtest.h>

#include <string>

#include "pteryla/core/error.hpp"

using namespace pteryla;

namespace {

std::string failureOf(void (*f)()) {
  try {
    f();
  } catch (const InternalError& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST(Checks, FailedComparisonPrintsBothValuesAndTheExpression) {
  const std::string m = failureOf([] {
    const size_t got = 3, expected = 4;
    PTERYLA_CHECK_EQ(got, expected, "point count mismatch");
  });
  EXPECT_NE(m.find("got == expected"), std::string::npos) << m;
  EXPECT_NE(m.find("(3 vs 4)"), std::string::npos) << m;
  EXPECT_NE(m.find("point count mismatch"), std::string::npos) << m;
  const std::string le = failureOf([] { PTERYLA_CHECK_LE(7, 5, "too many"); });
  EXPECT_NE(le.find("(7 vs 5)"), std::string::npos) << le;
  const std::string ptr = failureOf([] {
    const int* p = nullptr;
    PTERYLA_CHECK_NE(p, nullptr, "needs a value");
  });
  EXPECT_NE(ptr.find("(null vs null)"), std::string::npos) << ptr;
}

TEST(Checks, PassingComparisonEvaluatesEachOperandOnce) {
  int calls = 0;
  auto next = [&] { return ++calls; };
  PTERYLA_CHECK_EQ(next(), 1, "first call");
  PTERYLA_CHECK_GE(next(), 2, "second call");
  EXPECT_EQ(calls, 2);
}

TEST(Checks, DebugChecksFollowTheBuild) {
  const std::string m = failureOf([] { PTERYLA_DCHECK_EQ(1, 2, "debug only"); });
#if !defined(NDEBUG) || defined(PTERYLA_DEBUG_CHECKS)
  EXPECT_NE(m.find("(1 vs 2)"), std::string::npos) << m;
#else
  EXPECT_TRUE(m.empty()) << m;
#endif
}
