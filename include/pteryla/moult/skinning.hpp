#pragma once
// Skin deformation (Streit 2003, 8.3, Fig. 8.6: "vertex blending in an area of influence around the
// joints"): a small joint hierarchy with per-vertex weights (docs/skeleton-format.md) and keyframed
// joint rotations. Follicles are stored as (face, barycentric) and ride the deformed skin
// (coat::updateFollicleGeometry); the coat is then repacked in its rest layer order.
//
// Pose model: joint j turns by a local rotation R_j about its rest position c_j; rotations compose down
// the chain (forward kinematics), M_j = M_parent(j) * T(c_j) R_j T(-c_j). The rotation axis of a key is
// given in rest (mesh) coordinates and turns with the parent. Linear blend skinning with weights w_j:
//   p' = p + sum_j w_j (M_j p - p)
// (the displacement form, so an identity pose leaves every vertex exactly in place).
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/coat/skin.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/moult/keyframes.hpp"

namespace pteryla::moult {

struct Skeleton {
  std::vector<std::string> names;
  std::vector<int32_t> parent;       // -1 for the root (joint 0); parents come before children
  std::vector<glm::dvec3> position;  // rest position of each joint, mesh coordinates
  // Skin weights per vertex, CSR: vertex v is influenced by weightJoint[weightOffset[v] .. [v+1]) with
  // weights (positive, normalised to sum 1). A vertex without entries in the file is bound to the root.
  std::vector<uint32_t> weightOffset;
  std::vector<uint32_t> weightJoint;
  std::vector<double> weight;

  size_t jointCount() const { return names.size(); }
  size_t vertexCount() const { return weightOffset.empty() ? 0 : weightOffset.size() - 1; }
  int32_t find(const std::string& name) const;  // -1 if absent
};

// Reads "joints" and "weights" from r (docs/skeleton-format.md) for a mesh with `vertexCount`
// vertices; does not call r.finish(). Errors name the file and key path ("weights[12]").
Skeleton readSkeleton(JsonReader& r, size_t vertexCount);
// A skeleton side file (only "joints" and "weights"; unknown keys are errors).
Skeleton loadSkeleton(const std::string& path, size_t vertexCount);

// World transform of a joint relative to its rest pose: x -> r x + t.
struct RigidTransform {
  glm::dmat3 r{1.0};
  glm::dvec3 t{0.0};
  glm::dvec3 apply(const glm::dvec3& p) const { return r * p + t; }
};

// Local rotation of every joint (unit quaternions; identity = rest).
struct SkeletonPose {
  std::vector<glm::dquat> rotation;
};
SkeletonPose restPose(const Skeleton& s);

std::vector<RigidTransform> jointTransforms(const Skeleton& s, const SkeletonPose& pose);
// Linear blend skinning of `rest` (one point per skeleton vertex) into `out`.
void skinPoints(const Skeleton& s, const std::vector<RigidTransform>& joints, const std::vector<glm::dvec3>& rest,
                std::vector<glm::dvec3>& out);
// One vertex of skinPoints (the same arithmetic): vertex v at rest position p.
glm::dvec3 skinPoint(const Skeleton& s, const std::vector<RigidTransform>& joints, const glm::dvec3& p, size_t v);
// Deforms posed.positions from rest.positions and recomputes normals and areas (coat::recomputeGeometry).
// `posed` must have rest's connectivity (a copy of it). Returns false and leaves `posed` untouched when
// the pose moves no vertex (an identity pose), so a rest pose keeps the rest normals bit for bit.
bool poseSkinMesh(const Skeleton& s, const SkeletonPose& pose, const coat::SkinMesh& rest, coat::SkinMesh& posed);

// Keyframed joint rotations. Between keys of one joint the rotation is slerped (linear) or slerped with
// a smoothstep parameter (smooth); step holds each key. A joint without keys stays at rest.
struct SkeletonAnimation {
  Interpolation interpolation = Interpolation::Linear;
  std::vector<std::vector<double>> times;          // per joint, strictly increasing
  std::vector<std::vector<glm::dquat>> rotations;  // per joint, one per time
};
SkeletonPose poseAt(const SkeletonAnimation& a, double t);

// One key's rotation from [axis_x, axis_y, axis_z, degrees]; a zero axis is allowed only with 0 degrees.
glm::dquat rotationFromAxisAngle(const glm::dvec3& axis, double degrees);

// A skeleton with its animation: the scene's "skeleton" object (docs/moult.md):
//   {"file": "<skeleton json, relative to the scene file>"  (or inline "joints" and "weights"),
//    "interpolation": "linear" | "smooth" | "step",
//    "keys": [{"joint": "elbow" | 1, "t": 0, "rotation": [ax, ay, az, degrees]}, ...]}
// Calls r.finish(). Two keys of one joint at the same time are an error.
struct SkinRig {
  Skeleton skeleton;
  SkeletonAnimation animation;
  std::string file;  // the skeleton file ("" when inline)
};
SkinRig readSkinRig(JsonReader& r, size_t vertexCount);

}  // namespace pteryla::moult
