#pragma once
// SceneSettings: the module sections of a Scene as typed settings (the packer's knobs and styling, the
// moult schedules, the controls, the skeleton, the growth schedule, directions and ordering), each parsed
// in one place, once per change of its section, and the revisions the pipeline's caches are keyed by.
//
// The Scene keeps its sections as JSON: it is what the viewer edits and what is saved. Pipeline::editScene
// hands every edited scene to update(), which compares the sections row by row of sectionStages() (the
// section-to-stage table) and gives each changed section a new revision. A typed section is parsed by its
// module's reader the first time a stage reads it after a change, so a bad section is still an Error with
// the scene file and its key path, raised where the stage reading it runs (as the viewer and the host
// report evaluation errors), and nothing is kept from a parse that failed.
#include <array>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/relax.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/moult/skinning.hpp"
#include "pteryla/pipeline/scene.hpp"

namespace pteryla::pipeline {

// What a cached result was made from, as revisions: of settings sections (SceneSettings::revision), of
// the rest state (the directions stage's evaluation count) and counts that decide its layout. Every cache
// of the pipeline that outlives a stage's re-run is reused only while the key of its inputs equals the
// key it was made with; data that changes every frame (skin positions, frames, ages) is compared by
// value beside it. An empty key (default) stands for "not made" and equals no key made from revisions.
class InputKey {
 public:
  InputKey() = default;
  InputKey(std::initializer_list<uint64_t> parts) { add(parts); }
  InputKey& add(std::initializer_list<uint64_t> parts);
  InputKey& add(const InputKey& other);
  bool empty() const { return size_ == 0; }
  bool operator==(const InputKey& o) const { return size_ == o.size_ && parts_ == o.parts_; }
  bool operator!=(const InputKey& o) const { return !(*this == o); }

 private:
  static constexpr size_t kCapacity = 8;
  std::array<uint64_t, kCapacity> parts_{};
  size_t size_ = 0;
};

// The sections with typed settings (rows of sectionStages(); TractMoult is every tract's "moult").
enum class Section { Tracts, TractMoult, Growth, Directions, Ordering, Skeleton, Moult, Controls, Packing };

// A tract's settings (the "tracts" section, one element; its "moult" is in SceneSettings::moult).
struct TractSettings {
  coat::Tract tract;
  double density = 0;  // follicles per unit area (0: use count)
  size_t count = 0;
  bool autoScale = false;   // scale feathers so their length is ~featherSpacings x follicle spacing
  double featherScale = 1;  // explicit scale factor
  double featherSpacings = 3.5;
  coat::RelaxOptions relax;
  std::vector<glm::dvec3> pinned;
  std::vector<uint64_t> removed;  // "removed_follicles": ids dropped after relaxation (sorted, unique)
  coat::TractFeatherOptions feathers;
  std::shared_ptr<const feather::GrowthSchedule> growth;  // the tract's "growth" (null: none)
  std::string overlapGroup;      // "overlap_group": tracts of one group share one distribution where they overlap
  std::optional<uint64_t> seed;  // "seed": this tract's own follicle seed (else derived from the scene's)
  double area = 0;
  std::string element;
};

// The controls with the tracts they name resolved to tract indices.
struct ControlSettings {
  std::vector<moult::ControlSpec> controls;
  std::vector<std::vector<uint32_t>> tracts;  // per control: tract indices (empty = any)
};

class SceneSettings {
 public:
  // Takes the scene's sections as they are now: each section whose value differs from the last call's
  // (compared as earliestChangedStage compares them; all of them on the first call) gets a new revision,
  // and its typed settings are parsed again when next read.
  void update(const Scene& scene);
  uint64_t revision(Section s) const { return revision_[static_cast<size_t>(s)]; }
  // Whether the time stages read the time: a skeleton, a moult (scene-wide or a tract's) or controls.
  // Conservative: any such section counts, even one that turns out to be disabled.
  bool readsTime() const { return readsTime_; }

  // The typed sections of `scene` (the scene last given to update()). Each throws pteryla::Error with
  // the scene file and the key path when its section is malformed.
  // The tracts on the rest skin `rest` (label files, face groups and areas are read on it); parsed again
  // when the tracts section or `restRevision` (the skin stage's evaluation count) changes.
  const std::vector<TractSettings>& tracts(const Scene& scene, const coat::SkinMesh& rest, uint64_t restRevision);
  const coat::PackingSettings& packing(const Scene& scene);  // defaults when the section is empty
  // Per tract: its moult options (the scene's "moult" overridden by the tract's; nullopt: it does not moult).
  const std::vector<std::optional<moult::MoultOptions>>& moult(const Scene& scene);
  const ControlSettings& controls(const Scene& scene);
  // The skeleton with its animation for a rest skin of `vertexCount` vertices; null without one.
  const moult::SkinRig* skeleton(const Scene& scene, size_t vertexCount);
  // The scene's growth schedule (docs/growth.md); null when the section is empty.
  std::shared_ptr<const feather::GrowthSchedule> growth(const Scene& scene);
  // The "directions" and "ordering" sections; null when empty (the stage picks its defaults).
  const coat::DirectionOptions* directions(const Scene& scene);
  const coat::OrderOptions* ordering(const Scene& scene);

  // The keys of what the typed sections are made from.
  InputKey packingKey() const { return {revision(Section::Packing)}; }
  InputKey moultKey() const { return {revision(Section::Moult), revision(Section::TractMoult)}; }
  InputKey controlsKey() const { return {revision(Section::Controls), revision(Section::Tracts)}; }
  InputKey skeletonKey(size_t vertexCount) const { return {revision(Section::Skeleton), vertexCount}; }

 private:
  template <class T>
  struct Parsed {
    InputKey key;  // empty: not parsed (or the parse failed)
    T value{};
  };
  std::array<uint64_t, size_t(Section::Packing) + 1> revision_{};
  uint64_t nextRevision_ = 0;
  std::array<Json, size_t(Section::Packing) + 1> value_;  // per section: its value at the last update
  bool updated_ = false, readsTime_ = false;

  Parsed<std::vector<TractSettings>> tracts_;
  Parsed<coat::PackingSettings> packing_;
  Parsed<std::vector<std::optional<moult::MoultOptions>>> moult_;
  Parsed<ControlSettings> controls_;
  Parsed<std::optional<moult::SkinRig>> skeleton_;
  Parsed<std::shared_ptr<const feather::GrowthSchedule>> growth_;
  Parsed<std::optional<coat::DirectionOptions>> directions_;
  Parsed<std::optional<coat::OrderOptions>> ordering_;
};

}  // namespace pteryla::pipeline
