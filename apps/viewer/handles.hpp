#pragma once
// Handles in the 3D view (docs/viewer.md, "Handles"): the points of the scene a user grabs with the orbit
// tool: expressive controls, packing brush spheres, styling vectors, key feathers placed at a point and
// pinned follicles. Hovering one shows a readout, dragging it moves the point over the skin (one edit on
// release), Delete removes the selected one. Delete on feathers removes their follicles (FollicleRef).
// No GL, no ImGui (unit-tested in tests/viewer).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "document.hpp"

namespace pteryla::viewer {

enum class HandleKind { Control, Brush, Vector, KeyFeather, Pinned };
const char* handleKindName(HandleKind k);  // "control", "brush", "vector", "key feather", "pinned follicle"

struct Handle {
  HandleKind kind = HandleKind::Control;
  size_t index = 0;  // in its list (controls, packing.styling, directions.vectors, the tract's key_feathers / pinned)
  size_t tract = 0;  // KeyFeather, Pinned
  glm::vec3 at{0};
  bool operator==(const Handle& o) const { return kind == o.kind && index == o.index && tract == o.tract; }
};

// Every handle of the scene, in a fixed order (controls, brushes, vectors, then per tract key feathers
// and pinned follicles). Brushes are the sphere selections; key feathers given by follicle id have none.
std::vector<Handle> sceneHandles(const pipeline::Scene& s);
// The handle's current entry in `s` (its position may have moved); nullopt when it is gone.
std::optional<Handle> findHandle(const pipeline::Scene& s, const Handle& h);
// Several lines: what it is, its name or tract, where, its radius or direction.
std::string handleReadout(const pipeline::Scene& s, const Handle& h);

// One edit each; throw pteryla::Error (scene unchanged) when the handle is gone.
void moveHandle(Document& d, const Handle& h, const glm::dvec3& to);
void removeHandle(Document& d, const Handle& h);
// A follicle deleted by hand (with its feather): its tract and stable id (Snapshot::follicleTract and
// follicleId). Deleting writes the id to the tract's "removed_follicles" (docs/scene-format.md), which the
// distribution drops after relaxation, so the other feathers stay where they are.
struct FollicleRef {
  size_t tract = 0;
  uint64_t id = 0;
  bool operator==(const FollicleRef& o) const { return tract == o.tract && id == o.id; }
};
// The follicles of the snapshot's feathers `feathers` (indices into its feather arrays) and follicles
// `follicles` (indices into its follicle arrays), each once; indices out of range are skipped.
std::vector<FollicleRef> follicleRefs(const Snapshot& s, const std::vector<int>& feathers,
                                      const std::vector<int>& follicles);

// Removes several handles and follicles as one edit (one undo step; Delete on a box selection or on the
// selected feather). Handles that are gone and follicles already removed are skipped; returns how many
// were removed (0: no edit).
size_t removeHandles(Document& d, const std::vector<Handle>& hs, const std::vector<FollicleRef>& follicles = {});

}  // namespace pteryla::viewer
