// Level of detail by screen size (Streit 2003, 7.1.3) through the scene path the CLI uses
// (SceneView + Pipeline), and what the alpha and BRDF textures buy at reduced geometry: the image of a
// coat at 45% of its barbs stays close to the full coat with the textures, much closer than the same
// reduction drawn without them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "gl_fixture.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/scene_view.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

using gltest::context;

pipeline::Scene coatScene(bool bySize, double lod = 0.6) {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 5, "mesh": "meshes/sphere_250.obj",
    "feathers": {"contour": "feathers/contour.json"},
    "tracts": [{"name": "all", "count": 150, "feather_scale": "auto", "relax": {"iterations": 10},
                "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}],
    "directions": {"axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "ordering": {"method": "axis", "axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "packing": {"method": "height_field"},
    "camera": {"auto_frame": false, "eye": [0.4, 0.6, 3.2], "target": [0, 0, 0], "fov": 35}})");
  j["render"] = {{"lod", lod}, {"lod_by_screen_size", bySize}};
  return pipeline::sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
}

Camera cameraAt(float distance) {
  Camera c;
  c.eye = glm::normalize(glm::vec3(0.4f, 0.6f, 3.2f)) * distance;
  c.target = glm::vec3(0);
  c.fovYDegrees = 35.0f;
  return c;
}

}  // namespace

TEST(SceneLod, FartherFeathersGetLowerLevelsWithinTheirBounds) {
  pipeline::Pipeline p(coatScene(true));
  const std::vector<double> nearL = screenSizeLods(p, cameraAt(2.0f), 640, 480);
  const std::vector<double> farL = screenSizeLods(p, cameraAt(16.0f), 640, 480);
  ASSERT_EQ(nearL.size(), p.feathers().size());
  double sumNear = 0, sumFar = 0;
  for (size_t i = 0; i < nearL.size(); ++i) {
    EXPECT_GE(farL[i], 0.1 - 1e-9);
    EXPECT_LE(nearL[i], 1.0);
    EXPECT_LE(farL[i], nearL[i]) << "feather " << i;
    sumNear += nearL[i];
    sumFar += farL[i];
  }
  EXPECT_LT(sumFar, 0.5 * sumNear);
  // A bigger image needs more detail.
  const std::vector<double> bigL = screenSizeLods(p, cameraAt(16.0f), 2560, 1920);
  for (size_t i = 0; i < bigL.size(); ++i) EXPECT_GE(bigL[i], farL[i]);
}

TEST(SceneLod, RenderBySizeDrawsFewerTrianglesAndKeepsTheLook) {
  // The same scene and camera rendered with a uniform level and with levels by screen size: far fewer
  // triangles, a small mean error, and every feather's level set (the scene's lod multiplies it).
  pipeline::Pipeline uniform(coatScene(false)), bySize(coatScene(true));
  SceneView a(context()), b(context());
  const Image imgA = a.render(uniform, 320, 240), imgB = b.render(bySize, 320, 240);
  const size_t triA = uniform.coatMesh().mesh.triangleCount(), triB = bySize.coatMesh().mesh.triangleCount();
  EXPECT_TRUE(uniform.featherLods().empty());
  ASSERT_EQ(bySize.featherLods().size(), bySize.feathers().size());
  EXPECT_LT(triB, triA * 0.8) << triB << " of " << triA;
  const double mae = meanAbsoluteError(imgA, imgB);
  // The same triangle budget spent uniformly (a lower level for every feather) looks worse: detail goes
  // where the barbs are far enough apart on screen to be seen.
  pipeline::Pipeline same(coatScene(false, 0.6 * double(triB) / double(triA)));
  SceneView c(context());
  const Image imgC = c.render(same, 320, 240);
  const size_t triC = same.coatMesh().mesh.triangleCount();
  const double maeUniform = meanAbsoluteError(imgA, imgC);
  std::printf(
      "screen-size LOD at 320x240: %zu of %zu triangles, mean absolute error %.4f (uniform level with "
      "%zu triangles: %.4f)\n",
      triB, triA, mae, triC, maeUniform);
  EXPECT_LT(mae, 0.02);
  EXPECT_NEAR(double(triC), double(triB), 0.1 * double(triB));
  EXPECT_LT(mae, 0.5 * maeUniform);
  // Rendering again draws the same image (levels are a pure function of scene, camera and size).
  EXPECT_EQ(meanAbsoluteError(b.render(bySize, 320, 240), imgB), 0.0);
}

TEST(SceneLod, TexturesKeepTheLookAtFortyFivePercent) {
  // 7.1.3: alpha (barbs repeated across a polygon) and BRDF textures let a feather lose geometry without
  // changing its look. Mean absolute error of 45% against 100% geometry, with and without them.
  pipeline::Pipeline p(coatScene(false, 1.0));
  Renderer r(context());
  const Camera cam = cameraAt(5.0f);
  const std::vector<Light> lights = sceneLights(p.scene());
  r.setMaterials(sceneMaterials(p.scene(), p.coatMesh()));
  auto renderAt = [&](double lod, bool textures) {
    p.setLod(lod);
    const pipeline::CoatMesh& coat = p.coatMesh();
    r.setSkin(p.skinTriMesh());
    r.setCoat(coat.mesh, drawRanges(coat));
    RenderSettings s = sceneSettings(p.scene(), 320, 240);
    s.useAlphaTexture = textures;
    s.useBrdf = textures;
    // The claim is about the textures: shadows, cast by each level's own barbs, are left out.
    s.shadows = false;
    return r.renderImage(cam, lights, s);
  };
  const Image fullTex = renderAt(1.0, true), fullPlain = renderAt(1.0, false);
  const Image lowTex = renderAt(0.45, true), lowPlain = renderAt(0.45, false);
  const double withTextures = meanAbsoluteError(fullTex, lowTex);
  const double without = meanAbsoluteError(fullTex, lowPlain);
  const double plainVsPlain = meanAbsoluteError(fullPlain, lowPlain);
  std::printf(
      "45%% vs 100%% geometry: mean absolute error %.4f with alpha/BRDF textures, %.4f without (%.4f "
      "against the full coat also drawn without)\n",
      withTextures, without, plainVsPlain);
  EXPECT_LT(withTextures, 0.02);
  EXPECT_LT(withTextures, 0.7 * without);
}

// material.uv (Streit 2003, 7.1.1) picks which texture coordinates the colour pattern follows: the
// feather file's choice reaches the renderer's material, and each mapping lays the same pattern
// differently (three different images of one coat), while the default stays "global".
TEST(SceneMaterials, TextureMappingFollowsTheFeatherFile) {
  Json feather = readJsonFile(std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json");
  std::vector<Image> images;
  for (const char* uv : {"global", "barb", "growth"}) {
    feather["material"] = {{"pattern", "barred"}, {"base_color", {0.45, 0.33, 0.2}}, {"uv", uv}};
    pipeline::Scene scene = coatScene(false, 0.5);
    scene.feathers["contour"] = feather;
    pipeline::Pipeline p(scene);
    const std::vector<FeatherMaterial> m = sceneMaterials(p.scene(), p.coatMesh());
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(int(m[0].colorUv), std::string(uv) == "global" ? int(ColorUv::Global)
                                 : std::string(uv) == "barb" ? int(ColorUv::Barb)
                                                             : int(ColorUv::Growth));
    EXPECT_EQ(p.coatMesh().materials[0].uv, uv);
    SceneView view(context());
    images.push_back(view.render(p, 160, 120, "shaded"));
  }
  for (size_t a = 0; a < images.size(); ++a)
    for (size_t b = a + 1; b < images.size(); ++b) {
      size_t differ = 0;
      for (size_t i = 0; i < images[a].rgba.size(); i += 4)
        differ += std::abs(int(images[a].rgba[i]) - int(images[b].rgba[i])) > 8;
      EXPECT_GT(differ, 200u) << "mappings " << a << " and " << b << " draw the same image";
    }
  // A bad mapping is refused, naming it.
  feather["material"]["uv"] = "planar";
  pipeline::Scene bad = coatScene(false, 0.5);
  bad.feathers["contour"] = feather;
  try {
    pipeline::Pipeline p(bad);
    p.coatMesh();
    ADD_FAILURE() << "no error for material.uv \"planar\"";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("material.uv"), std::string::npos) << e.what();
  }
  // The feather file round-trips the choice, and leaves the default out.
  feather["material"]["uv"] = "growth";
  JsonReader fr(feather, "", "feather");
  const feather::FeatherParams fp = feather::readFeather(fr);
  EXPECT_EQ(fp.material.uv, "growth");
  EXPECT_EQ(feather::featherToJson(fp)["material"]["uv"], "growth");
  feather["material"].erase("uv");
  JsonReader fr2(feather, "", "feather");
  EXPECT_FALSE(feather::featherToJson(feather::readFeather(fr2))["material"].contains("uv"));
}

// render.* keys of #29: read, checked (the element named), written back; the studio rig's three lights
// sit where a look-dev user expects them around the camera (key above and on the camera's side, fill
// on the other side, rim behind).
TEST(SceneLook, RenderKeysRoundTripAndBadValuesNameTheKey) {
  pipeline::Scene s = coatScene(false);
  EXPECT_TRUE(s.render.shadows);
  EXPECT_EQ(s.render.msaa, 4);
  EXPECT_EQ(s.render.tone, "linear");
  Json j = pipeline::sceneToJson(s, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
  j["render"]["msaa"] = 8;
  j["render"]["tone"] = "filmic";
  j["render"]["exposure"] = -0.5;
  j["render"]["light_rig"] = "studio";
  j["render"]["ground"] = true;
  j["render"]["ground_color"] = {0.5, 0.4, 0.3};
  j["render"]["shadows"] = false;
  j["render"]["shadow_strength"] = 0.25;
  const pipeline::Scene t = pipeline::sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
  EXPECT_EQ(t.render.msaa, 8);
  EXPECT_EQ(t.render.tone, "filmic");
  EXPECT_EQ(t.render.exposure, -0.5);
  EXPECT_EQ(t.render.lightRig, "studio");
  EXPECT_TRUE(t.render.ground);
  EXPECT_EQ(t.render.groundColor, glm::dvec3(0.5, 0.4, 0.3));
  EXPECT_FALSE(t.render.shadows);
  EXPECT_EQ(t.render.shadowStrength, 0.25);
  EXPECT_EQ(pipeline::sceneToJson(t, std::string(PTERYLA_DATA_DIR) + "/scene_test.json")["render"], j["render"]);
  const RenderSettings rs = sceneSettings(t, 64, 64);
  EXPECT_EQ(rs.msaaSamples, 8);
  EXPECT_TRUE(rs.filmic);
  EXPECT_FALSE(rs.shadows);
  EXPECT_TRUE(rs.ground);
  for (const auto& [key, value] : std::vector<std::pair<std::string, Json>>{{"msaa", 3},
                                                                            {"exposure", 9},
                                                                            {"tone", "aces"},
                                                                            {"light_rig", "three"},
                                                                            {"shadow_strength", 1.5},
                                                                            {"shadows", "yes"},
                                                                            {"ground_color", {2, 0, 0}}}) {
    Json bad = j;
    bad["render"][key] = value;
    try {
      pipeline::sceneFromJson(bad, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
      ADD_FAILURE() << key << " accepted " << value.dump();
    } catch (const Error& e) {
      EXPECT_NE(e.element().find("render." + key), std::string::npos) << key << ": " << e.element();
    }
  }
}

TEST(SceneLook, StudioRigPutsKeyFillAndRimAroundTheCamera) {
  pipeline::Scene s = coatScene(false);
  s.render.lightRig = "studio";
  const glm::vec3 view = glm::normalize(glm::vec3(s.camera.target - s.camera.eye));
  const glm::vec3 up = glm::vec3(s.camera.up);
  const glm::vec3 right = glm::normalize(glm::cross(view, up));
  const std::vector<Light> l = sceneLights(s);
  ASSERT_EQ(l.size(), 3u);
  auto dir = [&](int i) { return glm::normalize(l[size_t(i)].direction); };  // toward the light
  EXPECT_LT(glm::dot(dir(0), view), 0.0f) << "key on the camera's side";
  EXPECT_GT(glm::dot(dir(0), up), 0.3f) << "key above";
  EXPECT_LT(glm::dot(dir(0), right), 0.0f) << "key from the left";
  EXPECT_GT(glm::dot(dir(1), right), 0.3f) << "fill from the right";
  EXPECT_LT(glm::length(l[1].color), 0.6f * glm::length(l[0].color)) << "fill weaker than key";
  EXPECT_GT(glm::dot(dir(2), view), 0.3f) << "rim from behind";
  s.render.lightRig = "scene";
  EXPECT_EQ(sceneLights(s).size(), s.lights.size());
}

// A timeline step that changes no input of any stage (a scene that reads no time) costs nothing: no
// stage evaluates again, the renderer keeps its uploaded coat and its shadow map, and the frame is the
// same, with screen-size levels of detail on or off (#27).
TEST(SceneLod, AStaticTimeStepRedoesNothing) {
  for (const bool bySize : {false, true}) {
    pipeline::Pipeline p(coatScene(bySize));
    SceneView view(context());
    const Image first = view.render(p, 160, 120);
    EXPECT_TRUE(view.renderer().lastStats().shadowMapRendered);
    const Image second = view.render(p, 160, 120);  // settles the per-feather levels of detail
    using pipeline::Stage;
    std::vector<uint64_t> before;
    for (int s = 0; s <= static_cast<int>(Stage::Mesh); ++s) before.push_back(p.evaluations(static_cast<Stage>(s)));
    p.setTime(p.time() + 0.04);
    const Image third = view.render(p, 160, 120);
    for (int s = 0; s <= static_cast<int>(Stage::Mesh); ++s)
      EXPECT_EQ(p.evaluations(static_cast<Stage>(s)), before[s]) << pipeline::stageName(static_cast<Stage>(s));
    EXPECT_FALSE(view.renderer().lastStats().shadowMapRendered) << "the map is kept";
    EXPECT_EQ(third.rgba, second.rgba);
    EXPECT_EQ(second.rgba, first.rgba);
  }
}

namespace {

// coatScene with an auto-framed camera (looking along the explicit camera's view).
pipeline::Scene autoFramedScene(bool bySize, double lod = 0.6) {
  pipeline::Scene s = coatScene(bySize, lod);
  s.camera.autoFrame = true;
  s.camera.viewDir = glm::dvec3(-0.4, -0.6, -3.2);
  return s;
}

}  // namespace

// Levels by screen size are the default (#27), and what a render meshes follows the camera: the same coat
// seen from 2.2 and from 12 units meshes far fewer triangles from afar, and never more than the scene's
// render.lod (the cap) gives every feather.
TEST(SceneLod, AFarCameraMeshesFewerTrianglesThanANearOne) {
  EXPECT_TRUE(pipeline::Scene{}.render.lodByScreenSize) << "on by default";
  auto trianglesFrom = [](float distance) {
    pipeline::Scene s = coatScene(true);
    s.camera.eye = glm::dvec3(cameraAt(distance).eye);
    pipeline::Pipeline p(s);
    SceneView view(context());
    view.render(p, 320, 240);
    return p.coatMesh().mesh.triangleCount();
  };
  const size_t nearTri = trianglesFrom(2.2f), farTri = trianglesFrom(12.0f);
  pipeline::Pipeline uniform(coatScene(false));
  const size_t cap = uniform.coatMesh().mesh.triangleCount();
  std::printf("triangles meshed at 320x240: %zu from 2.2 units, %zu from 12, %zu at the uniform level\n", nearTri,
              farTri, cap);
  EXPECT_LE(nearTri, cap);
  EXPECT_LT(farTri, nearTri / 2);
}

// The fixed level (render.lod_by_screen_size false, `--fixed-lod`) draws exactly what SceneView drew
// before levels by screen size: every feather at render.lod, an auto-framed camera framing that coat's
// mesh. Bit for bit, also after a render by screen size on the same pipeline.
TEST(SceneLod, TheFixedLevelPathIsUnchangedBitForBit) {
  for (const bool autoFrame : {false, true}) {
    SCOPED_TRACE(autoFrame ? "auto-framed" : "explicit camera");
    pipeline::Scene s = autoFrame ? autoFramedScene(false) : coatScene(false);
    // The reference, drawn by hand the way SceneView::render did.
    pipeline::Pipeline ref(s);
    const pipeline::CoatMesh& coat = ref.coatMesh();
    const TriMesh skin = ref.skinTriMesh();
    Renderer r(context());
    r.setMaterials(sceneMaterials(ref.scene(), coat));
    r.setSkin(skin);
    r.setCoat(coat.mesh, drawRanges(coat));
    const Image expected = r.renderImage(sceneCamera(ref.scene(), skin, coat.mesh, 320, 240), sceneLights(ref.scene()),
                                         sceneSettings(ref.scene(), 320, 240));

    pipeline::Pipeline p(s);
    SceneView view(context());
    const Image fixed = view.render(p, 320, 240);
    EXPECT_TRUE(p.featherLods().empty());
    EXPECT_EQ(p.coatMesh().mesh.positions, coat.mesh.positions);
    EXPECT_EQ(p.coatMesh().mesh.indices, coat.mesh.indices);
    EXPECT_EQ(fixed.rgba, expected.rgba);
    // By screen size, then fixed again: the levels are cleared and the same image comes back.
    p.editScene(pipeline::Stage::Mesh, [](pipeline::Scene& sc) { sc.render.lodByScreenSize = true; });
    const Image bySize = view.render(p, 320, 240);
    EXPECT_FALSE(p.featherLods().empty());
    EXPECT_NE(bySize.rgba, expected.rgba);
    p.editScene(pipeline::Stage::Mesh, [](pipeline::Scene& sc) { sc.render.lodByScreenSize = false; });
    EXPECT_EQ(view.render(p, 320, 240).rgba, expected.rgba);
  }
}

// An auto-framed camera with levels by screen size frames the skin and the coat's reach from the packed
// feathers (coatReachBounds), so the coat is meshed once, at its screen levels, never first at the uniform
// level. The reach holds the coat's full-detail mesh and is barely larger.
TEST(SceneLod, AutoFramingDoesNotMeshTheCoatFirst) {
  using pipeline::Stage;
  pipeline::Pipeline p(autoFramedScene(true));
  glm::vec3 lo, hi;
  ASSERT_TRUE(coatReachBounds(p, lo, hi));
  EXPECT_EQ(p.evaluations(Stage::Mesh), 0u) << "the reach needs no mesh";
  EXPECT_GT(p.evaluations(Stage::Pack), 0u);

  pipeline::Pipeline full(autoFramedScene(false, 1.0));
  glm::vec3 mlo, mhi, slo, shi;
  ASSERT_TRUE(full.coatMesh().mesh.bounds(mlo, mhi));
  ASSERT_TRUE(full.skinTriMesh().bounds(slo, shi));
  mlo = glm::min(mlo, slo);
  mhi = glm::max(mhi, shi);
  const float diag = glm::length(mhi - mlo);
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(lo[k], mlo[k] + 0.01f * diag) << "axis " << k;
    EXPECT_GE(hi[k], mhi[k] - 0.01f * diag) << "axis " << k;
  }
  EXPECT_LT(glm::length(hi - lo), 1.05f * diag);
  std::printf("reach bounds diagonal %.4f, full-detail mesh and skin %.4f\n", double(glm::length(hi - lo)),
              double(diag));

  SceneView view(context());
  view.render(p, 320, 240);
  EXPECT_EQ(p.evaluations(Stage::Mesh), 1u) << "meshed once, at the screen levels";
  const size_t meshed = p.coatMesh().mesh.triangleCount();
  pipeline::Pipeline uniform(autoFramedScene(false));
  EXPECT_LT(meshed, uniform.coatMesh().mesh.triangleCount());
  // The camera framed the reach: the same as sceneCameraForBounds of it.
  const Camera cam = sceneCameraForBounds(p.scene(), lo, hi, 320, 240);
  EXPECT_EQ(screenSizeLods(p, cam, 320, 240), p.featherLods());
  // Rendering again meshes nothing.
  view.render(p, 320, 240);
  EXPECT_EQ(p.evaluations(Stage::Mesh), 1u);
}

// The memory ceiling counts what a render meshes: before packing, the least levels by screen size (a
// tenth of render.lod), and before meshing, the levels the mesh is given. A coat refused at a fixed level
// renders by screen size from afar; meshed at the uniform level instead, the mesh stage refuses it.
TEST(SceneLod, TheMemoryCeilingCountsTheLevelsARenderMeshes) {
  struct Ceiling {
    double saved = memoryLimitBytes();
    ~Ceiling() { setMemoryLimitBytes(saved); }
  } restore;
  pipeline::Scene farScene = coatScene(true);
  farScene.camera.eye = glm::dvec3(cameraAt(12.0f).eye);
  pipeline::Scene fixed = farScene;
  fixed.render.lodByScreenSize = false;
  const double uniformTriangles = double(pipeline::Pipeline(fixed).coatMesh().mesh.triangleCount());
  // A ceiling of half the uniform coat's triangles at 200 bytes (the estimate's, docs/limits.md).
  setMemoryLimitBytes(uniformTriangles * 200.0 / 2.0);
  pipeline::Pipeline refused(fixed);
  EXPECT_THROW(refused.coatMesh(), Error) << "at a fixed level";

  pipeline::Pipeline p(farScene);
  SceneView view(context());
  EXPECT_NO_THROW(view.render(p, 320, 240));
  EXPECT_LT(p.coatMesh().mesh.triangleCount(), 60000u);

  pipeline::Pipeline uniform(farScene);
  try {
    uniform.coatMesh();  // no render: every feather at render.lod
    ADD_FAILURE() << "the uniform mesh passed the ceiling";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the coat's mesh"), std::string::npos) << e.what();
    EXPECT_EQ(e.element(), "feathers.contour");
  }
}

// The checker measures every feather at full detail, also after a render by screen size set levels on the
// pipeline, and gives the levels back.
TEST(SceneLod, TheCheckerMeshesEveryFeatherAfterARender) {
  pipeline::Pipeline rendered(coatScene(true)), fresh(coatScene(true));
  SceneView view(context());
  view.render(rendered, 320, 240);
  const std::vector<double> levels = rendered.featherLods();
  ASSERT_FALSE(levels.empty());
  const pipeline::QualityMetrics a = rendered.check(), b = fresh.check();
  EXPECT_EQ(a.intersectingPairs, b.intersectingPairs);
  EXPECT_EQ(a.skinPenetrations, b.skinPenetrations);
  EXPECT_EQ(a.coverage, b.coverage);
  EXPECT_EQ(rendered.featherLods(), levels);
}
