// Helical growth generator (Zhang & Kanai): growth schedule, dt invariance, unfurling, spacing
// diagnostics, conversion to FeatherParams and the "helical" feather file form.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <glm/geometric.hpp>

#include <cmath>
#include <iostream>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/helical.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

const std::string kContour = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-contour.json";
const std::string kFlight = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-flight.json";

// The "helical" object of an example feather file.
HelicalParams exampleParams(const std::string& path) {
  static Json contour = readJsonFile(kContour), flight = readJsonFile(kFlight);
  const Json& j = path == kContour ? contour : flight;
  JsonReader r(j.at("helical"), path, "helical");
  return readHelical(r);
}

// Max distance of points to their least-squares plane.
double planeDeviation(const std::vector<glm::dvec3>& pts) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += Eigen::Vector3d(p.x, p.y, p.z);
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d n = es.eigenvectors().col(0);  // smallest eigenvalue
  double worst = 0;
  for (const auto& p : pts) worst = std::max(worst, std::abs(n.dot(Eigen::Vector3d(p.x, p.y, p.z) - mean)));
  return worst;
}

void expectSameSnapshot(const HelicalSnapshot& a, const HelicalSnapshot& b, double tol) {
  ASSERT_EQ(a.barb, b.barb);
  ASSERT_EQ(a.offset, b.offset);
  ASSERT_EQ(a.complete, b.complete);
  ASSERT_EQ(a.points.size(), b.points.size());
  double worst = 0;
  for (size_t i = 0; i < a.points.size(); ++i) worst = std::max(worst, glm::length(a.points[i] - b.points[i]));
  EXPECT_LE(worst, tol);
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
TEST(HelicalCurve1D, InterpolatesKeysMonotonicallyWithoutOvershoot) {
  const Curve1D c({{0, 1.0}, {0.3, 0.2}, {0.5, 0.1}, {0.8, 0.9}, {1, 1.0}});
  for (const auto& k : c.keys()) EXPECT_NEAR(c(k.x), k.y, 1e-15);
  EXPECT_DOUBLE_EQ(c(-1), 1.0);
  EXPECT_DOUBLE_EQ(c(2), 1.0);
  double prev = c(0);
  for (int i = 1; i <= 500; ++i) {  // decreasing on [0, 0.5], within the keys' range everywhere
    const double x = 0.5 * i / 500, y = c(x);
    EXPECT_LE(y, prev + 1e-12) << x;
    EXPECT_GE(y, 0.1 - 1e-12);
    prev = y;
  }
  for (int i = 0; i <= 1000; ++i) {
    const double y = c(i / 1000.0);
    EXPECT_GE(y, c.minValue() - 1e-12);
    EXPECT_LE(y, c.maxValue() + 1e-12);
  }
  const Curve1D back = curveFromJson(curveToJson(c), "mem", "curve");
  EXPECT_EQ(back, c);
  EXPECT_THROW(curveFromJson(Json::parse("[[0, 1], [0, 2]]"), "f.json", "helical.barbSpeed"), Error);
  EXPECT_THROW(curveFromJson(Json::parse("[]"), "f.json", "helical.barbSpeed"), Error);
  EXPECT_THROW(Curve1D({{0.5, 1.0}, {0.2, 1.0}}), Error);
}

TEST(HelicalCollar, CircleAndBezierAreArcLengthParameterized) {
  const Collar circle(CollarShape{CollarShape::Kind::Circle, 1.5, {}});
  EXPECT_NEAR(circle.length(), 2 * kPi * 1.5, 1e-12);
  EXPECT_NEAR(glm::length(circle.point(0.25) - glm::dvec2(0, 1.5)), 0, 1e-12);
  EXPECT_NEAR(glm::dot(circle.outwardNormal(0.1), circle.point(0.1)), 1.5, 1e-12);

  // A squarish closed Bezier (4 segments, counter-clockwise): equal s steps give equal arc steps.
  CollarShape sq;
  sq.kind = CollarShape::Kind::Bezier;
  sq.points = {{1, 0},  {1, 0.6},   {0.6, 1},   {0, 1},  {-0.6, 1}, {-1, 0.6},
               {-1, 0}, {-1, -0.6}, {-0.6, -1}, {0, -1}, {0.6, -1}, {1, -0.6}};
  const Collar bz(sq);
  EXPECT_NEAR(glm::length(bz.point(0.0) - glm::dvec2(1, 0)), 0, 1e-12);
  const int n = 400;
  double minStep = 1e9, maxStep = 0;
  for (int i = 0; i < n; ++i) {
    const double d = glm::length(bz.point((i + 1.0) / n) - bz.point(static_cast<double>(i) / n));
    minStep = std::min(minStep, d);
    maxStep = std::max(maxStep, d);
  }
  EXPECT_NEAR(maxStep, bz.length() / n, 1e-4 * bz.length() / n);
  EXPECT_NEAR(minStep, bz.length() / n, 1e-3 * bz.length() / n);  // chords on curved parts are shorter

  std::reverse(sq.points.begin() + 1, sq.points.end());  // clockwise
  try {
    Collar bad(sq, "cw.json");
    FAIL() << "a clockwise collar was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "cw.json");
    EXPECT_EQ(e.element(), "helical.collar.points");
  }
}

// ---------------------------------------------------------------------------------------------------
TEST(HelicalGrowth, ExactEventTimesForConstantSpeeds) {
  HelicalParams p;  // constant speeds 0.05, f = 2
  p.barbCount = 40;
  const HelicalGrowth g(p);
  const double D = p.anteriorLeft - p.posteriorLeft;
  EXPECT_NEAR(g.clampTime(0), D / 0.05, 1e-9);
  for (double t : {0.0, 1.3, 7.77}) EXPECT_NEAR(g.emitterLocus(0, t), p.anteriorLeft - 0.05 * t, 1e-12);
  EXPECT_NEAR(g.emitterLocus(1, 3.0), p.anteriorRight + 0.15, 1e-12);
  EXPECT_DOUBLE_EQ(g.emitterLocus(0, 1e6), p.posteriorLeft);  // clamped at I_P
  for (size_t i = g.vaneBegin(0); i < g.vaneBegin(1); ++i) {
    const HelicalBarb& b = g.barbs()[i];
    EXPECT_DOUBLE_EQ(b.spawnTime, b.index / p.frequency);  // eq. 3, not quantized to any dt
    // Back to I_A at constant V_b: travel time = distance / speed.
    EXPECT_NEAR(b.completionTime - b.spawnTime, (p.anteriorLeft - b.spawnLocus) / 0.05, 1e-9);
    EXPECT_NEAR(g.barbLocus(b, 0.5 * (b.completionTime - b.spawnTime)), 0.5 * (b.spawnLocus + p.anteriorLeft), 1e-9);
  }
  // Termination: N barbs complete at endTime, none of the discarded ones before it.
  EXPECT_GE(g.completedCount(), static_cast<size_t>(p.barbCount));
  EXPECT_LE(g.completedCount(), static_cast<size_t>(p.barbCount) + 1);  // a left/right tie
  const HelicalFeather f = helicalFeather(g);
  EXPECT_EQ(f.barbs.size(), g.completedCount());
  EXPECT_NEAR(f.length, p.growthSpeed * g.endTime(), 1e-12);
}

TEST(HelicalGrowth, SteppingIsIndependentOfDt) {
  const HelicalParams p = exampleParams(kContour);
  const HelicalGrowth g(p);
  const HelicalSnapshot ref = helicalSnapshot(g, g.endTime());
  ASSERT_GT(ref.points.size(), 1000u);
  for (double dt : {0.05, 0.0137, 0.5, 3.0}) {
    HelicalState s(g);
    int steps = 0;
    while (!s.finished() && steps < 1000000) {
      s.step(dt);
      ++steps;
    }
    ASSERT_TRUE(s.finished()) << dt;
    SCOPED_TRACE(dt);
    expectSameSnapshot(s.snapshot(), ref, 1e-12);
  }
  // Uneven steps, compared mid-growth too.
  HelicalState s(g);
  const double steps[] = {0.3, 0.01, 1.7, 0.049, 2.2};
  for (int i = 0; i < 10; ++i) s.step(steps[i % 5]);
  expectSameSnapshot(s.snapshot(), helicalSnapshot(g, s.time()), 1e-12);
  EXPECT_GT(s.spawnedCount(), 0u);
}

TEST(HelicalGrowth, RecordingStepOnlyChangesSamplingNotShape) {
  // Algorithm 1 records a trail point per time step; here the recording step (sampleDt) is separate
  // from event times, so a 8x coarser recording gives the same barbs, just fewer points on them.
  HelicalParams fine = exampleParams(kContour);
  fine.sampleDt = 0.05;
  HelicalParams coarse = fine;
  coarse.sampleDt = 0.4;
  const HelicalGrowth gf(fine), gc(coarse);
  EXPECT_EQ(gf.endTime(), gc.endTime());
  // On the collar (w = 0) trail points are exact: end points (spawn, fusion with the rachis) coincide.
  const HelicalFeather ff = helicalFeather(gf, 0, 0), fc = helicalFeather(gc, 0, 0);
  ASSERT_EQ(ff.barbs.size(), fc.barbs.size());
  for (size_t i = 0; i < ff.barbs.size(); ++i) {
    const auto &a = ff.barbs[i], &b = fc.barbs[i];
    EXPECT_EQ(a.attach, b.attach);
    EXPECT_LT(b.count, a.count);
    EXPECT_NEAR(glm::length(ff.points[a.first] - fc.points[b.first]), 0, 1e-9);
    EXPECT_NEAR(glm::length(ff.points[a.first + a.count - 1] - fc.points[b.first + b.count - 1]), 0, 1e-9);
  }
  // Unfurled, lengths along the trail are chords of the sampled helix: close, not identical.
  const HelicalFeather uf = helicalFeather(gf, 1, 1), uc = helicalFeather(gc, 1, 1);
  for (size_t i = 0; i < uf.barbs.size(); ++i) {
    const auto &a = uf.barbs[i], &b = uc.barbs[i];
    EXPECT_LT(glm::length(uf.points[a.first + a.count - 1] - uc.points[b.first + b.count - 1]), 1e-3 * uf.length);
  }
}

// ---------------------------------------------------------------------------------------------------
TEST(HelicalVanes, MovingThePosteriorPolarChangesTheVaneWidthRatioMonotonically) {
  // Fig. 7: polar 0.5 -> 0.4 -> 0.2 widens the left vane and narrows the right one.
  HelicalParams p = exampleParams(kFlight);
  p.barbCount = 200;
  double prev = 0;
  for (double polar : {0.5, 0.4, 0.2}) {
    p.setPosteriorPolar(polar, 0.01);
    const HelicalSpacingStats st = helicalSpacingStats(HelicalGrowth(p));
    const double ratio = st.vane[0].width / st.vane[1].width;
    std::cout << "posterior polar " << polar << ": left/right vane width " << st.vane[0].width << " / "
              << st.vane[1].width << " = " << ratio << "\n";
    if (polar == 0.5) {
      EXPECT_NEAR(ratio, 1.0, 1e-6);
    }
    EXPECT_GT(ratio, prev * 1.2) << polar;
    prev = ratio;
  }
  EXPECT_GT(prev, 3.0);
}

TEST(HelicalVanes, BarbsAreDenserNearTheVaneEdgeThanNearTheRachis) {
  // Section 5: with V_b slanting toward the posterior polar, the inter-barb spacing near the vane edge
  // is smaller than near the rachis (Feo et al.'s measurements).
  for (const std::string& file : {kContour, kFlight}) {
    const HelicalSpacingStats st = helicalSpacingStats(HelicalGrowth(exampleParams(file)));
    for (int v = 0; v < 2; ++v) {
      SCOPED_TRACE(file + (v ? " right" : " left"));
      EXPECT_GT(st.vane[v].nearEdge, 0);
      EXPECT_LT(st.vane[v].nearEdge, 0.8 * st.vane[v].nearRachis);
    }
  }
  // Control: with constant speeds the spacing is the same everywhere (barbs are straight, parallel).
  HelicalParams flat = exampleParams(kContour);
  flat.emitterSpeed = Curve1D::constant(0.05);
  flat.barbSpeed = Curve1D::constant(0.05);
  const HelicalSpacingStats st = helicalSpacingStats(HelicalGrowth(flat));
  EXPECT_NEAR(st.vane[0].nearEdge / st.vane[0].nearRachis, 1.0, 0.02);
}

TEST(HelicalUnfurl, ZeroLeavesBarbsOnTheCollarAndOneFlattensThem) {
  const HelicalParams p = exampleParams(kContour);
  const HelicalGrowth g(p);
  const double R = p.collar.radius;
  // Feather frame of a circle collar: the follicle axis is the line y = 0, z = -R.
  const HelicalFeather f0 = helicalFeather(g, 0, 0);
  double worstR = 0;
  for (const auto& q : f0.points) worstR = std::max(worstR, std::abs(std::hypot(q.y, q.z + R) - R));
  EXPECT_LT(worstR, 1e-9 * R);
  EXPECT_GT(planeDeviation(f0.points), 0.1 * f0.length);  // curled: far from any plane

  const HelicalFeather f1 = helicalFeather(g, 1, 1);
  const double dev = planeDeviation(f1.points);
  std::cout << "w = 1: max distance to best-fit plane " << dev << " (" << 100 * dev / f1.length
            << "% of the feather length)\n";
  EXPECT_LT(dev, 0.01 * f1.length);
  // Unfurling keeps heights and segment lengths.
  ASSERT_EQ(f0.points.size(), f1.points.size());
  for (const auto& b : f0.barbs) {
    for (uint32_t k = 0; k + 1 < b.count; ++k) {
      const size_t i = b.first + k;
      EXPECT_DOUBLE_EQ(f0.points[i].x, f1.points[i].x);
      EXPECT_NEAR(glm::length(f0.points[i + 1] - f0.points[i]), glm::length(f1.points[i + 1] - f1.points[i]), 1e-9);
    }
  }
  // Partial unfurling lies in between, and per vane: only the left vane flattened.
  const HelicalFeather half = helicalFeather(g, 0.5, 0.5);
  const double dHalf = planeDeviation(half.points);
  EXPECT_GT(dHalf, dev);
  EXPECT_LT(dHalf, planeDeviation(f0.points));
  const HelicalFeather leftOnly = helicalFeather(g, 1, 0);
  double leftZ = 0, rightZ = 0;
  for (const auto& b : leftOnly.barbs)
    for (uint32_t k = 0; k < b.count; ++k)
      (b.vane == 0 ? leftZ : rightZ) = std::max(b.vane == 0 ? leftZ : rightZ, std::abs(leftOnly.points[b.first + k].z));
  EXPECT_LT(leftZ, 1e-9 * f1.length);
  EXPECT_GT(rightZ, 0.5 * R);
}

TEST(HelicalSpacing, ArcLengthSpawningRemovesTheTipAnomaly) {
  // Section 5: spawning tied to time gives abnormal barb spacing at the tip; spawning by equal emitter
  // trail length keeps it regular.
  HelicalParams p = exampleParams(kContour);
  p.spawnMode = SpawnMode::Time;
  const HelicalSpacingStats timeStats = helicalSpacingStats(HelicalGrowth(p));
  p.spawnMode = SpawnMode::ArcLength;
  const HelicalSpacingStats arcStats = helicalSpacingStats(HelicalGrowth(p));
  for (int v = 0; v < 2; ++v) {
    const VaneSpacingStats &t = timeStats.vane[v], &a = arcStats.vane[v];
    std::cout << (v ? "right" : "left") << " vane tip spacing / median spacing: time mode " << t.tipRatio << " (max "
              << t.tipMaxRatio << ", " << t.tipBarbs << " tip barbs), arc-length mode " << a.tipRatio << " (max "
              << a.tipMaxRatio << ", " << a.tipBarbs << " tip barbs)\n";
    RecordProperty(v ? "tip_ratio_time_right" : "tip_ratio_time_left", std::to_string(t.tipRatio));
    RecordProperty(v ? "tip_ratio_arc_right" : "tip_ratio_arc_left", std::to_string(a.tipRatio));
    EXPECT_FALSE(t.tipRatio >= 0.5 && t.tipRatio <= 2.0) << t.tipRatio;
    EXPECT_GE(a.tipRatio, 0.5);
    EXPECT_LE(a.tipRatio, 2.0);
    EXPECT_LT(a.tipMaxRatio, 1.2);
    EXPECT_GE(a.tipBarbs, 2);
    // Body spacing is v_grow / f in both modes.
    EXPECT_NEAR(t.medianSpacing, p.growthSpeed / p.frequency, 1e-3);
    EXPECT_NEAR(a.medianSpacing, p.growthSpeed / p.frequency, 1e-3);
  }
}

// ---------------------------------------------------------------------------------------------------
TEST(HelicalConvert, FitBezierReproducesACubic) {
  const std::vector<glm::dvec3> cvs = {{0, 0, 0}, {1, 2, 0.5}, {2, -1, 0.2}, {3, 1, -0.4}};
  std::vector<glm::dvec3> pts;
  for (int i = 0; i <= 200; ++i) pts.push_back(bezierPoint(cvs, std::pow(i / 200.0, 1.3)));  // uneven
  double err = 1;
  const std::vector<glm::dvec3> fit = fitBezier(pts.data(), pts.size(), 4, &err);
  EXPECT_LT(err, 1e-4);
  for (int i = 0; i <= 20; ++i) {
    const glm::dvec3 q = bezierPoint(fit, i / 20.0);
    double best = 1e9;
    for (const auto& p : pts) best = std::min(best, glm::length(p - q));
    EXPECT_LT(best, 0.02);
  }
  // Too few points: still a valid curve through the end points.
  const std::vector<glm::dvec3> two = {{0, 0, 0}, {1, 1, 0}};
  const auto line = fitBezier(two.data(), 2, 4);
  ASSERT_EQ(line.size(), 4u);
  EXPECT_EQ(line.front(), two.front());
  EXPECT_EQ(line.back(), two.back());
}

TEST(HelicalConvert, FeatherParamsReproduceTheGrownVanes) {
  const HelicalParams p = exampleParams(kFlight);
  const HelicalGrowth g(p);
  const HelicalFeather f = helicalFeather(g);
  const HelicalConversion c = convertHelical(g, f, 14.0);
  EXPECT_LT(c.maxFitError, 0.005);
  EXPECT_NEAR(c.feather.rachisLength, 14.0, 1e-12);
  EXPECT_EQ(c.barbs[0] + c.barbs[1], static_cast<int>(f.barbs.size()));
  for (int v = 0; v < 2; ++v) {
    EXPECT_GE(c.keyBarbs[v], 3);
    EXPECT_LE(c.keyBarbs[v], p.maxKeyBarbs);
  }
  validateFeather(c.feather);
  const FeatherCurves curves = generateBarbs(c.feather);
  ASSERT_FALSE(curves.barbs.empty());
  // Vane widths of the Streit barbs match the grown feather (scaled).
  const HelicalSpacingStats st = helicalSpacingStats(g);
  double width[2] = {0, 0};
  std::vector<glm::vec3> poly;
  for (const BarbCurve& b : curves.barbs) {
    barbPolyline(curves, b, 16, poly);
    for (const auto& q : poly) width[b.vane] = std::max(width[b.vane], std::abs(static_cast<double>(q.y)));
  }
  for (int v = 0; v < 2; ++v) EXPECT_NEAR(width[v], st.vane[v].width * c.scale, 0.03 * st.vane[v].width * c.scale) << v;
}

TEST(HelicalFile, ExamplesLoadAsOrdinaryFeathers) {
  for (const std::string& file : {kContour, kFlight}) {
    SCOPED_TRACE(file);
    const FeatherParams p = loadFeather(file);
    EXPECT_EQ(p.generator, "helical");
    EXPECT_FALSE(p.left.keyBarbs.empty());
    EXPECT_FALSE(p.silhouette.left.empty());
    const FeatherCurves c = generateBarbs(p);
    ASSERT_GT(c.barbs.size(), 50u);
    size_t perVane[2] = {0, 0};
    for (const BarbCurve& b : c.barbs) {
      ++perVane[b.vane];
      EXPECT_TRUE(std::isfinite(b.length));
    }
    EXPECT_GT(perVane[0], 20u);
    EXPECT_GT(perVane[1], 20u);
    for (const auto& q : c.cvs) ASSERT_TRUE(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z));
    // Save -> load gives the same feather (the helical object is kept, derived fields regenerate).
    const std::string out = std::string(PTERYLA_BUILD_DIR) + "/test_helical_roundtrip.json";
    saveFeather(out, p);
    FeatherParams q = loadFeather(out);
    q.sourceFile = p.sourceFile;
    EXPECT_TRUE(p == q);
    // The Streit conversion path gives the same barbs as the file.
    FeatherParams direct = helicalToFeatherParams(exampleParams(file));
    EXPECT_EQ(direct.left.keyBarbs.size(), p.left.keyBarbs.size());
  }
  // The flight feather is asymmetric: the left (trailing) vane is much wider.
  const FeatherParams flight = loadFeather(kFlight);
  double maxL = 0, maxR = 0;
  for (const auto& q : flight.silhouette.left.points) maxL = std::max(maxL, q.y);
  for (const auto& q : flight.silhouette.right.points) maxR = std::max(maxR, q.y);
  EXPECT_GT(maxL, 2.5 * maxR);
}

TEST(HelicalFile, BadInputNamesFileAndElement) {
  auto expectError = [](const std::string& helical, const std::string& element) {
    Json j = readJsonFile(kContour);
    j["helical"] = Json::parse(helical);
    JsonReader r(j, "bad.json");
    try {
      readFeather(r);
      ADD_FAILURE() << "accepted " << helical;
    } catch (const Error& e) {
      EXPECT_EQ(e.file(), "bad.json") << helical;
      EXPECT_EQ(e.element(), element) << helical << ": " << e.what();
    }
  };
  expectError(R"({"posterior": {"left": 0.995, "right": 0.49}})", "helical.posterior");
  expectError(R"({"barbSpeed": [[0, 0.05], [1, -0.01]]})", "helical.barbSpeed");
  expectError(R"({"barbSpeed": [[0, 0.05], [0, 0.06]]})", "helical.barbSpeed[1]");
  expectError(R"({"frequncy": 2})", "helical.frequncy");
  expectError(R"({"spawnMode": "space"})", "helical.spawnMode");
  expectError(R"({"collar": {"type": "bezier", "points": [[0, 0], [1, 0]]}})", "helical.collar.points");
  expectError(R"({"unfurl": {"left": 1.5}})", "helical.unfurl.left");
  expectError(R"({"barbCount": 0})", "helical.barbCount");
  // Absurd sampling is refused instead of exhausting memory.
  expectError(R"({"sampleDt": 1e-7, "barbCount": 5000})", "helical.sampleDt");
}

TEST(HelicalGrowth, BezierCollarGrowsAFeather) {
  HelicalParams p = exampleParams(kContour);
  p.collar.kind = CollarShape::Kind::Bezier;
  // An ellipse-like collar, wider across than deep.
  p.collar.points = {{2, 0},  {2, 0.8},   {1.1, 1.2},   {0, 1.2},  {-1.1, 1.2}, {-2, 0.8},
                     {-2, 0}, {-2, -0.8}, {-1.1, -1.2}, {0, -1.2}, {1.1, -1.2}, {2, -0.8}};
  const HelicalGrowth g(p);
  const HelicalFeather f = helicalFeather(g, 1, 1);
  EXPECT_LT(planeDeviation(f.points), 0.01 * f.length);
  const HelicalSpacingStats st = helicalSpacingStats(g);
  EXPECT_NEAR(st.vane[0].width, st.vane[1].width, 1e-6 * st.vane[0].width);
  EXPECT_NEAR(st.vane[0].width, 0.48 * g.collar().length() + 0.5 * f.rachisWidth, 0.01 * st.vane[0].width);
}
