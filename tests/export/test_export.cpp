// Coat export (exchange/coat_export.hpp): the USD files read back with a strict independent reader
// (usda_reader.hpp), the glTF files read back with tinygltf, a golden tiny coat, determinism, and bad
// input. The Khronos validator runs on the CLI's exports in export_cli.sh.
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/exchange/coat_export.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pteryla.hpp"
#include "../../src/exchange/frames.hpp"
#include "usda_reader.hpp"

namespace fs = std::filesystem;
using namespace pteryla;

namespace {

const std::string kData = PTERYLA_DATA_DIR;
const std::string kTests = PTERYLA_TEST_DIR;
const std::string kTiny = kTests + "/tiny_coat.json";
const std::string kGolden = kTests + "/golden/tiny_coat.usda";

std::string outDir() {
  const std::string d = std::string(PTERYLA_BUILD_DIR) + "/test_export_out";
  fs::create_directories(d);
  return d;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::unique_ptr<pipeline::Pipeline> load(const std::string& scene, std::optional<double> lod = std::nullopt) {
  auto p = std::make_unique<pipeline::Pipeline>(pipeline::loadScene(scene));
  if (lod) p->setLod(*lod);
  return p;
}

usda::Layer exportUsd(pipeline::Pipeline& p, const std::string& name, exchange::ExportOptions opt) {
  const std::string path = outDir() + "/" + name;
  exchange::exportCoat(p, path, opt);
  return usda::read(slurp(path));
}

const usda::Prim& prim(const usda::Layer& l, std::initializer_list<const char*> path) {
  const usda::Prim* p = nullptr;
  for (const char* n : path) {
    if (!p) {
      for (const auto& top : l.prims)
        if (top.name == n) p = &top;
    } else {
      p = p->child(n);
    }
    if (!p) throw std::runtime_error(std::string("no prim ") + n);
  }
  return *p;
}

size_t len(const usda::Attribute& a) { return a.value.items.size(); }

size_t liveCoatTriangles(pipeline::Pipeline& p) {
  const TriMesh& m = p.coatMesh().mesh;
  size_t n = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    n += !(m.indices[3 * t + 1] == m.indices[3 * t] && m.indices[3 * t + 2] == m.indices[3 * t]);
  return n;
}

float asFloat(const usda::Value& v) {
  float f = 0;
  std::from_chars(v.text.data(), v.text.data() + v.text.size(), f);
  return f;
}

// Checks a BasisCurves prim's shapes; returns its curve count.
size_t checkCurves(const usda::Prim& c) {
  EXPECT_EQ(c.type, "BasisCurves");
  EXPECT_EQ(c.attr("type").value.text, "linear");
  EXPECT_EQ(c.attr("wrap").value.text, "nonperiodic");
  const auto& counts = c.attr("curveVertexCounts").value.items;
  size_t total = 0;
  for (const auto& n : counts) {
    EXPECT_GE(n.number(), 2);
    total += size_t(n.number());
  }
  EXPECT_EQ(len(c.attr("points")), total);
  EXPECT_EQ(len(c.attr("widths")), total);
  EXPECT_EQ(c.attr("widths").meta.at("interpolation").text, "vertex");
  EXPECT_EQ(len(c.attr("primvars:st")), total);
  for (const char* u :
       {"primvars:feather_id", "primvars:tract", "primvars:layer", "primvars:age", "primvars:displayColor"}) {
    EXPECT_EQ(len(c.attr(u)), counts.size()) << u;
    EXPECT_EQ(c.attr(u).meta.at("interpolation").text, "uniform") << u;
  }
  for (const auto& w : c.attr("widths").value.items) EXPECT_GE(w.number(), 0.0);
  return counts.size();
}

}  // namespace

TEST(ExportFormat, ExtensionsAndRanges) {
  EXPECT_EQ(exchange::formatOf("a/b.GLB"), exchange::Format::Glb);
  EXPECT_EQ(exchange::formatOf("b.gltf"), exchange::Format::Gltf);
  EXPECT_EQ(exchange::formatOf("b.usda"), exchange::Format::Usda);
  try {
    exchange::formatOf("coat.fbx");
    FAIL() << "no error for .fbx";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "--out");
    EXPECT_EQ(e.file(), "coat.fbx");
  }
  try {
    exchange::frameTimes(2, 1, 24);
    FAIL() << "no error for --from after --to";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "--from");
  }
  EXPECT_THROW(exchange::coatAsOf("hair"), Error);
  const auto t = exchange::frameTimes(1, 2, 4);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_DOUBLE_EQ(t.back(), 2.0);
}

// The tiny coat's USD equals the golden file byte for byte (PTERYLA_UPDATE_GOLDEN=1 rewrites it).
TEST(ExportUsd, TinyCoatMatchesGolden) {
  auto p = load(kTiny);
  const std::string out = outDir() + "/tiny_coat.usda";
  exchange::exportCoat(*p, out, {});
  if (const char* u = std::getenv("PTERYLA_UPDATE_GOLDEN"); u && std::string(u) == "1")
    fs::copy_file(out, kGolden, fs::copy_options::overwrite_existing);
  ASSERT_TRUE(fs::exists(kGolden));
  EXPECT_TRUE(slurp(out) == slurp(kGolden))
      << "export of " << kTiny << " differs from " << kGolden << "; actual: " << out;
}

// Reading the golden back gives exactly the pipeline's floats: skin points in order, and every curve
// point is a vertex of the coat mesh, bit for bit; every float is written as its shortest exact text.
TEST(ExportUsd, GoldenReadsBackExactly) {
  auto p = load(kTiny);
  const usda::Layer l = usda::read(slurp(kGolden));
  EXPECT_EQ(l.meta.at("upAxis").text, "Y");
  EXPECT_EQ(l.meta.at("metersPerUnit").number(), 1.0);
  EXPECT_EQ(l.meta.at("defaultPrim").text, "pteryla");
  const TriMesh skin = p->skinTriMesh();
  const auto& pts = prim(l, {"pteryla", "skin"}).attr("points").value.items;
  ASSERT_EQ(pts.size(), skin.positions.size());
  for (size_t i = 0; i < pts.size(); ++i)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(asFloat(pts[i].items[size_t(c)]), skin.positions[i][c]) << "skin vertex " << i;
  const TriMesh& coat = p->coatMesh().mesh;
  std::set<std::array<float, 3>> vertices;
  for (const auto& v : coat.positions) vertices.insert({v.x, v.y, v.z});
  const auto& barbs = prim(l, {"pteryla", "coat", "barbs"}).attr("points").value.items;
  ASSERT_FALSE(barbs.empty());
  for (const auto& b : barbs) {
    const std::array<float, 3> q = {asFloat(b.items[0]), asFloat(b.items[1]), asFloat(b.items[2])};
    EXPECT_TRUE(vertices.count(q)) << "barb point " << b.items[0].text << " " << b.items[1].text << " "
                                   << b.items[2].text;
    for (const auto& x : b.items) {
      char buf[32];
      const auto r = std::to_chars(buf, buf + sizeof buf, asFloat(x));
      EXPECT_EQ(std::string(buf, r.ptr), x.text);
    }
  }
}

// The writer formats arrays in chunks in parallel and copies the text of a value equal to the one before
// it. Every float must still read back bit for bit, across chunk boundaries (16384 values), for repeats,
// for -0 next to 0 (equal as floats, different texts), denormals and the extremes.
TEST(ExportUsd, ArraysReadBackBitExactly) {
  const float special[] = {0.0f,     -0.0f,       -0.0f,          0.0f,
                           0.0f,     1.0f / 3.0f, 1.0f / 3.0f,    -1.17549435e-38f,
                           1.4e-45f, -1.4e-45f,   3.40282347e38f, -3.40282347e38f,
                           1e-7f,    123456.789f};
  exchange::detail::ExportScene scene;
  exchange::detail::ExportFrame frame;
  const size_t n = 40000;  // three chunks
  for (size_t i = 0; i < n; ++i) {
    const float a = special[i % std::size(special)], b = special[(i / 3) % std::size(special)];
    frame.skin.positions.push_back(i % 5 == 0 ? glm::vec3(a, b, -a) : glm::vec3(float(i) * 0.001f, a, b));
  }
  frame.skin.normals.assign(n, glm::vec3(0, 0, 1));
  for (uint32_t i = 0; i + 2 < n; i += 3) frame.skin.indices.insert(frame.skin.indices.end(), {i, i + 1, i + 2});
  scene.frames.push_back(frame);
  const std::string path = outDir() + "/special_numbers.usda";
  exchange::detail::UsdCounts counts;
  const size_t bytes = exchange::detail::writeUsda(scene, path, exchange::CoatAs::Cards, 1, counts);
  const std::string text = slurp(path);
  EXPECT_EQ(bytes, text.size());
  const usda::Layer l = usda::read(text);
  const auto& pts = prim(l, {"pteryla", "skin"}).attr("points").value.items;
  ASSERT_EQ(pts.size(), n);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const float expected = frame.skin.positions[i][c], actual = asFloat(pts[i].items[size_t(c)]);
      ASSERT_EQ(std::memcmp(&expected, &actual, sizeof(float)), 0)
          << "vertex " << i << " component " << c << ": " << pts[i].items[size_t(c)].text;
    }
  const auto& idx = prim(l, {"pteryla", "skin"}).attr("faceVertexIndices").value.items;
  ASSERT_EQ(idx.size(), frame.skin.indices.size());
  for (size_t i = 0; i < idx.size(); ++i) ASSERT_EQ(idx[i].text, std::to_string(frame.skin.indices[i])) << i;
}

TEST(ExportUsd, CurvesPerFeather) {
  auto p = load(kData + "/scenes/patch.json", 0.3);
  const usda::Layer l = exportUsd(*p, "patch_curves.usda", {});
  const size_t rachises = checkCurves(prim(l, {"pteryla", "coat", "rachises"}));
  const size_t barbs = checkCurves(prim(l, {"pteryla", "coat", "barbs"}));
  EXPECT_EQ(rachises, p->coatMesh().ranges.size()) << "one rachis per present feather";
  EXPECT_GT(barbs, 10 * rachises);
  // st: s along the rachis in [0,1]; t across: each barb stays on its vane's side of 0.5, both sides used.
  const auto& b = prim(l, {"pteryla", "coat", "barbs"});
  const auto& counts = b.attr("curveVertexCounts").value.items;
  const auto& st = b.attr("primvars:st").value.items;
  size_t at = 0, left = 0, right = 0;
  for (const auto& n : counts) {
    bool lo = true, hi = true;
    for (size_t k = 0; k < size_t(n.number()); ++k, ++at) {
      const double s = st[at].items[0].number(), t = st[at].items[1].number();
      EXPECT_GE(s, 0.0);
      EXPECT_LE(s, 1.0);
      lo = lo && t <= 0.5 + 1e-6;
      hi = hi && t >= 0.5 - 1e-6;
    }
    EXPECT_TRUE(lo || hi) << "a barb crosses the rachis in st";
    left += lo && !hi;
    right += hi && !lo;
  }
  EXPECT_GT(left, 0u);
  EXPECT_GT(right, 0u);
  // Every feather id names a present feather; layers follow the packing order.
  const coat::CoatFeathers& f = p->feathers();
  std::vector<uint32_t> layer(f.size());
  for (size_t k = 0; k < f.layerOrder.size(); ++k) layer[f.layerOrder[k]] = uint32_t(k);
  const auto& fid = b.attr("primvars:feather_id").value.items;
  const auto& lay = b.attr("primvars:layer").value.items;
  for (size_t i = 0; i < fid.size(); ++i) {
    const size_t id = size_t(fid[i].number());
    ASSERT_LT(id, f.size());
    EXPECT_TRUE(f.present[id]);
    EXPECT_EQ(size_t(lay[i].number()), layer[id]);
  }
}

TEST(ExportUsd, CardsMatchTheMesh) {
  auto p = load(kData + "/scenes/patch.json", 0.3);
  exchange::ExportOptions opt;
  opt.as = exchange::CoatAs::Cards;
  const usda::Layer l = exportUsd(*p, "patch_cards.usda", opt);
  const usda::Prim& c = prim(l, {"pteryla", "coat", "cards"});
  EXPECT_EQ(c.type, "Mesh");
  const size_t faces = len(c.attr("faceVertexCounts"));
  EXPECT_EQ(faces, liveCoatTriangles(*p));
  for (const auto& n : c.attr("faceVertexCounts").value.items) EXPECT_EQ(n.text, "3");
  EXPECT_EQ(len(c.attr("faceVertexIndices")), 3 * faces);
  const size_t points = len(c.attr("points"));
  for (const auto& i : c.attr("faceVertexIndices").value.items) ASSERT_LT(size_t(i.number()), points);
  EXPECT_EQ(len(c.attr("primvars:st")), points);
  EXPECT_EQ(len(c.attr("primvars:displayOpacity")), points);
  EXPECT_EQ(len(c.attr("normals")), points);
  for (const char* u : {"primvars:feather_id", "primvars:tract", "primvars:layer", "primvars:age"})
    EXPECT_EQ(len(c.attr(u)), faces) << u;
}

// Instances over a moulting coat: one per feather, the moulted ones invisible, and each instance's
// orientation turns the prototype's +x (shaft) onto the feather's shaft direction.
TEST(ExportUsd, InstancesHideMoultedFeathers) {
  auto p = load(kData + "/scenes/moult.json", 0.2);
  exchange::ExportOptions opt;
  opt.as = exchange::CoatAs::Instances;
  const usda::Layer l = exportUsd(*p, "moult_instances.usda", opt);
  const usda::Prim& pi = prim(l, {"pteryla", "coat", "feathers"});
  EXPECT_EQ(pi.type, "PointInstancer");
  const coat::CoatFeathers& f = p->feathers();
  const size_t n = f.size();
  for (const char* a :
       {"ids", "protoIndices", "positions", "orientations", "scales", "primvars:feather_id", "primvars:age"})
    EXPECT_EQ(len(pi.attr(a)), n) << a;
  const auto& targets = pi.rels.at("prototypes");
  const usda::Prim* protos = pi.child("Prototypes");
  ASSERT_NE(protos, nullptr);
  EXPECT_EQ(targets.size(), protos->children.size());
  EXPECT_LE(targets.size(), 4 * p->coatMesh().materials.size());
  for (size_t k = 0; k < targets.size(); ++k)
    EXPECT_EQ(targets[k], "/pteryla/coat/feathers/Prototypes/" + protos->children[k].name);
  for (const auto& i : pi.attr("protoIndices").value.items) EXPECT_LT(size_t(i.number()), targets.size());
  std::set<size_t> invisible, absent;
  for (const auto& i : pi.attr("invisibleIds").value.items) invisible.insert(size_t(i.number()));
  for (size_t i = 0; i < n; ++i)
    if (!f.present[i]) absent.insert(i);
  EXPECT_FALSE(absent.empty()) << "moult.json at its scene time should have moulted feathers";
  EXPECT_EQ(invisible, absent);
  const auto& q = pi.attr("orientations").value.items;
  const std::vector<double>& elev = p->elevations();
  for (size_t i = 0; i < n; ++i) {
    const double w = q[i].items[0].number(), x = q[i].items[1].number(), y = q[i].items[2].number(),
                 z = q[i].items[3].number();
    EXPECT_NEAR(w * w + x * x + y * y + z * z, 1.0, 2e-3);
    // Rotate (1, 0, 0) by the quaternion: first column of its matrix.
    const glm::dvec3 shaft(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y));
    const auto pl =
        feather::FeatherPlacement::fromFollicle(f.frames[i].origin, f.frames[i].tangent, f.frames[i].normal, elev[i]);
    EXPECT_GT(glm::dot(shaft, pl.x), 0.995) << "feather " << i;
  }
}

TEST(ExportUsd, FrameRangeAsTimeSamples) {
  auto p = load(kData + "/scenes/moult.json", 0.1);
  exchange::ExportOptions opt;
  opt.times = exchange::frameTimes(3.5, 4.0, 4);
  opt.fps = 4;
  const double before = p->time();
  const usda::Layer l = exportUsd(*p, "moult_range.usda", opt);
  EXPECT_EQ(p->time(), before) << "the export restores the pipeline's time";
  EXPECT_EQ(l.meta.at("startTimeCode").number(), 14.0);
  EXPECT_EQ(l.meta.at("endTimeCode").number(), 16.0);
  EXPECT_EQ(l.meta.at("timeCodesPerSecond").number(), 4.0);
  const usda::Prim& b = prim(l, {"pteryla", "coat", "barbs"});
  const auto& pts = b.attr("points");
  EXPECT_FALSE(pts.hasDefault);
  ASSERT_EQ(pts.samples.size(), 3u);
  const auto& counts = b.attr("curveVertexCounts").samples;
  ASSERT_EQ(counts.size(), 3u);
  for (const auto& [code, v] : pts.samples) {
    size_t total = 0;
    for (const auto& c : counts.at(code).items) total += size_t(c.number());
    EXPECT_EQ(v.items.size(), total) << "time code " << code;
  }
}

// glTF read back by tinygltf: skin + one primitive per material, the per-feather attributes, the
// anisotropy extension, exact positions.
TEST(ExportGltf, ReadsBack) {
  auto p = load(kData + "/scenes/patch.json", 0.3);
  const std::string path = outDir() + "/patch.glb";
  exchange::exportCoat(*p, path, {});
  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  const std::string bytes = slurp(path);
  ASSERT_TRUE(loader.LoadBinaryFromMemory(&m, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                          unsigned(bytes.size())))
      << err;
  ASSERT_EQ(m.meshes.size(), 1u);
  ASSERT_EQ(m.nodes.size(), 1u);
  EXPECT_TRUE(m.animations.empty());
  size_t triangles = 0, featherIdsSeen = 0;
  const TriMesh skin = p->skinTriMesh();
  for (size_t k = 0; k < m.meshes[0].primitives.size(); ++k) {
    const auto& prim = m.meshes[0].primitives[k];
    triangles += m.accessors[size_t(prim.indices)].count / 3;
    if (k == 0) {
      // The skin: positions exactly the pipeline's, in order.
      const auto& a = m.accessors[size_t(prim.attributes.at("POSITION"))];
      ASSERT_EQ(a.count, skin.positions.size());
      const auto& v = m.bufferViews[size_t(a.bufferView)];
      const float* f = reinterpret_cast<const float*>(m.buffers[0].data.data() + v.byteOffset + a.byteOffset);
      for (size_t i = 0; i < a.count; ++i)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(f[3 * i + size_t(c)], skin.positions[i][c]);
      continue;
    }
    for (const char* name :
         {"POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "COLOR_0", "_FEATHER_ID", "_TRACT", "_LAYER", "_AGE"})
      ASSERT_TRUE(prim.attributes.count(name)) << name;
    const auto& mat = m.materials[size_t(prim.material)];
    EXPECT_TRUE(mat.extensions.count("KHR_materials_anisotropy"));
    EXPECT_EQ(mat.alphaMode, "BLEND");
    const auto& a = m.accessors[size_t(prim.attributes.at("_FEATHER_ID"))];
    const auto& v = m.bufferViews[size_t(a.bufferView)];
    const float* f = reinterpret_cast<const float*>(m.buffers[0].data.data() + v.byteOffset + a.byteOffset);
    for (size_t i = 0; i < a.count; ++i) {
      ASSERT_EQ(f[i], std::floor(f[i]));
      ASSERT_LT(size_t(f[i]), p->feathers().size());
      ASSERT_TRUE(p->feathers().present[size_t(f[i])]);
    }
    featherIdsSeen += a.count;
  }
  EXPECT_GT(featherIdsSeen, 0u);
  EXPECT_EQ(triangles, skin.triangleCount() + liveCoatTriangles(*p));
  ASSERT_EQ(
      std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), "KHR_materials_anisotropy") != m.extensionsUsed.end(),
      true);
}

TEST(ExportGltf, FrameRangeIsAFlipbook) {
  auto p = load(kData + "/scenes/moult.json", 0.1);
  exchange::ExportOptions opt;
  opt.times = exchange::frameTimes(3.5, 4.0, 4);
  opt.fps = 4;
  const std::string path = outDir() + "/moult_range.gltf";
  exchange::exportCoat(*p, path, opt);
  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadASCIIFromFile(&m, &err, &warn, path)) << err;
  ASSERT_EQ(m.nodes.size(), 3u);
  ASSERT_EQ(m.animations.size(), 1u);
  ASSERT_EQ(m.animations[0].channels.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    const auto& ch = m.animations[0].channels[k];
    EXPECT_EQ(ch.target_node, int(k));
    EXPECT_EQ(ch.target_path, "scale");
    EXPECT_EQ(m.animations[0].samplers[size_t(ch.sampler)].interpolation, "STEP");
    // Keys from 0 to the end of frame k's interval: k / fps shown, (k + 1) / fps hidden (the last stays).
    const auto& in = m.accessors[size_t(m.animations[0].samplers[size_t(ch.sampler)].input)];
    EXPECT_EQ(in.count, k == 0 || k == 2 ? 2u : 3u);
    EXPECT_DOUBLE_EQ(in.minValues[0], 0.0);
    EXPECT_DOUBLE_EQ(in.maxValues[0], double(std::min<size_t>(k + 1, 2)) / 4.0);
  }
  EXPECT_EQ(m.nodes[0].scale.size(), 0u);
  EXPECT_EQ(m.nodes[1].scale, std::vector<double>({0.0, 0.0, 0.0}));
}

TEST(Export, SameSceneSameBytes) {
  for (const char* name : {"a.glb", "a.usda"}) {
    auto p = load(kTiny);
    const std::string x = outDir() + "/det1_" + name, y = outDir() + "/det2_" + name;
    exchange::exportCoat(*p, x, {});
    auto q = load(kTiny);
    exchange::exportCoat(*q, y, {});
    EXPECT_TRUE(slurp(x) == slurp(y)) << name;
  }
}

TEST(Export, FailedWriteLeavesNothing) {
  auto p = load(kTiny);
  const std::string file = outDir() + "/not_a_dir";
  { std::ofstream(file) << "x"; }
  const std::string out = file + "/coat.glb";
  try {
    exchange::exportCoat(*p, out, {});
    FAIL() << "wrote under a regular file";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), out);
  }
  EXPECT_EQ(slurp(file), "x");
  exchange::ExportOptions range;
  range.times = {0, 1};
  EXPECT_THROW(exchange::exportCoat(*p, outDir() + "/range.obj", range), Error);
  EXPECT_FALSE(fs::exists(outDir() + "/range.obj"));
}

// The host API's export: the same bytes as the library call for the same scene, frame() kept valid.
TEST(ExportHost, SessionExportsTheSameCoat) {
  Session s = Session::fromSceneFile(kTiny);
  ASSERT_TRUE(s.evaluate());
  const size_t vertices = s.frame().positions.size;
  const std::string out = outDir() + "/session_tiny.usda";
  const ExportSummary r = s.exportTo(out);
  EXPECT_EQ(r.frames, 1u);
  EXPECT_EQ(r.bytes, fs::file_size(out));
  EXPECT_TRUE(slurp(out) == slurp(kGolden));
  ExportSettings range;
  range.times = {0.0, 0.5, 1.0};
  range.coatAs = "instances";
  EXPECT_EQ(s.exportTo(outDir() + "/session_range.usda", range).frames, 3u);
  EXPECT_EQ(s.frame().positions.size, vertices);
  range.times = {1.0, 0.5};
  try {
    s.exportTo(outDir() + "/bad.usda", range);
    FAIL() << "decreasing times accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "times[1]");
  }
}
