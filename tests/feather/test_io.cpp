#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "feather_fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/interpolate.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla;
using namespace pteryla::feather;
namespace fs = std::filesystem;

namespace {

std::string tmpPath(const std::string& name) {
  const fs::path dir = fs::path(PTERYLA_BUILD_DIR) / "test_feather_tmp";
  fs::create_directories(dir);
  return (dir / name).string();
}

const char* kMinimal = R"({
  "pteryla_feather": 1,
  "calamus": {"length": 0.1, "width_ratio": 0.8},
  "rachis": {"length": 1.0, "width": 0.02, "lateral_curvature": 0, "ventral_dorsal_curvature_deg": 10},
  "barbs": {"length": 0.3, "spacing_base": 0.02, "spacing_tip": 0.01},
  "left_vane": {"base_angle_deg": 60, "tip_angle_deg": 30,
                "key_barbs": [{"rp": 0.5, "cvs": [[0,0,0],[0.5,0.1,0],[1,0,0]]}]},
  "right_vane": {"base_angle": 1.0, "tip_angle": 0.5, "key_barbs": []}
})";

// Loads kMinimal with `edit` applied; returns the error (element and message) or "" when it loads.
std::string loadEdited(const std::function<void(Json&)>& edit, std::string* element = nullptr) {
  Json j = Json::parse(kMinimal);
  edit(j);
  const std::string path = tmpPath("edited.json");
  writeJsonFile(path, j);
  try {
    loadFeather(path);
  } catch (const Error& e) {
    if (element) *element = e.element();
    EXPECT_EQ(e.file(), path);
    return e.what();
  }
  return "";
}

}  // namespace

TEST(FeatherFile, MinimalLoadsWithUnits) {
  const std::string path = tmpPath("minimal.json");
  std::ofstream(path) << kMinimal;
  const FeatherParams p = loadFeather(path);
  EXPECT_NEAR(p.left.baseAngle, kPi / 3, 1e-15);
  EXPECT_NEAR(p.rachisVentralDorsalCurvature, 10 * kPi / 180, 1e-15);
  EXPECT_EQ(p.left.keyBarbs.size(), 1u);
  EXPECT_TRUE(p.right.keyBarbs.empty());
  EXPECT_EQ(p.sourceFile, path);
  EXPECT_EQ(p.generator, "streit");
}

TEST(FeatherFile, MalformedFilesNameTheField) {
  struct Case {
    const char* what;
    std::function<void(Json&)> edit;
    const char* element;
  };
  const std::vector<Case> cases = {
      {"unknown key", [](Json& j) { j["rachis"]["lenght"] = 1; }, "rachis.lenght"},
      {"missing field", [](Json& j) { j["rachis"].erase("length"); }, "rachis.length"},
      {"missing vane", [](Json& j) { j.erase("right_vane"); }, "right_vane"},
      {"missing key_barbs", [](Json& j) { j["right_vane"].erase("key_barbs"); }, "right_vane.key_barbs"},
      {"rp above 1", [](Json& j) { j["left_vane"]["key_barbs"][0]["rp"] = 1.5; }, "left_vane.key_barbs[0].rp"},
      {"rp below 0", [](Json& j) { j["left_vane"]["key_barbs"][0]["rp"] = -0.1; }, "left_vane.key_barbs[0].rp"},
      {"NaN as text", [](Json& j) { j["barbs"]["length"] = "NaN"; }, "barbs.length"},
      {"infinite", [](Json& j) { j["barbs"]["spacing_tip"] = std::numeric_limits<double>::infinity(); },
       "barbs.spacing_tip"},
      {"one control vertex", [](Json& j) { j["left_vane"]["key_barbs"][0]["cvs"] = Json::parse("[[0,0,0]]"); },
       "left_vane.key_barbs[0].cvs"},
      {"bad control vertex", [](Json& j) { j["left_vane"]["key_barbs"][0]["cvs"][1] = Json::parse("[0,1]"); },
       "left_vane.key_barbs[0].cvs[1]"},
      {"zero spacing", [](Json& j) { j["barbs"]["spacing_base"] = 0; }, "barbs.spacing_base"},
      {"negative length", [](Json& j) { j["calamus"]["length"] = -1; }, "calamus.length"},
      {"angle twice", [](Json& j) { j["right_vane"]["base_angle_deg"] = 50; }, "right_vane.base_angle_deg"},
      {"angle range", [](Json& j) { j["left_vane"]["tip_angle_deg"] = 200; }, "left_vane.tip_angle_deg"},
      {"wrong version", [](Json& j) { j["pteryla_feather"] = 2; }, "pteryla_feather"},
      {"no version", [](Json& j) { j.erase("pteryla_feather"); }, "pteryla_feather"},
      {"unknown generator", [](Json& j) { j["generator"] = "nope"; }, "generator"},
      {"silhouette rp order", [](Json& j) { j["silhouette"] = Json::parse(R"({"left": [[0.5, 1], [0.2, 1]]})"); },
       "silhouette.left[1][0]"},
      {"material colour", [](Json& j) { j["material"] = Json::parse(R"({"base_color": [1, 2, 0]})"); },
       "material.base_color"},
      {"material unknown key", [](Json& j) { j["material"] = Json::parse(R"({"colour": "red"})"); }, "material.colour"},
      {"brdf spacing 0", [](Json& j) { j["material"] = Json::parse(R"({"brdf": {"d": 0}})"); }, "material.brdf.d"},
      {"brdf spacing huge", [](Json& j) { j["material"] = Json::parse(R"({"brdf": {"d": 21}})"); }, "material.brdf.d"},
      {"brdf floor 1", [](Json& j) { j["material"] = Json::parse(R"({"brdf": {"d": 1, "h": 1}})"); },
       "material.brdf.h"},
      {"brdf floor text", [](Json& j) { j["material"] = Json::parse(R"({"brdf": {"h": "low"}})"); }, "material.brdf.h"},
      {"brdf unknown key", [](Json& j) { j["material"] = Json::parse(R"({"brdf": {"sigma": 0.2}})"); },
       "material.brdf.sigma"},
      {"brdf not an object", [](Json& j) { j["material"] = Json::parse(R"({"brdf": 1.5})"); }, "material.brdf"},
      {"splits range", [](Json& j) { j["splits"] = Json::parse(R"({"count": 2, "rp_min": 0.9, "rp_max": 0.1})"); },
       "splits.rp_min"},
      {"afterfeather field",
       [](Json& j) {
         j["afterfeather"] = j;
         j["afterfeather"].erase("pteryla_feather");
         j["afterfeather"]["rachis"]["width"] = -1;
       },
       "afterfeather.rachis.width"},
  };
  for (const Case& c : cases) {
    std::string element;
    const std::string msg = loadEdited(c.edit, &element);
    EXPECT_FALSE(msg.empty()) << c.what << " was accepted";
    EXPECT_EQ(element, c.element) << c.what << ": " << msg;
    EXPECT_NE(msg.find(c.element), std::string::npos) << c.what << ": " << msg;
  }
  EXPECT_EQ(loadEdited([](Json&) {}), "");
}

TEST(FeatherFile, SyntaxErrorAndMissingFile) {
  const std::string path = tmpPath("broken.json");
  std::ofstream(path) << "{ \"pteryla_feather\": 1, ";
  EXPECT_THROW(loadFeather(path), Error);
  EXPECT_THROW(loadFeather(tmpPath("does_not_exist.json")), Error);
}

TEST(FeatherFile, RoundTripIsExact) {
  FeatherParams p = feather::testing::contourParams();
  p.rachisLateralCurvature = 0.1234567890123;
  p.silhouette.right.points = {{0, 0.1}, {0.3, 0.7}, {0.3, 0.2}, {1, 0}};
  p.splits.count = 2;
  p.splits.openingAngle = 0.0987654321;
  p.material.texture = "textures/contour.png";
  p.material.baseColor = glm::dvec3(0.1, 0.2, 0.30000000000000004);
  p.material.pattern = "bars";
  p.material.brdfD = 1.7000000000000002;
  p.material.brdfH = 0.123456789;
  p.seed = 0xFFFFFFFFFFFFFFFFull;
  FeatherParams after = feather::testing::contourParams();
  after.rachisLength = 0.3;
  p.afterfeather = std::make_shared<const FeatherParams>(after);
  const std::string path = tmpPath("roundtrip.json");
  saveFeather(path, p);
  FeatherParams q = loadFeather(path);
  EXPECT_EQ(q, p);
  // Interpolated feathers (arbitrary doubles everywhere) round-trip too.
  const FeatherParams m = interpolateFeathers(p, feather::testing::contourParams(), 0.37);
  saveFeather(path, m);
  EXPECT_EQ(loadFeather(path), m);
}

TEST(FeatherFile, MaterialBrdfIsOptionalPerParameterAndComparedByValue) {
  FeatherParams p = feather::testing::contourParams();
  const std::string path = tmpPath("brdf.json");
  p.material.brdfD = 2.5;  // h left to the scene
  saveFeather(path, p);
  std::ifstream in(path);
  const Json j = Json::parse(in);
  EXPECT_EQ(j["material"]["brdf"], Json::parse(R"({"d": 2.5})"));
  FeatherParams q = loadFeather(path);
  EXPECT_EQ(q.material.brdfD, 2.5);
  EXPECT_FALSE(q.material.brdfH.has_value());
  EXPECT_EQ(q, p);
  q.material.brdfH = 0.0;  // set to the default value is still set: not equal
  EXPECT_NE(q, p);
  EXPECT_FALSE(q.material.empty());
  p.material.brdfD.reset();
  EXPECT_TRUE(p.material.empty());
  saveFeather(path, p);
  std::ifstream again(path);
  EXPECT_FALSE(Json::parse(again).contains("material"));
}

TEST(FeatherFile, EmbeddedDefinitionCarriesItsPath) {
  Json scene = Json::parse(R"({"feathers": [ )" + std::string(kMinimal) + "]}");
  scene["feathers"][0].erase("pteryla_feather");  // optional when embedded
  JsonReader top(scene, "scene.json");
  auto list = top.objects("feathers");
  const FeatherParams p = readFeather(list[0]);
  EXPECT_EQ(p.rachisLength, 1.0);
  scene["feathers"][0]["barbs"]["length"] = -2;
  JsonReader top2(scene, "scene.json");
  auto list2 = top2.objects("feathers");
  try {
    readFeather(list2[0]);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "feathers[0].barbs.length");
    EXPECT_EQ(e.file(), "scene.json");
  }
}

TEST(FeatherFile, OutlineSilhouetteIsConverted) {
  Json j = Json::parse(kMinimal);
  j["silhouette"] =
      Json::parse(R"({"outline": [[0.1, 0], [0.1, 0.5], [1.1, 0.5], [1.1, -0.5], [0.1, -0.5]], "samples": 5})");
  const std::string path = tmpPath("outline.json");
  writeJsonFile(path, j);
  const FeatherParams p = loadFeather(path);
  ASSERT_EQ(p.silhouette.left.points.size(), 5u);
  EXPECT_GT(p.silhouette.left.points[1].y, 0.3);
}

TEST(FeatherFile, EveryLibraryFeatherLoadsAndGenerates) {
  const fs::path dir = fs::path(PTERYLA_DATA_DIR) / "feathers";
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  for (const char* required :
       {"down", "semiplume", "contour", "covert", "primary", "secondary", "rectrix", "filoplume", "bristle", "eyespot"})
    EXPECT_NE(std::find(names.begin(), names.end(), required), names.end())
        << "missing data/feathers/" << required << ".json";
  for (const auto& n : names) {
    SCOPED_TRACE(n);
    const std::string path = (dir / (n + ".json")).string();
    FeatherParams p;
    ASSERT_NO_THROW(p = loadFeather(path));
    const FeatherCurves c = generateBarbs(p);
    EXPECT_GT(c.barbs.size(), 10u);
    // Round trip through a temporary file is exact.
    const std::string out = tmpPath(n + ".json");
    saveFeather(out, p);
    EXPECT_EQ(loadFeather(out), p);
  }
}

TEST(FeatherFile, PrimaryHasNarrowerLeadingVane) {
  const FeatherParams p = loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/primary.json");
  const FeatherCurves c = generateBarbs(p);
  double extent[2] = {0, 0};  // widest reach across the shaft per vane
  for (const BarbCurve& b : c.barbs) {
    if (b.part != 0) continue;
    for (uint16_t k = 0; k < b.cvCount; ++k)
      extent[b.vane] = std::max(extent[b.vane], double(std::abs(c.cvs[b.cvOffset + k].y)));
  }
  // The right vane leads (outer edge of the wing): clearly narrower than the trailing left vane.
  EXPECT_LT(extent[1], 0.6 * extent[0]);
  EXPECT_GT(extent[1], 0.05 * extent[0]);
}

TEST(FeatherFile, GeneratorHookDispatches) {
  FeatherGenerator g;
  g.read = [](JsonReader& r, FeatherParams& p) { p.generatorParams = {{"turns", r.number("test_turns", 0, 100)}}; };
  g.write = [](const FeatherParams& p, Json& j) { j["test_turns"] = p.generatorParams["turns"]; };
  g.generate = [](const FeatherParams& p, FeatherCurves& out, const GenerateOptions&) {
    out.shafts.resize(1);
    out.barbBegin = {0};
    out.barbEnd = {0};
    out.shafts[0].points = {glm::vec3(0), glm::vec3(float(p.generatorParams["turns"].get<double>()), 0, 0)};
  };
  registerFeatherGenerator("test_gen", g);
  EXPECT_THROW(registerFeatherGenerator("streit", g), Error);
  Json j = Json::parse(kMinimal);
  j["generator"] = "test_gen";
  j["test_turns"] = 3.5;
  const std::string path = tmpPath("generator.json");
  writeJsonFile(path, j);
  const FeatherParams p = loadFeather(path);
  EXPECT_EQ(p.generator, "test_gen");
  const FeatherCurves c = generateBarbs(p);
  EXPECT_TRUE(c.barbs.empty());
  EXPECT_FLOAT_EQ(c.shafts[0].points[1].x, 3.5f);
  saveFeather(path, p);
  EXPECT_EQ(loadFeather(path), p);
  j["test_turns"] = 300;
  writeJsonFile(path, j);
  EXPECT_THROW(loadFeather(path), Error);
}

TEST(FeatherFile, CurvesObjHasOnePolylinePerBarb) {
  const FeatherParams p = feather::testing::contourParams();
  const FeatherCurves c = generateBarbs(p);
  const std::string path = tmpPath("curves.obj");
  writeCurvesObj(path, c, 6);
  std::ifstream in(path);
  std::string line;
  size_t lines = 0, verts = 0;
  while (std::getline(in, line)) {
    if (line.rfind("l ", 0) == 0) ++lines;
    if (line.rfind("v ", 0) == 0) ++verts;
  }
  EXPECT_EQ(lines, c.barbs.size() + c.shafts.size());
  EXPECT_EQ(verts, c.barbs.size() * 7 + c.shafts[0].points.size());
}
