#pragma once
// Gizmos in the 3D view (docs/viewer.md, "Gizmos"): the math and the scene edits behind them, with no GL
// and no ImGui (unit-tested in tests/viewer; input_gizmo.cpp draws and drags them).
//   - A selected expressive control shows its offset (docs/controls.md: the displacement that `direction`
//     follows, that `aim` points at, and that drives the `dynamic` chain) as an arrow from its placement
//     to placement + offset, with three axis handles at the tip. Dragging a handle moves the offset along
//     that axis; the release writes it at the current time (a key when the offset is keyed, else the
//     constant). "Key" keys every behaviour and the offset at the current time.
//   - A selected skeleton joint shows three rotation rings about its pivot, about the axes of its parent's
//     posed frame (a key's rotation axis is in rest coordinates and turns with the parent, docs/moult.md),
//     so a ring drag of `a` degrees about axis k makes the joint's local rotation rot(e_k, a) * R. The
//     release keys the joint's rotation at the current time.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "document.hpp"
#include "pteryla/moult/skinning.hpp"

namespace pteryla::viewer {

// ---- Control offsets ----------------------------------------------------------------------------------

struct ControlOffset {
  glm::dvec3 at{0.0};      // placement (rest coordinates), the arrow's base
  glm::dvec3 offset{0.0};  // at the time asked for
  bool keyed = false;      // the offset has keys (else it is a constant, or absent = 0)
};
// The control's placement and offset at time t as the moult module evaluates them; nullopt when the
// control is missing or unreadable.
std::optional<ControlOffset> controlOffsetAt(const pipeline::Scene& s, size_t control, double t);

// One edit: a keyed offset gets (or updates) its key at `time`; an unkeyed one is set as the constant.
void setControlOffset(Document& d, size_t control, const glm::dvec3& offset, double time);
// One edit: keys every behaviour and the offset at `time` with their values there (constants become keys).
void keyControlAll(Document& d, size_t control, double time);

// Moving the offset tip along a world axis with the mouse: the parameter along the line through `origin`
// with unit direction `axis` closest to the ray (nullopt when the ray runs along the line).
std::optional<double> closestOnLine(const glm::dvec3& origin, const glm::dvec3& axis, const glm::dvec3& rayOrigin,
                                    const glm::dvec3& rayDir);

// ---- Skeleton joints -----------------------------------------------------------------------------------

// The scene's skeleton section parsed (a cache: read again only when the section, the scene file or the
// vertex count change). get() returns nullptr without a skeleton or when it does not read (error() says
// why). `version` (Document::changeCount(), 0 = unknown) skips even comparing the section while the
// scene has not changed: the app asks several times a frame.
class RigCache {
 public:
  const moult::SkinRig* get(const pipeline::Scene& s, size_t vertexCount, uint64_t version = 0);
  const std::string& error() const { return error_; }

 private:
  uint64_t version_ = 0;
  size_t vertexCount_ = 0;
  std::string file_;
  Json key_;
  std::shared_ptr<moult::SkinRig> rig_;
  std::string error_;
};

// The posed joints at time t: pivot (world), the parent's posed rotation (identity for the root: the
// rings' frame) and the local rotation (the animation's, at t).
struct PosedJoints {
  std::vector<glm::dvec3> pivot;
  std::vector<glm::dmat3> parentFrame;
  std::vector<glm::dquat> local;
};
PosedJoints poseJoints(const moult::SkinRig& rig, double t);

// A local rotation turned by `degrees` about axis k (0 x, 1 y, 2 z) of the parent's frame.
glm::dquat turnLocal(const glm::dquat& local, int axis, double degrees);
// [axis_x, axis_y, axis_z, degrees] of a rotation (degrees in [0, 180]; the identity is [0, 0, 1, 0]).
Json axisAngleJson(const glm::dquat& q);
// One edit: the joint's key at `time` (replacing a key of that joint, by name or index, at that time) with
// this local rotation; a new key names the joint. Throws pteryla::Error (scene unchanged) without a
// skeleton section or for a joint out of range.
void keyJointRotation(Document& d, const moult::Skeleton& skeleton, size_t joint, double time, const glm::dquat& local);

// What the app draws and drags this frame (input_gizmo.cpp): the selected control's offset arrow (control
// < 0: none) and the skeleton posed at the current time (rig null: no skeleton).
struct GizmoGeometry {
  int control = -1;
  glm::dvec3 at{0.0}, offset{0.0};
  bool offsetKeyed = false;
  double handleLength = 0.1;  // the axis handles at the offset's tip, scene units
  const moult::SkinRig* rig = nullptr;
  PosedJoints joints;
  double ringRadius = 0.1;  // the selected joint's rotation rings, scene units
};

// Signed angle (radians) from a to b about `axis` (a, b projected onto the plane normal to it).
double angleAbout(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& axis);

}  // namespace pteryla::viewer
