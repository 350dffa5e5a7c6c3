#include <gtest/gtest.h>

#include "stage_graph.hpp"

using pteryla::pipeline::StageGraph;

// skin -> follicles -> pack -> mesh, and time -> pack.
TEST(StageGraph, EditDirtiesOnlyDownstream) {
  StageGraph g;
  int skin = 0, fol = 0, time = 0, pack = 0, mesh = 0;
  auto sSkin = g.add("skin", {}, [&] { ++skin; });
  auto sFol = g.add("follicles", {sSkin}, [&] { ++fol; });
  auto sTime = g.add("time", {}, [&] { ++time; });
  auto sPack = g.add("pack", {sFol, sTime}, [&] { ++pack; });
  auto sMesh = g.add("mesh", {sPack}, [&] { ++mesh; });
  g.pull(sMesh);
  EXPECT_EQ(skin + fol + time + pack + mesh, 5);
  g.pull(sMesh);  // nothing dirty: nothing recomputed
  EXPECT_EQ(skin + fol + time + pack + mesh, 5);
  g.invalidate(sTime);  // a timeline scrub
  EXPECT_FALSE(g.dirty(sFol));
  EXPECT_TRUE(g.dirty(sMesh));
  g.pull(sMesh);
  EXPECT_EQ(skin, 1);
  EXPECT_EQ(fol, 1);
  EXPECT_EQ(time, 2);
  EXPECT_EQ(pack, 2);
  EXPECT_EQ(mesh, 2);
  EXPECT_EQ(g.evaluations(sPack), 2u);
  g.invalidate(sSkin);
  g.pull(sFol);  // pulling an upstream stage leaves downstream dirty
  EXPECT_EQ(fol, 2);
  EXPECT_TRUE(g.dirty(sMesh));
  EXPECT_EQ(g.name(sPack), "pack");
}
