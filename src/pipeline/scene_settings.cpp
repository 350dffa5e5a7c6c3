// The scene's module sections as typed settings (scene_settings.hpp): each section is read here by its
// module's parser (docs/scene-format.md), once per change of its section.
#include "scene_settings.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "scene_sections.hpp"

namespace pteryla::pipeline {

InputKey& InputKey::add(std::initializer_list<uint64_t> parts) {
  for (uint64_t p : parts) {
    PTERYLA_CHECK(size_ < kCapacity, "an InputKey holds at most 8 revisions");
    parts_[size_++] = p;
  }
  return *this;
}

InputKey& InputKey::add(const InputKey& other) {
  for (size_t i = 0; i < other.size_; ++i) add({other.parts_[i]});
  return *this;
}

namespace {

// Follicles of a tract with neither count nor density, times its share of the mesh area: 3,000 lets the
// small parts of real meshes (fingers, ears, fins) carry their own feathers (issue #22, docs/packing.md).
constexpr size_t kAutoCount = 3000;
// Memory estimates checked against the ceiling (core/limits.hpp, docs/limits.md). Lower bounds from the
// bird (3152 feathers, 1.29 M triangles at lod 0.6: 775 MB peak), so no scene that fits is refused.
constexpr double kBytesPerFollicle = 32e3;

constexpr size_t kSections = size_t(Section::Packing) + 1;

// The scene's key and sub-key of each section (its row of sectionStages()).
const SectionStage& rowOf(Section s) {
  static const std::array<const SectionStage*, kSections> rows = [] {
    const std::array<std::pair<const char*, const char*>, kSections> names = {{{"tracts", ""},
                                                                               {"tracts", "moult"},
                                                                               {"growth", ""},
                                                                               {"directions", ""},
                                                                               {"ordering", ""},
                                                                               {"skeleton", ""},
                                                                               {"moult", ""},
                                                                               {"controls", ""},
                                                                               {"packing", ""}}};
    std::array<const SectionStage*, kSections> out{};
    for (size_t i = 0; i < kSections; ++i) {
      for (const SectionStage& row : sectionStages())
        if (std::strcmp(row.key, names[i].first) == 0 && std::strcmp(row.subKey, names[i].second) == 0) out[i] = &row;
      PTERYLA_CHECK(out[i], "every typed section has a row in sectionStages()");
    }
    return out;
  }();
  return *rows[static_cast<size_t>(s)];
}

bool nonEmpty(const Json& j) { return !j.is_null() && !(j.is_object() && j.empty()) && !(j.is_array() && j.empty()); }

std::string tractName(const Scene& scene, size_t i) {
  if (i < scene.tracts.size() && scene.tracts[i].is_object()) {
    const auto it = scene.tracts[i].find("name");
    if (it != scene.tracts[i].end() && it->is_string()) return it->get<std::string>();
  }
  return {};
}

// Per tract: the scene's "moult" overridden by the tract's own "moult" (an object of overrides, or
// true/false); nullopt when the tract does not moult.
std::vector<std::optional<moult::MoultOptions>> parseMoult(const Scene& scene) {
  std::vector<std::optional<moult::MoultOptions>> out(scene.tracts.size(), std::nullopt);
  std::optional<moult::MoultOptions> defaults;
  if (!scene.moult.empty()) {
    JsonReader r(scene.moult, scene.file, "moult");
    defaults = moult::readMoultOptions(r);
  }
  for (size_t i = 0; i < scene.tracts.size(); ++i) {
    const Json& t = scene.tracts[i];
    const Json sec = t.is_object() && t.contains("moult") ? t.at("moult") : Json();
    const std::string where = "tracts[" + std::to_string(i) + "].moult";
    if (sec.is_null()) {
      out[i] = defaults;
    } else if (sec.is_boolean()) {
      if (sec.get<bool>()) out[i] = defaults ? *defaults : moult::MoultOptions{};
    } else if (sec.is_object()) {
      JsonReader r(sec, scene.file, where);
      out[i] = moult::readMoultOptions(r, defaults ? *defaults : moult::MoultOptions{});
    } else {
      throw Error("expected a moult object (overrides of the scene's \"moult\") or true/false", scene.file, where);
    }
    if (out[i] && !out[i]->enabled) out[i].reset();
  }
  return out;
}

// A tract's "removed_follicles" (docs/scene-format.md): follicle ids, each a non-negative integer; sorted
// and unique. Ids the distribution does not make are ignored (an earlier tract's count changed, say).
std::vector<uint64_t> readRemovedFollicles(JsonReader& r) {
  std::vector<uint64_t> out;
  if (!r.has("removed_follicles")) {
    r.allow("removed_follicles");
    return out;
  }
  const Json& list = r.raw("removed_follicles");
  if (!list.is_array()) r.fail("removed_follicles", "expected an array of follicle ids");
  out.reserve(list.size());
  for (size_t k = 0; k < list.size(); ++k) {
    const Json& v = list[k];
    const bool ok = v.is_number_unsigned() || (v.is_number_integer() && v.get<int64_t>() >= 0);
    if (!ok)
      throw Error("expected a follicle id (a non-negative integer), got " + v.dump(), r.file(),
                  r.pathOf("removed_follicles") + "[" + std::to_string(k) + "]");
    out.push_back(v.get<uint64_t>());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Every tract's settings (docs/tracts.md) on the rest skin: the faces it covers, its follicle count or
// density (checked against the memory ceiling), feather scale, relaxation, pinned and removed follicles,
// key feathers and growth. Its "moult" is read by parseMoult.
std::vector<TractSettings> parseTracts(const Scene& scene, const coat::SkinMesh& rest) {
  std::vector<TractSettings> out;
  std::vector<coat::Tract> earlier;
  const double meshArea = rest.totalArea();
  double plannedFollicles = 0;
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
    requireMemory(
        plannedFollicles * kBytesPerFollicle,
        "the coat of about " + std::to_string(static_cast<uint64_t>(std::min(plannedFollicles, 1e18))) + " follicles",
        scene.file,
        where + (t.count            ? ".count"
                 : r.has("density") ? ".density"
                                    : ""));
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
    t.removed = readRemovedFollicles(r);
    t.feathers = coat::parseTractFeatherOptions(r);
    if (r.has("growth")) {
      JsonReader g = r.object("growth");
      t.growth = std::make_shared<const feather::GrowthSchedule>(feather::readGrowthSchedule(g));
    } else {
      r.allow("growth");
    }
    r.allow("moult");  // read by the time stages
    r.finish();
    out.push_back(std::move(t));
  }
  return out;
}

ControlSettings parseControls(const Scene& scene) {
  ControlSettings out;
  if (scene.controls.empty()) return out;
  out.controls = moult::readControls(scene.controls, scene.file, "controls");
  out.tracts.assign(out.controls.size(), {});
  for (size_t c = 0; c < out.controls.size(); ++c) {
    const auto& wanted = out.controls[c].tracts;
    for (size_t k = 0; k < wanted.size(); ++k) {
      bool found = false;
      for (size_t i = 0; i < scene.tracts.size(); ++i)
        if (tractName(scene, i) == wanted[k]) {
          out.tracts[c].push_back(static_cast<uint32_t>(i));
          found = true;
        }
      if (!found)
        throw Error("unknown tract '" + wanted[k] + "'", scene.file,
                    "controls[" + std::to_string(c) + "].tracts[" + std::to_string(k) + "]");
    }
  }
  return out;
}

// The cached value of `p` when it was made from `key`, else `parse()` stored under `key`. A parse that
// throws leaves `p` empty, so the error is raised again by the next read.
template <class T, class P, class Parse>
const T& cached(P& p, const InputKey& key, Parse&& parse) {
  if (p.key.empty() || p.key != key) {
    p.key = InputKey{};
    p.value = parse();
    p.key = key;
  }
  return p.value;
}

}  // namespace

void SceneSettings::update(const Scene& scene) {
  const Json sections = {{"tracts", scene.tracts},     {"growth", scene.growth},     {"directions", scene.directions},
                         {"ordering", scene.ordering}, {"skeleton", scene.skeleton}, {"moult", scene.moult},
                         {"controls", scene.controls}, {"packing", scene.packing}};
  for (size_t i = 0; i < kSections; ++i) {
    Json value = sectionValue(sections, rowOf(Section(i)));
    if (updated_ && value == value_[i]) continue;
    value_[i] = std::move(value);
    revision_[i] = ++nextRevision_;
  }
  updated_ = true;
  readsTime_ = nonEmpty(scene.skeleton) || nonEmpty(scene.controls) || nonEmpty(scene.moult);
  for (const Json& t : scene.tracts)
    if (t.is_object() && t.contains("moult") && t.at("moult") != Json(false)) readsTime_ = true;
}

const std::vector<TractSettings>& SceneSettings::tracts(const Scene& scene, const coat::SkinMesh& rest,
                                                        uint64_t restRevision) {
  return cached<std::vector<TractSettings>>(tracts_, {revision(Section::Tracts), restRevision},
                                            [&] { return parseTracts(scene, rest); });
}

const coat::PackingSettings& SceneSettings::packing(const Scene& scene) {
  return cached<coat::PackingSettings>(packing_, packingKey(), [&] {
    if (scene.packing.empty()) return coat::PackingSettings{};
    JsonReader r(scene.packing, scene.file, "packing");
    return coat::parsePackingSettings(r);
  });
}

const std::vector<std::optional<moult::MoultOptions>>& SceneSettings::moult(const Scene& scene) {
  return cached<std::vector<std::optional<moult::MoultOptions>>>(moult_, moultKey(), [&] { return parseMoult(scene); });
}

const ControlSettings& SceneSettings::controls(const Scene& scene) {
  return cached<ControlSettings>(controls_, controlsKey(), [&] { return parseControls(scene); });
}

const moult::SkinRig* SceneSettings::skeleton(const Scene& scene, size_t vertexCount) {
  const auto& rig = cached<std::optional<moult::SkinRig>>(skeleton_, skeletonKey(vertexCount), [&] {
    std::optional<moult::SkinRig> out;
    if (!scene.skeleton.empty()) {
      JsonReader r(scene.skeleton, scene.file, "skeleton");
      out = moult::readSkinRig(r, vertexCount);
    }
    return out;
  });
  return rig ? &*rig : nullptr;
}

std::shared_ptr<const feather::GrowthSchedule> SceneSettings::growth(const Scene& scene) {
  return cached<std::shared_ptr<const feather::GrowthSchedule>>(
      growth_, {revision(Section::Growth)}, [&]() -> std::shared_ptr<const feather::GrowthSchedule> {
        if (scene.growth.empty()) return nullptr;
        JsonReader g(scene.growth, scene.file, "growth");
        return std::make_shared<const feather::GrowthSchedule>(feather::readGrowthSchedule(g));
      });
}

const coat::DirectionOptions* SceneSettings::directions(const Scene& scene) {
  const auto& d = cached<std::optional<coat::DirectionOptions>>(
      directions_, {revision(Section::Directions)}, [&]() -> std::optional<coat::DirectionOptions> {
        if (scene.directions.empty()) return std::nullopt;
        JsonReader r(scene.directions, scene.file, "directions");
        return coat::parseDirections(r);
      });
  return d ? &*d : nullptr;
}

const coat::OrderOptions* SceneSettings::ordering(const Scene& scene) {
  const auto& o = cached<std::optional<coat::OrderOptions>>(ordering_, {revision(Section::Ordering)},
                                                            [&]() -> std::optional<coat::OrderOptions> {
                                                              if (scene.ordering.empty()) return std::nullopt;
                                                              JsonReader r(scene.ordering, scene.file, "ordering");
                                                              return coat::parseOrdering(r);
                                                            });
  return o ? &*o : nullptr;
}

}  // namespace pteryla::pipeline
