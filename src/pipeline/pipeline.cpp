// The evaluation pipeline: one StageGraph node per stage of the thesis' method (Streit 2003, Ch.6-8),
// each owning its cached result. See include/pteryla/pipeline/pipeline.hpp for the graph.
#include "pteryla/pipeline/pipeline.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <limits>
#include <optional>
#include <glm/common.hpp>
#include <cmath>
#include <cstring>
#include <map>

#include "pteryla/coat/check.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/coat/metrics.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/coat/drape.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/relax.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/mesh.hpp"
#include "coat_mesher.hpp"
#include "scene_sections.hpp"
#include "stage_graph.hpp"
#include "time_stages.hpp"

namespace pteryla::pipeline {

const char* stageName(Stage s) {
  switch (s) {
    case Stage::Skin: return "skin";
    case Stage::Tracts: return "tracts";
    case Stage::Distribute: return "distribute";
    case Stage::Interpolate: return "interpolate";
    case Stage::Directions: return "directions";
    case Stage::Pose: return "pose";
    case Stage::Ages: return "ages";
    case Stage::Controls: return "controls";
    case Stage::Pack: return "pack";
    case Stage::Mesh: return "mesh";
  }
  return "?";
}

namespace {

// Per-tract settings the pipeline reads itself (the rest of a tract object belongs to coat parsers).
struct TractSettings {
  coat::Tract tract;
  double density = 0;       // follicles per unit area (0: use count)
  size_t count = 0;
  bool autoScale = false;   // scale feathers so their length is ~featherSpacings x follicle spacing
  double featherScale = 1;  // explicit scale factor
  double featherSpacings = 3.5;
  coat::RelaxOptions relax;
  std::vector<glm::dvec3> pinned;
  coat::TractFeatherOptions feathers;
  std::shared_ptr<const feather::GrowthSchedule> growth;  // the tract's "growth" (null: none)
  std::string overlapGroup;  // "overlap_group": tracts of one group share one distribution where they overlap
  std::optional<uint64_t> seed;  // "seed": this tract's own follicle seed (else derived from the scene's)
  double area = 0;
  std::string element;
};

// Follicles of a tract with neither count nor density, times its share of the mesh area: 3,000 lets the
// small parts of real meshes (fingers, ears, fins) carry their own feathers (issue #22, docs/packing.md).
constexpr size_t kAutoCount = 3000;
// Memory estimates checked against the ceiling (core/limits.hpp, docs/limits.md). Lower bounds from the
// bird (3152 feathers, 1.29 M triangles at lod 0.6: 775 MB peak), so no scene that fits is refused.
constexpr double kBytesPerFollicle = 32e3;
constexpr double kTrianglesPerBarb = 16;
constexpr double kBytesPerTriangle = 200;

// Axes of the rest skin's bounding box, longest first.
void boxAxes(const coat::SkinMesh& m, glm::dvec3& lo, glm::dvec3& hi, int axes[3]) {
  lo = hi = m.positions.empty() ? glm::dvec3(0) : m.positions[0];
  for (const auto& p : m.positions) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
  const glm::dvec3 ext = hi - lo;
  axes[0] = 0; axes[1] = 1; axes[2] = 2;
  std::sort(axes, axes + 3, [&](int a, int b) { return ext[a] > ext[b]; });
}


}  // namespace

struct Pipeline::Impl {
  Scene scene;
  ProgressFn progress;
  double time = 0, lod = 1;
  std::vector<double> featherLods;  // per feather, multiplies lod (empty: 1 for all)
  StageGraph graph;  // node int(s) is stage s

  std::optional<coat::SkinMesh> memorySkin;  // the rest skin when given in memory (else scene.meshPath)
  std::vector<glm::dvec3> skinPose;          // the caller's posed positions (empty: skeleton / rest)
  std::map<uint64_t, double> hostElevations;  // setFixedElevations: follicle id -> radians

  // Cached stage results.
  coat::SkinMesh rest, posed;
  coat::FeatherLibrary library;
  std::vector<std::string> materialNames;
  std::vector<TractSettings> tractSettings;
  std::shared_ptr<const feather::GrowthSchedule> sceneGrowth;  // the scene's "growth" (null: none)
  std::vector<coat::Tract> tracts;
  coat::Follicles follicles, posedFollicles;
  std::vector<coat::RelaxResult> relaxResults;
  std::vector<coat::TractParameterization> params;
  coat::CoatFeathers coatRest;    // interpolated + rest frames + order
  coat::SurfaceDirections directions;
  coat::DirectionOptions directionOptions;
  coat::OrderOptions orderOptions;
  coat::PackOptions packOptions;
  coat::CoatFeathers coatNow;     // at the current time: posed frames, ages, presence
  coat::CoatFeathers packCoat;    // coatNow with growing feathers as grown (the pack input when any grows)
  std::vector<double> packGrownAge;  // per feather, the age packCoat's parameters are grown to (empty = none)
  TimeState timeState;
  std::vector<double> fixedElevation;
  const coat::PackResult* packed = nullptr;  // timeState.frame.result once packed
  const coat::CoatFeathers* packedCoat = nullptr;  // the coat `packed` was packed from (coatNow or packCoat)
  // Draped packing (packing.method "drape"): the pack stage lays nothing (every elevation 0, `flatPack`)
  // and the mesh stage drapes the assembled mesh; `drape` is its last result.
  coat::PackResult flatPack;
  coat::DrapeResult drape;
  CoatMesh mesh;
  CoatMesher mesher;                // mesh.mesh is its last result
  // Rest-state generation: bumped whenever the directions stage (downstream of every rest stage) runs,
  // so caches of time-stage results know when the rest state they were made from is gone.
  uint64_t restGeneration = 1;
  uint64_t coatNowGeneration = 0;   // generation coatNow was copied from coatRest at
  uint64_t posedGeneration = 0;     // generation `posed` is an untouched copy of `rest` at (0 = not)
  // check(): the last unpacked proxy coat and its intersecting pair count. The unpacked coat comes from
  // the input alone, so checks after edits that leave it as it was (packing, pose-free edits, LOD)
  // reuse the count instead of searching the same mesh again.
  TriMesh lastUnpacked;
  std::optional<size_t> lastUnpackedPairs;

  static StageGraph::Id id(Stage s) { return static_cast<StageGraph::Id>(s); }

  void build();
  void computeSkin();
  void computeTracts();
  void computeDistribute();
  void redistributeOverlaps(uint64_t& nextId);
  void computeInterpolate();
  coat::TractParameterization boxParameterization(uint32_t tract) const;
  void computeDirections();
  void computePose();
  void computeAges();
  void computeControls();
  void computePack();
  void computeMesh();
};

void Pipeline::Impl::build() {
  auto add = [&](Stage s, std::vector<Stage> in, void (Impl::*fn)()) {
    std::vector<StageGraph::Id> inputs;
    for (Stage i : in) inputs.push_back(id(i));
    const StageGraph::Id added = graph.add(stageName(s), inputs, [this, fn] { (this->*fn)(); });
    PTERYLA_CHECK(added == id(s), "stages are added in the order of pipeline::Stage");
  };
  add(Stage::Skin, {}, &Impl::computeSkin);
  add(Stage::Tracts, {Stage::Skin}, &Impl::computeTracts);
  add(Stage::Distribute, {Stage::Tracts}, &Impl::computeDistribute);
  add(Stage::Interpolate, {Stage::Distribute}, &Impl::computeInterpolate);
  add(Stage::Directions, {Stage::Interpolate}, &Impl::computeDirections);
  add(Stage::Pose, {Stage::Directions}, &Impl::computePose);
  add(Stage::Ages, {Stage::Pose}, &Impl::computeAges);
  add(Stage::Controls, {Stage::Ages}, &Impl::computeControls);
  add(Stage::Pack, {Stage::Controls}, &Impl::computePack);
  add(Stage::Mesh, {Stage::Pack}, &Impl::computeMesh);
}

void Pipeline::Impl::computeSkin() {
  report(progress, "load", 0);
  coat::MeshLoadOptions o;
  o.repair = scene.meshRepair;
  if (memorySkin) {
    rest = *memorySkin;
  } else {
    if (!scene.fromBareMesh && !std::filesystem::is_regular_file(scene.meshPath))
      throw Error("mesh file '" + scene.meshPath + "' " +
                      (std::filesystem::exists(scene.meshPath) ? "is not a regular file" : "does not exist"),
                  scene.file, "mesh");
    rest = coat::loadSkinMesh(scene.meshPath, o);
  }
  // Feather library: every named feather of the scene.
  library.clear();
  materialNames.clear();
  // A scene without feathers gets the bundled contour feather, as a bare mesh does.
  const Json feathers = scene.feathers.empty()
                            ? Json{{"contour", (std::filesystem::path(dataDir()) / "feathers" / "contour.json").string()}}
                            : scene.feathers;
  for (auto it = feathers.begin(); it != feathers.end(); ++it) {
    feather::FeatherParams p;
    if (it->is_string()) {
      try {
        p = feather::loadFeather(it->get<std::string>());
      } catch (const Error& e) {
        throw Error(e.detail(), e.file().empty() ? scene.file : e.file(),
                    e.file().empty() ? "feathers." + it.key() : e.element());
      }
    } else {
      JsonReader r(*it, scene.file, "feathers." + it.key());
      p = feather::readFeather(r);
      p.sourceFile = scene.file;
    }
    p.name = it.key();
    library[it.key()] = std::move(p);
    materialNames.push_back(it.key());
  }
  if (library.empty()) throw Error("the scene defines no feathers", scene.file, "feathers");
  report(progress, "load", 1);
}

void Pipeline::Impl::computeTracts() {
  tractSettings.clear();
  tracts.clear();
  // The scene's growth schedule (docs/growth.md), read with the tracts: feathers whose file and tract
  // give none grow and wear by it.
  sceneGrowth.reset();
  if (!scene.growth.empty()) {
    JsonReader g(scene.growth, scene.file, "growth");
    sceneGrowth = std::make_shared<const feather::GrowthSchedule>(feather::readGrowthSchedule(g));
  }
  std::vector<coat::Tract> earlier;
  const double meshArea = rest.totalArea();
  double plannedFollicles = 0;
  if (scene.tracts.empty()) scene.tracts = Json::array({Json{{"name", "all"}}});
  for (size_t i = 0; i < scene.tracts.size(); ++i) {
    const std::string where = "tracts[" + std::to_string(i) + "]";
    JsonReader r(scene.tracts[i], scene.file, where);
    TractSettings t;
    t.element = where;
    t.tract = coat::readTract(r, rest, earlier);
    // Names are how ordering, directions and controls refer to tracts (docs/tracts.md: unique).
    for (const coat::Tract& e : earlier)
      if (e.name == t.tract.name) r.fail("name", "duplicate tract name '" + e.name + "'");
    earlier.push_back(t.tract);
    const double area = coat::tractArea(rest, t.tract);
    if (r.has("count")) {
      t.count = static_cast<size_t>(r.integer("count", 0, 2000000));
      r.allow("density");
    } else if (r.has("density")) {
      if (!r.json().at("density").is_number()) r.fail("density", "expected a number of follicles per unit area");
      t.density = r.number("density", 0.0, 1e9);
    } else {
      r.allow("density");
      t.count = static_cast<size_t>(std::lround(kAutoCount * area / std::max(meshArea, 1e-300)));
    }
    // Memory before distributing: every follicle becomes a feather (frames, pack data, mesh).
    const double follicles = t.count ? double(t.count) : t.density * area;
    plannedFollicles += follicles;
    requireMemory(plannedFollicles * kBytesPerFollicle,
                  "the coat of about " + std::to_string(static_cast<uint64_t>(std::min(plannedFollicles, 1e18))) +
                      " follicles",
                  scene.file, where + (t.count ? ".count" : r.has("density") ? ".density" : ""));
    if (r.has("feather_scale") && r.json().at("feather_scale").is_string()) {
      if (r.string("feather_scale") != "auto") r.fail("feather_scale", "expected a positive number or \"auto\"");
      t.autoScale = true;
    } else {
      // Without a feather_scale, feathers are sized from the follicle spacing, on any mesh.
      t.autoScale = !r.has("feather_scale");
      t.featherScale = r.number("feather_scale", 1.0, 1e-6, 1e6);
    }
    t.featherSpacings = r.number("feather_spacings", t.featherSpacings, 0.1, 100.0);
    t.area = area;
    t.overlapGroup = r.string("overlap_group", "");
    if (r.has("seed")) t.seed = r.seed("seed", 0);
    t.relax.iterations = 40;
    if (r.has("relax")) {
      JsonReader rr = r.object("relax");
      t.relax.iterations = static_cast<int>(rr.integer("iterations", t.relax.iterations, 0, 100000));
      t.relax.overRelaxation = rr.number("over_relaxation", t.relax.overRelaxation, 1.0, 1.99);
      t.relax.fixBoundary = rr.boolean("fix_boundary", t.relax.fixBoundary);
      for (auto& b : rr.objects("bias")) {
        coat::BiasVector v;
        v.origin = b.vec3("at");
        v.direction = b.vec3("direction");
        v.sigma = b.number("sigma", 0.0, 0.0, 1e9);
        v.stretch = b.number("stretch", v.stretch, 1.0, 10.0);
        v.densityGain = b.number("density_gain", 0.0, 0.0, 100.0);
        b.finish();
        t.relax.bias.push_back(v);
      }
      rr.finish();
    } else {
      r.allow("relax");
    }
    if (r.has("pinned")) {
      for (auto& p : r.objects("pinned")) {
        t.pinned.push_back(p.vec3("at"));
        p.finish();
      }
    } else {
      r.allow("pinned");
    }
    t.feathers = coat::parseTractFeatherOptions(r);
    if (r.has("growth")) {
      JsonReader g = r.object("growth");
      t.growth = std::make_shared<const feather::GrowthSchedule>(feather::readGrowthSchedule(g));
    } else {
      r.allow("growth");
    }
    r.allow("moult");  // read by the time stages
    r.finish();
    tracts.push_back(t.tract);
    tractSettings.push_back(std::move(t));
  }
}

void Pipeline::Impl::computeDistribute() {
  follicles.clear();
  relaxResults.clear();
  uint64_t nextId = 0;
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    TractSettings& t = tractSettings[i];
    coat::ScatterOptions so;
    // A tract's own seed re-scatters only that tract; the others keep their follicles.
    so.seed = t.seed ? mix64(*t.seed * 0x9E37u + 0x5EED0000u) : mix64(scene.seed * 0x9E37u + i);
    so.density.uniform = t.density;
    so.count = t.count;
    so.tractIndex = static_cast<uint32_t>(i);
    so.firstId = nextId;
    // count 0 with no density: a tract of hand-placed (pinned) follicles only, e.g. flight feathers.
    coat::Follicles f = (so.count == 0 && t.density <= 0) ? coat::Follicles{} : coat::scatterFollicles(rest, t.tract, so);
    nextId += f.size() + t.pinned.size() + 1;
    for (size_t k = 0; k < t.pinned.size(); ++k)
      coat::addPinnedFollicleNear(f, rest, t.tract, t.pinned[k], static_cast<uint32_t>(i), nextId - 1 - k);
    coat::RelaxOptions ro = t.relax;
    ro.progress = [&, i](const std::string&, double fr) {
      return report(progress, "distribute", (double(i) + fr) / double(tractSettings.size()));
    };
    relaxResults.push_back(f.size() > t.pinned.size() ? coat::relaxFollicles(rest, t.tract, f, ro) : coat::RelaxResult{});
    follicles.append(f);
  }
  redistributeOverlaps(nextId);
  report(progress, "distribute", 1);
}

// Thesis 9.2.1: "if the tracts are the same feather type a more uniform distribution is typically desired.
// This can be accomplished by running the follicle distribution algorithm a second time, on only polygons
// of multiple tracts." Per overlap_group (in order of first appearance): the faces in two or more of its
// tracts lose the follicles scattered there (pinned ones stay) and get one distribution at the group's
// mean density, relaxed on those faces; each new follicle joins the group's tract whose remaining
// follicle is nearest (the tract it continues). Deterministic in the scene seed and the group's index.
void Pipeline::Impl::redistributeOverlaps(uint64_t& nextId) {
  std::vector<std::string> groups;
  for (const TractSettings& t : tractSettings)
    if (!t.overlapGroup.empty() && std::find(groups.begin(), groups.end(), t.overlapGroup) == groups.end())
      groups.push_back(t.overlapGroup);
  for (size_t g = 0; g < groups.size(); ++g) {
    std::vector<uint32_t> members;
    for (size_t i = 0; i < tractSettings.size(); ++i)
      if (tractSettings[i].overlapGroup == groups[g]) members.push_back(static_cast<uint32_t>(i));
    if (members.size() < 2) continue;
    std::vector<uint8_t> cover(rest.faceCount(), 0), isMember(tractSettings.size(), 0);
    double density = 0;
    for (uint32_t i : members) {
      isMember[i] = 1;
      const TractSettings& t = tractSettings[i];
      for (uint32_t f : t.tract.faces) cover[f] = static_cast<uint8_t>(std::min(cover[f] + 1, 2));
      density += t.density > 0 ? t.density : double(t.count) / std::max(t.area, 1e-300);
    }
    density /= double(members.size());
    coat::Tract shared;
    shared.name = groups[g] + " overlap";
    for (uint32_t f = 0; f < cover.size(); ++f)
      if (cover[f] >= 2) shared.faces.push_back(f);
    if (shared.faces.empty() || !(density > 0)) continue;
    // The group's follicles off the shared faces (and pinned ones) stay.
    coat::Follicles kept;
    kept.reserve(follicles.size());
    for (size_t k = 0; k < follicles.size(); ++k) {
      if (isMember[follicles.tract[k]] && cover[follicles.face[k]] >= 2 && !follicles.pinned[k]) continue;
      kept.push(rest, follicles.face[k], follicles.bary[k], follicles.tract[k], follicles.id[k], follicles.pinned[k]);
    }
    coat::ScatterOptions so;
    so.seed = mix64(scene.seed * 0x9E37u + 0x0E7A0000u + g);
    so.density.uniform = density;
    so.tractIndex = members[0];
    so.firstId = nextId;
    coat::Follicles fresh = coat::scatterFollicles(rest, shared, so);
    nextId += fresh.size() + 1;
    if (fresh.size() > 1) coat::relaxFollicles(rest, shared, fresh, coat::RelaxOptions{});
    // Each joins the member tract of the nearest remaining follicle (ties: the earlier tract).
    std::vector<glm::dvec3> sites;
    std::vector<uint32_t> siteTract;
    for (size_t k = 0; k < kept.size(); ++k)
      if (isMember[kept.tract[k]]) {
        sites.push_back(kept.position[k]);
        siteTract.push_back(kept.tract[k]);
      }
    for (size_t k = 0; k < fresh.size(); ++k) {
      uint32_t best = members[0];
      double bestD = std::numeric_limits<double>::infinity();
      for (size_t s = 0; s < sites.size(); ++s) {
        const double d = glm::dot(sites[s] - fresh.position[k], sites[s] - fresh.position[k]);
        if (d < bestD || (d == bestD && siteTract[s] < best)) {
          bestD = d;
          best = siteTract[s];
        }
      }
      fresh.tract[k] = best;
    }
    kept.append(fresh);
    follicles = std::move(kept);
  }
}

coat::TractParameterization Pipeline::Impl::boxParameterization(uint32_t tract) const {
  glm::dvec3 lo, hi;
  int ax[3];
  boxAxes(rest, lo, hi, ax);
  const glm::dvec3 ext = glm::max(hi - lo, glm::dvec3(1e-12));
  coat::TractParameterization p;
  p.method = coat::ParamMethod::Projection;
  p.note = "bounding-box projection (at most one key feather)";
  p.scale = ext[ax[0]];
  for (size_t f = 0; f < follicles.size(); ++f) {
    if (follicles.tract[f] != tract) continue;
    const glm::dvec3 q = (follicles.position[f] - lo) / ext;
    p.follicles.push_back(static_cast<uint32_t>(f));
    p.follicleUv.push_back({q[ax[0]], q[ax[1]]});
  }
  return p;
}

void Pipeline::Impl::computeInterpolate() {
  report(progress, "interpolate", 0);
  params.clear();
  std::vector<coat::TractKeys> keys;
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    TractSettings& t = tractSettings[i];
    try {
      params.push_back(coat::parameterizeTract(rest, t.tract, static_cast<uint32_t>(i), follicles,
                                               t.feathers.parameterization));
    } catch (const Error&) {
      // With at most one key feather nothing is interpolated, so a closed or folded tract needs no
      // real parameterization: (u,v) from the two longest axes of the mesh's bounding box.
      if (t.feathers.keys.size() > 1) throw;
      params.push_back(boxParameterization(static_cast<uint32_t>(i)));
    }
  }
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    TractSettings& t = tractSettings[i];
    coat::TractKeys k;
    k.param = &params[i];
    k.keys = coat::resolveKeyFeathers(follicles, params[i], t.feathers.keys, library, t.tract.name, t.feathers.feather,
                                      scene.file);
    k.scaleJitter = t.feathers.scaleJitter;
    keys.push_back(std::move(k));
  }
  coatRest = coat::CoatFeathers{};
  coat::InterpolateOptions io;
  io.seed = scene.seed;
  coat::interpolateCoatFeathers(follicles, keys, library, io, coatRest);
  // Tract-level feather scale (explicit, or automatic from the follicle spacing).
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    const TractSettings& t = tractSettings[i];
    double s = t.featherScale;
    if (t.autoScale && i < relaxResults.size() && relaxResults[i].spacing > 0) {
      double len = 0;
      size_t n = 0;
      for (size_t f = 0; f < coatRest.size(); ++f)
        if (coatRest.tract[f] == i) { len += coatRest.params[f].totalLength(); ++n; }
      if (n && len > 0) s = t.featherSpacings * relaxResults[i].spacing / (len / double(n));
    }
    if (s != 1.0)
      for (size_t f = 0; f < coatRest.size(); ++f)
        if (coatRest.tract[f] == i) coat::scaleFeather(coatRest.params[f], s);
  }
  // Growth schedules: the tract's, else the feather file's, else the scene's (else the default).
  for (size_t f = 0; f < coatRest.size(); ++f) {
    const uint32_t t = coatRest.tract[f];
    if (t < tractSettings.size() && tractSettings[t].growth) coatRest.params[f].growth = tractSettings[t].growth;
    else if (!coatRest.params[f].growth) coatRest.params[f].growth = sceneGrowth;
  }
  // Memory of the coat's geometry before packing and meshing it: barbs on both vanes (and afterfeathers)
  // at the current level of detail, about kTrianglesPerBarb triangles each.
  double triangles = 0;
  size_t largest = 0;
  double largestBarbs = 0;
  for (size_t f = 0; f < coatRest.size(); ++f) {
    double barbs = 0;
    for (const feather::FeatherParams* p = &coatRest.params[f]; p; p = p->afterfeather.get())
      barbs += 2.0 * p->rachisLength / std::max(std::min(p->spacingBase, p->spacingTip), 1e-300);
    if (barbs > largestBarbs) { largestBarbs = barbs; largest = f; }
    triangles += barbs * kTrianglesPerBarb * lod;
  }
  if (!coatRest.params.empty()) {
    const std::string name = coatRest.params[largest].name;
    requireMemory(triangles * kBytesPerTriangle,
                  "the coat's geometry (about " + std::to_string(static_cast<uint64_t>(std::min(triangles, 1e18))) +
                      " triangles; up to " + std::to_string(static_cast<uint64_t>(std::min(largestBarbs, 1e18))) +
                      " barbs per feather)",
                  scene.file, name.empty() ? "feathers" : "feathers." + name);
  }
  report(progress, "interpolate", 1);
}

// Directions and ordering are read here, not with the tracts, so editing them re-orients and
// repacks without re-relaxing follicles.
void Pipeline::Impl::computeDirections() {
  directionOptions = coat::DirectionOptions{};
  orderOptions = coat::OrderOptions{};
  if (scene.fromBareMesh) {
    // Any mesh with one command: feathers flow along the longest bounding-box axis and are layered
    // along it (roof tiles from the far end).
    glm::dvec3 lo, hi;
    int ax[3];
    boxAxes(rest, lo, hi, ax);
    glm::dvec3 a = 0.5 * (lo + hi), b = a;
    a[ax[0]] = lo[ax[0]];
    b[ax[0]] = hi[ax[0]];
    directionOptions.field.axis = {a, b};
    orderOptions.method = coat::OrderMethod::Axis;
    orderOptions.axis = {a, b};
  }
  if (!scene.directions.empty()) {
    JsonReader r(scene.directions, scene.file, "directions");
    directionOptions = coat::parseDirections(r);
  }
  if (!scene.ordering.empty()) {
    JsonReader r(scene.ordering, scene.file, "ordering");
    orderOptions = coat::parseOrdering(r);
  } else if (!scene.directions.empty() && directionOptions.field.axis.size() >= 2) {
    // A scene that gives a body axis and no ordering is layered along that axis (roof tiles from the tail).
    orderOptions.method = coat::OrderMethod::Axis;
    orderOptions.axis = directionOptions.field.axis;
  }
  ++restGeneration;
  directions = coat::computeSurfaceDirections(rest, tracts, follicles, directionOptions);
  coat::evaluateFrames(rest, follicles, directions, coatRest);
  try {
    coat::orderLayers(rest, tracts, params, follicles, directions, orderOptions, coatRest);
  } catch (const Error& e) {
    throw e.withFile(scene.file);  // "ordering.tracts[2]" is a key of the scene
  }
}

void Pipeline::Impl::computePose() {
  timeState.generation = restGeneration;
  if (!skinPose.empty()) {
    // The caller's pose (setSkinPose) replaces the skeleton's. Checked against the rest skin again here:
    // a scene edit may have changed the mesh since it was set.
    if (skinPose.size() != rest.positions.size())
      throw Error("the skin pose has " + std::to_string(skinPose.size()) + " vertices, the skin " +
                      std::to_string(rest.positions.size()),
                  scene.file, "pose");
    posed = rest;
    posed.positions = skinPose;
    coat::recomputeGeometry(posed);
    timeState.rest = &rest;
    timeState.posedMoved = true;
    posedGeneration = 0;
  } else {
    // poseSkin wants `posed` as a copy of `rest` and touches it only when the pose moves the skin.
    if (posedGeneration != restGeneration) posed = rest;
    poseSkin(scene, time, rest, posed, timeState);
    posedGeneration = timeState.posedMoved ? 0 : restGeneration;
  }
  posedFollicles = follicles;
  coat::updateFollicleGeometry(posed, posedFollicles);
  // Rest data (params, follicles, layer order) is copied once per rest state; the time stages rewrite
  // frames, ages and presence every frame.
  if (coatNowGeneration != restGeneration) {
    coatNow = coatRest;
    coatNowGeneration = restGeneration;
  }
  coat::evaluateFrames(posed, posedFollicles, directions, coatNow);
}

void Pipeline::Impl::computeAges() {
  coatNow.age.assign(coatNow.size(), 1.0);
  coatNow.present.assign(coatNow.size(), 1);
  featherAges(scene, time, params, posedFollicles, timeState, coatNow);
}

// Packing options (and their styling selections) are read here so a packing edit only repacks.
void Pipeline::Impl::computeControls() {
  packOptions = coat::PackOptions{};
  if (!scene.packing.empty()) {
    JsonReader r(scene.packing, scene.file, "packing");
    packOptions = coat::parsePackOptions(r);
  }
  fixedElevation.assign(coatNow.size(), std::nan(""));
  if (!packOptions.styling.empty()) {
    try {
      fixedElevation = coat::applyStyling(coatNow, packOptions.styling, fixedElevation).fixedElevation;
    } catch (const Error& e) {
      if (!e.file().empty()) throw;
      throw Error(e.detail(), scene.file, "packing." + e.element());  // "styling[0].ids[3]" is under packing
    }
  }
  // The caller's fixed elevations win over styling; expressive controls still raise on top of them.
  if (!hostElevations.empty())
    for (size_t i = 0; i < coatNow.size(); ++i)
      if (auto it = hostElevations.find(follicles.id[coatNow.follicle[i]]); it != hostElevations.end())
        fixedElevation[i] = it->second;
  applyControls(scene, time, posed, posedFollicles, timeState, coatNow, fixedElevation);
}

void Pipeline::Impl::computePack() {
  report(progress, "pack", 0);
  coat::PackOptions o = packOptions;
  o.fixedElevation = fixedElevation;
  // A growing feather is packed with its barbs (age 1 for the packer) as it will be meshed: once its
  // shaft is full grown, as grown at its age (the packer sees its barb lengths, angles and opening, and
  // computeMesh meshes the packed grown parameters as they are); while its shaft still grows, as the
  // mature feather, grown afterwards (a prefix of the packed shaft, barbs closed and short). Straight
  // shafts of the mature feather (the packer's age < opening_age rule) let opening barbs reach into
  // the skin, and a short grown shaft's thin footprint finds no skin to pack against.
  bool anyGrowing = false;
  for (size_t i = 0; i < coatNow.size() && !anyGrowing; ++i) anyGrowing = coatNow.present[i] && coatNow.age[i] < 1.0;
  const coat::CoatFeathers* packInput = &coatNow;
  packGrownAge.clear();
  if (anyGrowing) {
    packGrownAge.assign(coatNow.size(), 1.0);
    packCoat = coatNow;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, packCoat.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t i = range.begin(); i < range.end(); ++i)
        if (packCoat.present[i] && packCoat.age[i] < 1.0) {
          const feather::GrowthSchedule& schedule = feather::growthScheduleOf(coatNow.params[i]);
          if (packedAsGrown(packCoat.age[i], schedule)) {
            packCoat.params[i] = feather::featherAtAge(coatNow.params[i], coatNow.age[i], schedule);
            packGrownAge[i] = coatNow.age[i];
          }
          packCoat.age[i] = 1.0;
        }
    });
    packInput = &packCoat;
  }
  if (o.method == coat::PackMethod::Drape) {
    // Laid by the mesh stage (computeMesh drapes the flat coat): every feather meshed flat, unpacked.
    flatPack = coat::PackResult{};
    flatPack.order = coatNow.layerOrder;
    flatPack.elevation.assign(coatNow.size(), 0.0);
    flatPack.stats.packed = coatNow.layerOrder.size();
    packed = &flatPack;
    packedCoat = &coatNow;
  } else if (o.moultOver && moulting(coatNow)) {
    // A moult frame: the mature coat is packed as a frame without a moult would be, and the lost and
    // growing feathers are packed over it (docs/moult.md). With "moult_pack": "full" the frame is
    // repacked like any other (below).
    packed = &packMoultFrame(scene, posed, matureCoat(coatNow, timeState), *packInput, o, timeState, packGrownAge);
    packedCoat = packInput;
  } else {
    // Repacks incrementally from the last frame's pack or this frame's natural pack when it can.
    packed = &packFrame(scene, posed, *packInput, o, timeState, packGrownAge);
    packedCoat = packInput;
  }
  report(progress, "pack", 1);
}

void Pipeline::Impl::computeMesh() {
  report(progress, "mesh", 0);
  CoatMeshInput in;
  in.coat = &coatNow;
  in.packedCoat = packedCoat;
  in.packed = packed;
  in.lod = lod;
  in.featherLods = &featherLods;
  mesher.update(in, mesh.mesh);
  drape = coat::DrapeResult{};
  if (packOptions.method == coat::PackMethod::Drape) {
    mesher.keepIndices(mesh.mesh);
    coat::DrapeOptions dopt;
    dopt.gap = packOptions.clearance;
    dopt.maxSlope = std::tan(packOptions.drapeMaxSlopeDeg * feather::kPi / 180.0);
    dopt.threads = packOptions.threads;
    dopt.baseAllowance = packOptions.baseAllowance;
    drape = coat::drapeCoatMesh(posed, coatNow, mesh.mesh, dopt);
  }
  const std::vector<uint32_t>& which = mesher.feathers();
  const std::vector<feather::FeatherMeshRanges>& ranges = mesher.ranges();
  mesh.ranges.clear();
  mesh.ranges.reserve(ranges.size());
  std::map<std::string, uint32_t> matIndex;
  for (size_t k = 0; k < materialNames.size(); ++k) matIndex[materialNames[k]] = static_cast<uint32_t>(k);
  for (size_t k = 0; k < ranges.size(); ++k) {
    const uint32_t i = which[k];
    const auto& r = ranges[k];
    CoatDrawRange d;
    d.feather = i;
    const uint32_t first = r.shaftFirst;
    const uint32_t end = std::max({r.shaftFirst + r.shaftCount, r.leftFirst + r.leftCount, r.rightFirst + r.rightCount,
                                   r.afterFirst + r.afterCount});
    d.firstIndex = first;
    d.indexCount = end - first;
    d.partCount[0] = r.shaftCount;
    d.partCount[1] = r.leftCount;
    d.partCount[2] = r.rightCount;
    d.partCount[3] = r.afterCount;
    const auto it = matIndex.find(coatNow.params[i].name);
    d.material = it == matIndex.end() ? 0 : it->second;
    const coat::FeatherFrame& fr = coatNow.frames[i];
    const auto pl = feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, packed->elevation[i]);
    d.origin = glm::vec3(fr.origin);
    d.axisX = glm::vec3(pl.x);
    d.axisY = glm::vec3(pl.y);
    mesh.ranges.push_back(d);
  }
  mesh.materials.clear();
  for (const auto& name : materialNames) {
    const feather::FeatherParams& p = library.at(name);
    CoatMaterial m;
    m.name = name;
    auto resolve = [&](const std::string& t) { return t.empty() ? t : resolveRelative(p.sourceFile, t); };
    m.texture = resolve(p.material.texture);
    m.alphaTexture = resolve(p.material.alphaTexture);
    m.pattern = p.material.pattern;
    if (p.material.baseColor) m.baseColor = glm::vec3(*p.material.baseColor);
    m.uv = p.material.uv;
    mesh.materials.push_back(m);
  }
  report(progress, "mesh", 1);
}

Pipeline::Pipeline(Scene scene, ProgressFn progress) : impl_(std::make_unique<Impl>()) {
  impl_->scene = std::move(scene);
  impl_->progress = std::move(progress);
  impl_->time = impl_->scene.time;
  impl_->lod = impl_->scene.render.lod;
  impl_->build();
}

Pipeline::Pipeline(Scene scene, coat::SkinMesh skin, ProgressFn progress) : Pipeline(std::move(scene), std::move(progress)) {
  impl_->memorySkin = std::move(skin);
}

Pipeline::~Pipeline() = default;

const Scene& Pipeline::scene() const { return impl_->scene; }
void Pipeline::editScene(Stage from, const std::function<void(Scene&)>& edit) {
  edit(impl_->scene);
  invalidate(from);
}
void Pipeline::invalidate(Stage from) { impl_->graph.invalidate(impl_->id(from)); }
void Pipeline::setProgress(ProgressFn progress) { impl_->progress = std::move(progress); }

// Whether the time stages read the time (poseSkin: a skeleton; featherAges: a moult; applyControls:
// controls). Conservative: any such section counts, even one that turns out to be disabled.
namespace {
bool timeMatters(const Scene& scene) {
  auto nonEmpty = [](const Json& j) { return !j.is_null() && !(j.is_object() && j.empty()) && !(j.is_array() && j.empty()); };
  if (nonEmpty(scene.skeleton) || nonEmpty(scene.controls) || nonEmpty(scene.moult)) return true;
  for (const Json& t : scene.tracts)
    if (t.is_object() && t.contains("moult") && t.at("moult") != Json(false)) return true;
  return false;
}
}  // namespace

void Pipeline::setTime(double t) {
  if (!std::isfinite(t)) throw Error("time must be a finite number", "", "--time");
  if (t == impl_->time) return;
  impl_->time = t;
  // Only stages that depend on time: the skin pose and everything after it, and only when something in
  // the scene reads the time. A scene with no skeleton, moult or controls is the same coat at every
  // time, so scrubbing its timeline (a host's frame change) costs nothing.
  if (timeMatters(impl_->scene)) impl_->graph.invalidate(impl_->id(Stage::Pose));
}
double Pipeline::time() const { return impl_->time; }

void checkSkinPose(const coat::SkinMesh& rest, const std::vector<glm::dvec3>& positions) {
  const size_t n = rest.positions.size();
  if (positions.size() != n)
    throw Error("the pose has " + std::to_string(positions.size()) + " vertices; the skin has " + std::to_string(n) +
                    " (a pose keeps the skin's topology)",
                "", "pose");
  for (size_t v = 0; v < n; ++v)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(positions[v][c]) || std::abs(positions[v][c]) > coat::kMaxMeshCoordinate)
        throw Error("coordinate " + std::to_string(c) + " is " + std::to_string(positions[v][c]) +
                        ": pose coordinates must be finite and at most " + std::to_string(coat::kMaxMeshCoordinate) +
                        " in magnitude",
                    "", "vertex " + std::to_string(v));
}

void Pipeline::setSkinPose(std::vector<glm::dvec3> positions) {
  if (!positions.empty()) checkSkinPose(restSkin(), positions);
  if (positions == impl_->skinPose) return;
  impl_->skinPose = std::move(positions);
  impl_->graph.invalidate(impl_->id(Stage::Pose));
}
const std::vector<glm::dvec3>& Pipeline::skinPose() const { return impl_->skinPose; }

void Pipeline::setFixedElevations(std::map<uint64_t, double> elevations) {
  for (const auto& [id, e] : elevations)
    if (!std::isfinite(e) || e < 0 || e > feather::kPi / 2)
      throw Error("elevation " + std::to_string(e) + " is not in [0, pi/2] radians", "",
                  "follicle " + std::to_string(id));
  if (elevations == impl_->hostElevations) return;
  impl_->hostElevations = std::move(elevations);
  impl_->graph.invalidate(impl_->id(Stage::Controls));
}
const std::map<uint64_t, double>& Pipeline::fixedElevations() const { return impl_->hostElevations; }

void Pipeline::setLod(double f) {
  if (!(f > 0 && f <= 1)) throw Error("level of detail must be in (0, 1]", "", "lod");
  if (f == impl_->lod) return;
  impl_->lod = f;
  impl_->graph.invalidate(impl_->id(Stage::Mesh));
}
double Pipeline::lod() const { return impl_->lod; }

void Pipeline::setFeatherLods(std::vector<double> fractions) {
  for (size_t i = 0; i < fractions.size(); ++i)
    if (!(fractions[i] > 0 && fractions[i] <= 1))
      throw Error("per-feather level of detail must be in (0, 1], got " + std::to_string(fractions[i]), "",
                  "feather " + std::to_string(i));
  if (fractions == impl_->featherLods) return;
  impl_->featherLods = std::move(fractions);
  impl_->graph.invalidate(impl_->id(Stage::Mesh));
}
const std::vector<double>& Pipeline::featherLods() const { return impl_->featherLods; }

const coat::SkinMesh& Pipeline::restSkin() {
  impl_->graph.pull(impl_->id(Stage::Skin));
  return impl_->rest;
}
const coat::SkinMesh& Pipeline::posedSkin() {
  impl_->graph.pull(impl_->id(Stage::Pose));
  return impl_->posed;
}
const std::vector<coat::Tract>& Pipeline::tracts() {
  impl_->graph.pull(impl_->id(Stage::Tracts));
  return impl_->tracts;
}
const coat::Follicles& Pipeline::follicles() {
  impl_->graph.pull(impl_->id(Stage::Distribute));
  return impl_->follicles;
}
const coat::CoatFeathers& Pipeline::feathers() {
  impl_->graph.pull(impl_->id(Stage::Pack));
  return impl_->coatNow;
}
const std::vector<double>& Pipeline::elevations() {
  impl_->graph.pull(impl_->id(Stage::Pack));
  return impl_->packed->elevation;
}
const CoatMesh& Pipeline::coatMesh() {
  impl_->graph.pull(impl_->id(Stage::Mesh));
  return impl_->mesh;
}
TriMesh Pipeline::skinTriMesh() { return coat::toTriMesh(posedSkin()); }

QualityMetrics Pipeline::check() {
  QualityMetrics m;
  // Progress "check" over its parts: the tracts' distribution to 10%, the checker (pairs, skin,
  // coverage) to 75%, then the proxy coats' pair counts. A callback returning false stops it: the
  // metrics not computed yet stay empty.
  bool stopped = false;
  auto part = [&](double lo, double hi) -> ProgressFn {
    return [this, lo, hi, &stopped](const std::string&, double x) {
      if (!report(impl_->progress, "check", lo + (hi - lo) * x)) stopped = true;
      return !stopped;
    };
  };
  const auto& f = follicles();
  m.follicles = f.size();
  double hexSum = 0, cvSum = 0;
  size_t interior = 0;
  const ProgressFn tractsDone = part(0, 0.1);
  if (!tractsDone("check", 0)) return m;
  for (size_t i = 0; i < impl_->tracts.size(); ++i) {
    const auto d = coat::measureDistribution(impl_->rest, impl_->tracts[i], f);
    hexSum += d.hexFraction * double(d.interior);
    cvSum += d.nnCv * double(d.interior);
    interior += d.interior;
    if (!tractsDone("check", double(i + 1) / double(impl_->tracts.size()))) return m;
  }
  if (interior > 0) {
    m.hexFraction = hexSum / double(interior);
    m.nnCv = cvSum / double(interior);
  }
  const auto& coat = feathers();
  size_t present = 0;
  for (auto p : coat.present) present += p ? 1 : 0;
  m.feathers = present;
  const bool draped = impl_->packOptions.method == coat::PackMethod::Drape;
  // The independent checker (coat/check.hpp) on the coat at full geometry, and on the same coat before
  // packing: every feather at the packed coat's median elevation with its unpacked key barbs.
  const double savedLod = impl_->lod;
  setLod(1.0);
  const TriMesh& full = coatMesh().mesh;
  std::vector<uint32_t> tractFaces;
  for (const auto& t : impl_->tracts) tractFaces.insert(tractFaces.end(), t.faces.begin(), t.faces.end());
  std::sort(tractFaces.begin(), tractFaces.end());
  tractFaces.erase(std::unique(tractFaces.begin(), tractFaces.end()), tractFaces.end());
  coat::CheckOptions co;
  co.seed = impl_->scene.seed;
  co.attribute = true;  // which feathers intersect or penetrate (the counts are the same either way)
  co.progress = part(0.1, 0.75);
  coat::setFeatherBases(co, impl_->coatNow, impl_->packOptions.baseAllowance);
  const coat::CheckResult r = coat::check(impl_->posed, tractFaces, full, co);
  if (!r.complete) {
    setLod(savedLod);
    return m;
  }
  m.intersectingPairs = r.intersectingPairs;
  m.skinPenetrations = r.skinPenetrations;
  m.coverage = r.coverage;
  for (const coat::FeatherPairCount& p : r.featherPairs) {
    m.intersectingFeathers.push_back(p.a);
    m.intersectingFeathers.push_back(p.b);
  }
  std::sort(m.intersectingFeathers.begin(), m.intersectingFeathers.end());
  m.intersectingFeathers.erase(std::unique(m.intersectingFeathers.begin(), m.intersectingFeathers.end()),
                               m.intersectingFeathers.end());
  m.penetratingFeathers = r.penetratingFeathers;
  // How steeply feathers rise: the packed elevations, or for a draped coat its rise over the skin.
  const std::vector<double>& elevation = draped ? impl_->drape.elevation : impl_->packed->elevation;
  std::vector<double> el;
  for (size_t i = 0; i < impl_->coatNow.size(); ++i)
    if (impl_->coatNow.present[i] && i < elevation.size()) el.push_back(elevation[i] * 180.0 / feather::kPi);
  if (!el.empty()) {
    std::sort(el.begin(), el.end());
    m.elevationP50 = el[el.size() / 2];
    m.elevationP90 = el[std::min(el.size() - 1, el.size() * 9 / 10)];
  }
  if (draped) {
    m.fixedFeathers = impl_->drape.stats.trimmedFeathers;
    m.hiddenFeathers = impl_->drape.stats.hiddenFeathers;
  }
  if (!draped) {
    const TriMesh packedProxy = coat::proxyCoatMesh(impl_->coatNow, impl_->packed->elevation,
                                                    coat::allPackedParams(*impl_->packedCoat, *impl_->packed));
    m.intersectingPairsProxy = coat::countIntersectingPairs(packedProxy, part(0.75, 0.85));
    if (!m.intersectingPairsProxy) {
      setLod(savedLod);
      return m;
    }
  }
  // The unpacked coat, from the input alone: every feather at kUnpackedElevationDeg with its own key barbs.
  const std::vector<double> flat(impl_->coatNow.size(), kUnpackedElevationDeg * feather::kPi / 180.0);
  TriMesh unpacked = coat::proxyCoatMesh(impl_->coatNow, flat, impl_->coatNow.params);
  Impl& im = *impl_;
  if (im.lastUnpackedPairs && unpacked.positions == im.lastUnpacked.positions &&
      unpacked.indices == im.lastUnpacked.indices && unpacked.featherId == im.lastUnpacked.featherId) {
    m.intersectingPairsUnpacked = im.lastUnpackedPairs;
    report(impl_->progress, "check", 1);
  } else {
    m.intersectingPairsUnpacked = coat::countIntersectingPairs(unpacked, part(draped ? 0.75 : 0.85, 1));
    im.lastUnpackedPairs = m.intersectingPairsUnpacked;
    im.lastUnpacked = std::move(unpacked);
  }
  setLod(savedLod);
  return m;
}

double Pipeline::timeFullPack(int repeats) {
  elevations();  // the pack stage has run: its inputs are this frame's
  Impl& m = *impl_;
  coat::PackOptions o = m.packOptions;
  o.fixedElevation = m.fixedElevation;
  const coat::CoatFeathers& c = m.timeState.packReport.moult ? m.timeState.mature : (m.packGrownAge.empty() ? m.coatNow : m.packCoat);
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(1, repeats); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const coat::PackResult result = coat::pack(m.posed, c, o);
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

FrameReuse Pipeline::frameReuse() const {
  FrameReuse r;
  const PackReport& p = impl_->timeState.packReport;
  r.naturalPacked = impl_->timeState.controlResult.naturalPacked;
  r.naturalIncremental = p.naturalIncremental;
  r.naturalChanged = p.naturalChanged;
  r.naturalRecomputed = p.naturalRecomputed;
  r.packIncremental = p.finalIncremental;
  r.packChanged = p.finalChanged;
  r.packRecomputed = p.finalRecomputed;
  r.moult = p.moult;
  r.moultChanged = p.moultChanged;
  r.moultRecomputed = p.moultRecomputed;
  r.meshRegenerated = impl_->mesher.regenerated();
  r.meshReused = impl_->mesher.reused();
  return r;
}

uint64_t Pipeline::evaluations(Stage s) const { return impl_->graph.evaluations(Impl::id(s)); }
bool Pipeline::dirty(Stage s) const { return impl_->graph.dirty(Impl::id(s)); }
double Pipeline::lastSeconds(Stage s) const { return impl_->graph.lastSeconds(Impl::id(s)); }
double Pipeline::stageSeconds(Stage s) const { return impl_->graph.totalSeconds(impl_->id(s)); }
void Pipeline::resetTimings() { impl_->graph.resetTimings(); }

}  // namespace pteryla::pipeline
