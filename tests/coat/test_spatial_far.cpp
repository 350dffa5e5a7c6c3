// CellGrid::kNearest with points far apart (issue #21): an outlier or a second mesh component a million
// cells away used to make the shell search run for hours. The answer must stay exact and come quickly.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include <glm/common.hpp>

#include "../../src/coat/spatial_hash.hpp"
#include "pteryla/core/rng.hpp"

using pteryla::coat::detail::CellGrid;

namespace {

// Runs f on a thread; if it is not done after `seconds`, fails and ends the process (a hang must fail
// the test, not stall the suite).
template <class F>
void withinSeconds(double seconds, F&& f) {
  std::atomic<bool> done{false};
  std::thread t([&] {
    f();
    done = true;
  });
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!done && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (!done) {
    std::fprintf(stderr, "kNearest did not finish within %g s\n", seconds);
    std::fflush(stderr);
    std::_Exit(1);
  }
  t.join();
}

std::vector<std::pair<double, uint32_t>> bruteForce(const std::vector<glm::dvec3>& pts, const glm::dvec3& p,
                                                    uint32_t self, size_t k) {
  std::vector<std::pair<double, uint32_t>> all;
  for (uint32_t q = 0; q < pts.size(); ++q) {
    if (q == self) continue;
    const glm::dvec3 d = pts[q] - p;
    all.emplace_back(d.x * d.x + d.y * d.y + d.z * d.z, q);
  }
  std::sort(all.begin(), all.end());
  if (all.size() > k) all.resize(k);
  return all;
}

}  // namespace

TEST(CellGridFar, TwoComponentsAMillionCellsApart) {
  const std::vector<glm::dvec3> pts = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {1e6, 0, 0}, {1e6 + 1, 0, 0}, {1e6, 0, 1}};
  CellGrid grid(glm::dvec3(-2), 1.0);
  grid.build(pts.data(), pts.size());
  withinSeconds(20, [&] {
    for (uint32_t i = 0; i < pts.size(); ++i) {
      std::vector<std::pair<double, uint32_t>> out;
      double next2 = 0;
      grid.kNearest(pts.data(), pts[i], i, 10, out, &next2);
      EXPECT_EQ(out, bruteForce(pts, pts[i], i, 10)) << "point " << i;
      EXPECT_TRUE(std::isinf(next2));
    }
  });
}

TEST(CellGridFar, ClusterWithOutliersMatchesBruteForce) {
  std::vector<glm::dvec3> pts;
  pteryla::Rng rng(7);
  for (int i = 0; i < 2000; ++i) pts.emplace_back(rng.uniform(0, 40), rng.uniform(0, 40), rng.uniform(0, 1));
  pts.emplace_back(5e5, 3e5, 0);  // mistyped vertices
  pts.emplace_back(-2e5, 1e6, 7);
  glm::dvec3 lo(1e300);
  for (const auto& p : pts) lo = glm::min(lo, p);
  CellGrid grid(lo - glm::dvec3(2), 1.0);
  grid.build(pts.data(), pts.size());
  withinSeconds(20, [&] {
    for (uint32_t i : {0u, 17u, 1999u, 2000u, 2001u}) {
      for (size_t k : {1u, 10u, 40u}) {
        std::vector<std::pair<double, uint32_t>> out;
        double next2 = 0;
        grid.kNearest(pts.data(), pts[i], i, k, out, &next2);
        const auto want = bruteForce(pts, pts[i], i, k + 1);
        ASSERT_EQ(out.size(), k);
        for (size_t j = 0; j < k; ++j) EXPECT_EQ(out[j], want[j]) << "point " << i << " k " << k << " rank " << j;
        EXPECT_EQ(next2, want[k].first);
      }
    }
  });
}
