// Skin deformation by vertex blending around joints, Streit 2003, 8.3 (Fig. 8.6: bending wing; the
// follicles ride the skin and the feathers are repacked every frame).
#include "pteryla/moult/skinning.hpp"

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"

namespace pteryla::moult {

int32_t Skeleton::find(const std::string& name) const {
  for (size_t j = 0; j < names.size(); ++j)
    if (names[j] == name) return static_cast<int32_t>(j);
  return -1;
}

Skeleton readSkeleton(JsonReader& r, size_t vertexCount) {
  Skeleton s;
  const Json& joints = r.raw("joints");
  const std::string jp = r.pathOf("joints");
  if (!joints.is_array() || joints.empty()) r.fail("joints", "expected a non-empty array of joints");
  for (size_t j = 0; j < joints.size(); ++j) {
    JsonReader jr(joints[j], r.file(), jp + "[" + std::to_string(j) + "]");
    const std::string name = jr.string("name");
    if (name.empty()) jr.fail("name", "joint names must not be empty");
    if (s.find(name) >= 0) jr.fail("name", "duplicate joint name '" + name + "'");
    const int64_t parent = jr.integer("parent", -1, static_cast<int64_t>(j) - 1);
    if (j == 0 && parent != -1) jr.fail("parent", "the first joint is the root: its parent must be -1");
    if (j > 0 && parent < 0) jr.fail("parent", "only the first joint may be a root (parent -1)");
    s.names.push_back(name);
    s.parent.push_back(static_cast<int32_t>(parent));
    s.position.push_back(jr.vec3("position"));
    jr.finish();
  }
  // Weights: [vertex, joint, weight] triples, gathered per vertex.
  std::vector<std::vector<std::pair<uint32_t, double>>> per(vertexCount);
  if (r.has("weights")) {
    const Json& w = r.raw("weights");
    const std::string wp = r.pathOf("weights");
    if (!w.is_array()) r.fail("weights", "expected an array of [vertex, joint, weight]");
    for (size_t k = 0; k < w.size(); ++k) {
      const std::string at = wp + "[" + std::to_string(k) + "]";
      const Json& e = w[k];
      if (!e.is_array() || e.size() != 3 || !e[0].is_number_integer() || !e[1].is_number_integer())
        throw Error("expected [vertexIndex, jointIndex, weight]", r.file(), at);
      const int64_t v = e[0].get<int64_t>(), j = e[1].get<int64_t>();
      const double wt = jsonNumber(e[2], r.file(), at + "[2]");
      if (v < 0 || static_cast<uint64_t>(v) >= vertexCount)
        throw Error("vertex index " + std::to_string(v) + " out of range: the mesh has " + std::to_string(vertexCount) +
                        " vertices (is this the skeleton of another mesh?)",
                    r.file(), at + "[0]");
      if (j < 0 || static_cast<uint64_t>(j) >= s.names.size())
        throw Error("joint index " + std::to_string(j) + " out of range: the skeleton has " +
                        std::to_string(s.names.size()) + " joints",
                    r.file(), at + "[1]");
      if (!(wt >= 0)) throw Error("weights must be non-negative", r.file(), at + "[2]");
      if (wt > 0) per[static_cast<size_t>(v)].push_back({static_cast<uint32_t>(j), wt});
    }
  } else {
    r.allow("weights");
  }
  s.weightOffset.assign(vertexCount + 1, 0);
  for (size_t v = 0; v < vertexCount; ++v) {
    auto& list = per[v];
    if (list.empty()) list.push_back({0u, 1.0});
    // Merge duplicate joints, then normalise.
    std::sort(list.begin(), list.end());
    double sum = 0;
    size_t m = 0;
    for (size_t k = 0; k < list.size(); ++k) {
      if (m > 0 && list[m - 1].first == list[k].first)
        list[m - 1].second += list[k].second;
      else
        list[m++] = list[k];
    }
    list.resize(m);
    for (const auto& e : list) sum += e.second;
    for (const auto& e : list) {
      s.weightJoint.push_back(e.first);
      s.weight.push_back(e.second / sum);
    }
    s.weightOffset[v + 1] = static_cast<uint32_t>(s.weight.size());
  }
  return s;
}

Skeleton loadSkeleton(const std::string& path, size_t vertexCount) {
  const Json j = readJsonFile(path);
  JsonReader r(j, path);
  Skeleton s = readSkeleton(r, vertexCount);
  r.finish();
  return s;
}

SkeletonPose restPose(const Skeleton& s) {
  SkeletonPose p;
  p.rotation.assign(s.jointCount(), glm::dquat(1, 0, 0, 0));
  return p;
}

std::vector<RigidTransform> jointTransforms(const Skeleton& s, const SkeletonPose& pose) {
  PTERYLA_CHECK_EQ(pose.rotation.size(), s.jointCount(), "pose and skeleton differ in joint count");
  std::vector<RigidTransform> out(s.jointCount());
  for (size_t j = 0; j < s.jointCount(); ++j) {
    const glm::dmat3 r = glm::mat3_cast(pose.rotation[j]);
    const glm::dvec3& c = s.position[j];
    RigidTransform local{r, c - r * c};
    if (s.parent[j] < 0) {
      out[j] = local;
    } else {
      const RigidTransform& p = out[static_cast<size_t>(s.parent[j])];
      out[j] = {p.r * local.r, p.r * local.t + p.t};
    }
  }
  return out;
}

void skinPoints(const Skeleton& s, const std::vector<RigidTransform>& joints, const std::vector<glm::dvec3>& rest,
                std::vector<glm::dvec3>& out) {
  PTERYLA_CHECK_EQ(rest.size(), s.vertexCount(), "skinPoints: point count differs from the skeleton's vertex count");
  out.resize(rest.size());
  for (size_t v = 0; v < rest.size(); ++v) {
    const glm::dvec3& p = rest[v];
    glm::dvec3 d(0.0);
    for (uint32_t k = s.weightOffset[v]; k < s.weightOffset[v + 1]; ++k)
      d += s.weight[k] * (joints[s.weightJoint[k]].apply(p) - p);
    out[v] = p + d;
  }
}

glm::dvec3 skinPoint(const Skeleton& s, const std::vector<RigidTransform>& joints, const glm::dvec3& p, size_t v) {
  PTERYLA_CHECK(v < s.vertexCount(), "skinPoint: vertex out of range");
  glm::dvec3 d(0.0);
  for (uint32_t k = s.weightOffset[v]; k < s.weightOffset[v + 1]; ++k)
    d += s.weight[k] * (joints[s.weightJoint[k]].apply(p) - p);
  return p + d;
}

bool poseSkinMesh(const Skeleton& s, const SkeletonPose& pose, const coat::SkinMesh& rest, coat::SkinMesh& posed) {
  if (s.vertexCount() != rest.vertexCount())
    throw Error("the skeleton has weights for " + std::to_string(s.vertexCount()) + " vertices, the mesh has " +
                    std::to_string(rest.vertexCount()),
                rest.file, "skeleton");
  PTERYLA_CHECK(posed.vertexCount() == rest.vertexCount() && posed.faceCount() == rest.faceCount(),
                "posed mesh must be a copy of the rest mesh");
  const std::vector<RigidTransform> joints = jointTransforms(s, pose);
  bool moves = false;
  for (const auto& j : joints) moves = moves || j.r != glm::dmat3(1.0) || j.t != glm::dvec3(0.0);
  if (!moves) return false;
  skinPoints(s, joints, rest.positions, posed.positions);
  coat::recomputeGeometry(posed);
  return true;
}

SkeletonPose poseAt(const SkeletonAnimation& a, double t) {
  SkeletonPose p;
  p.rotation.assign(a.times.size(), glm::dquat(1, 0, 0, 0));
  for (size_t j = 0; j < a.times.size(); ++j) {
    const auto& ts = a.times[j];
    const auto& qs = a.rotations[j];
    if (ts.empty()) continue;
    if (t <= ts.front()) {
      p.rotation[j] = qs.front();
      continue;
    }
    if (t >= ts.back()) {
      p.rotation[j] = qs.back();
      continue;
    }
    const size_t k = static_cast<size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
    double x = (t - ts[k]) / (ts[k + 1] - ts[k]);
    switch (a.interpolation) {
      case Interpolation::Linear:
        break;
      case Interpolation::Smooth:
        x = x * x * (3.0 - 2.0 * x);
        break;
      case Interpolation::Step:
        x = 0;
        break;
    }
    p.rotation[j] = x == 0 ? qs[k] : glm::normalize(glm::slerp(qs[k], qs[k + 1], x));
  }
  return p;
}

glm::dquat rotationFromAxisAngle(const glm::dvec3& axis, double degrees) {
  if (degrees == 0) return glm::dquat(1, 0, 0, 0);
  const double len = glm::length(axis);
  PTERYLA_CHECK(len > 0, "rotation axis must be non-zero");
  return glm::angleAxis(glm::radians(degrees), axis / len);
}

SkinRig readSkinRig(JsonReader& r, size_t vertexCount) {
  SkinRig rig;
  if (r.has("file")) {
    if (r.has("joints") || r.has("weights"))
      r.fail("file", "give either \"file\" or inline \"joints\"/\"weights\", not both");
    rig.file = resolveRelative(r.file(), r.string("file"));
    if (!fileExists(rig.file)) r.fail("file", "skeleton file not found: " + rig.file);
    rig.skeleton = loadSkeleton(rig.file, vertexCount);
    r.allow("joints");
    r.allow("weights");
  } else {
    r.allow("file");
    if (!r.has("joints")) r.fail("joints", "a skeleton needs \"file\" or inline \"joints\" and \"weights\"");
    rig.skeleton = readSkeleton(r, vertexCount);
  }
  const Skeleton& s = rig.skeleton;
  const std::string interp = r.oneOf("interpolation", "linear", {"linear", "smooth", "step"});
  parseInterpolation(interp, rig.animation.interpolation);
  rig.animation.times.assign(s.jointCount(), {});
  rig.animation.rotations.assign(s.jointCount(), {});
  for (auto& k : r.objects("keys")) {
    int32_t joint = -1;
    const Json& jv = k.raw("joint");
    if (jv.is_string()) {
      joint = s.find(jv.get<std::string>());
      if (joint < 0) {
        std::string list;
        for (const auto& n : s.names) list += (list.empty() ? "" : ", ") + n;
        k.fail("joint", "unknown joint '" + jv.get<std::string>() + "' (joints: " + list + ")");
      }
    } else if (jv.is_number_integer()) {
      const int64_t j = jv.get<int64_t>();
      if (j < 0 || static_cast<uint64_t>(j) >= s.jointCount())
        k.fail("joint",
               "joint index " + std::to_string(j) + " out of range [0, " + std::to_string(s.jointCount()) + ")");
      joint = static_cast<int32_t>(j);
    } else {
      k.fail("joint", "expected a joint name or index");
    }
    const double t = k.number("t", -1e12, 1e12);
    const std::vector<double> rot = k.numbers("rotation");
    if (rot.size() != 4) k.fail("rotation", "expected [axis_x, axis_y, axis_z, degrees]");
    const glm::dvec3 axis(rot[0], rot[1], rot[2]);
    if (glm::length(axis) == 0 && rot[3] != 0) k.fail("rotation", "the rotation axis must be non-zero");
    k.finish();
    auto& ts = rig.animation.times[static_cast<size_t>(joint)];
    auto& qs = rig.animation.rotations[static_cast<size_t>(joint)];
    const auto it = std::lower_bound(ts.begin(), ts.end(), t);
    if (it != ts.end() && *it == t)
      k.fail("t", "joint '" + s.names[static_cast<size_t>(joint)] + "' already has a key at t = " + std::to_string(t));
    const auto pos = it - ts.begin();
    ts.insert(it, t);
    qs.insert(qs.begin() + pos, rotationFromAxisAngle(axis, rot[3]));
  }
  r.finish();
  return rig;
}

}  // namespace pteryla::moult
