#include "gizmo.hpp"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/moult/controls.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

namespace {

void needControl(const Scene& s, size_t c) {
  if (c >= s.controls.size() || !s.controls[c].is_object())
    throw Error(
        "control index " + std::to_string(c) + " out of range (" + std::to_string(s.controls.size()) + " controls)",
        s.file, "controls");
}

}  // namespace

std::optional<ControlOffset> controlOffsetAt(const Scene& s, size_t c, double t) {
  if (c >= s.controls.size() || !s.controls[c].is_object()) return std::nullopt;
  const Json& ctl = s.controls[c];
  try {
    JsonReader r(ctl, s.file, "controls[" + std::to_string(c) + "]");
    const moult::ControlSpec spec = moult::readControl(r);
    ControlOffset out;
    out.at = spec.at;
    out.offset = moult::controlValuesAt(spec, t).offset;
    out.keyed = actions::controlKeyedIn(ctl, "offset");
    return out;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void setControlOffset(Document& d, size_t c, const glm::dvec3& offset, double time) {
  if (!(std::isfinite(offset.x) && std::isfinite(offset.y) && std::isfinite(offset.z)))
    throw Error("a control offset must be finite", d.scene().file, "controls.offset");
  d.edit("offset " + std::to_string(c), [&](Scene& s) {
    needControl(s, c);
    Json& ctl = s.controls[c];
    if (actions::controlKeyedIn(ctl, "offset"))
      actions::controlKeyAt(ctl, time)["offset"] = actions::vec3Json(offset);
    else
      ctl["offset"] = actions::vec3Json(offset);
  });
}

void keyControlAll(Document& d, size_t c, double time) {
  needControl(d.scene(), c);
  const actions::ControlNow now = actions::controlAt(d.scene(), c, time);
  const std::optional<ControlOffset> off = controlOffsetAt(d.scene(), c, time);
  const glm::dvec3 offset = off ? off->offset : glm::dvec3(0.0);
  d.edit("key control", [&](Scene& s) {
    needControl(s, c);
    Json& ctl = s.controls[c];
    Json& k = actions::controlKeyAt(ctl, time);
    for (int i = 0; i < 5; ++i) {
      ctl.erase(actions::kControlBehaviours[i]);  // a keyed attribute has no constant
      k[actions::kControlBehaviours[i]] = now.value[i];
    }
    ctl.erase("offset");
    k["offset"] = actions::vec3Json(offset);
  });
}

std::optional<double> closestOnLine(const glm::dvec3& o, const glm::dvec3& a, const glm::dvec3& ro,
                                    const glm::dvec3& rd) {
  // Closest points of the lines o + s a and ro + u rd (a, rd unit): solve the 2x2 normal equations.
  const double b = glm::dot(a, rd);
  const double den = 1.0 - b * b;
  if (den < 1e-9) return std::nullopt;
  const glm::dvec3 w = o - ro;
  const double d = glm::dot(a, w), e = glm::dot(rd, w);
  return (b * e - d) / den;
}

const moult::SkinRig* RigCache::get(const Scene& s, size_t vertexCount, uint64_t version) {
  if (version != 0 && version == version_ && vertexCount == vertexCount_ && s.file == file_) return rig_.get();
  version_ = version;
  vertexCount_ = vertexCount;
  file_ = s.file;
  if (s.skeleton.empty() || vertexCount == 0) {
    rig_.reset();
    key_ = Json();
    error_.clear();
    return nullptr;
  }
  const Json key = {{"file", s.file}, {"skeleton", s.skeleton}, {"vertices", vertexCount}};
  if (key == key_) return rig_.get();
  key_ = key;
  rig_.reset();
  error_.clear();
  try {
    JsonReader r(s.skeleton, s.file, "skeleton");
    rig_ = std::make_shared<moult::SkinRig>(moult::readSkinRig(r, vertexCount));
  } catch (const std::exception& e) {
    error_ = e.what();
  }
  return rig_.get();
}

PosedJoints poseJoints(const moult::SkinRig& rig, double t) {
  const moult::Skeleton& sk = rig.skeleton;
  const moult::SkeletonPose pose = moult::poseAt(rig.animation, t);
  const std::vector<moult::RigidTransform> m = moult::jointTransforms(sk, pose);
  PosedJoints out;
  out.pivot.resize(sk.jointCount());
  out.parentFrame.assign(sk.jointCount(), glm::dmat3(1.0));
  out.local = pose.rotation;
  for (size_t j = 0; j < sk.jointCount(); ++j) {
    // M_j = M_parent T(c_j) R_j T(-c_j) keeps c_j where the parent puts it.
    out.pivot[j] = m[j].apply(sk.position[j]);
    if (sk.parent[j] >= 0) out.parentFrame[j] = m[size_t(sk.parent[j])].r;
  }
  return out;
}

glm::dquat turnLocal(const glm::dquat& local, int axis, double degrees) {
  glm::dvec3 e(0.0);
  e[std::clamp(axis, 0, 2)] = 1.0;
  return glm::normalize(glm::angleAxis(glm::radians(degrees), e) * local);
}

Json axisAngleJson(const glm::dquat& rq) {
  glm::dquat q = glm::normalize(rq);
  if (q.w < 0) q = -q;
  const double s = std::sqrt(std::max(0.0, 1.0 - q.w * q.w));
  const double degrees = glm::degrees(2.0 * std::atan2(s, q.w));
  if (s < 1e-12 || degrees < 1e-9) return Json::array({0.0, 0.0, 1.0, 0.0});
  auto tidy = [](double v) { return std::abs(v) < 1e-15 ? 0.0 : v; };
  return Json::array({tidy(q.x / s), tidy(q.y / s), tidy(q.z / s), degrees});
}

void keyJointRotation(Document& d, const moult::Skeleton& skeleton, size_t joint, double time,
                      const glm::dquat& local) {
  if (d.scene().skeleton.empty()) throw Error("the scene has no skeleton", d.scene().file, "skeleton");
  if (joint >= skeleton.jointCount())
    throw Error("joint index " + std::to_string(joint) + " out of range", d.scene().file, "skeleton.keys");
  if (!std::isfinite(time)) throw Error("the key time must be finite", d.scene().file, "skeleton.keys");
  const std::string& name = skeleton.names[joint];
  const Json rotation = axisAngleJson(local);
  d.edit("key joint " + name, [&](Scene& s) {
    Json& keys = s.skeleton["keys"];
    if (!keys.is_array()) keys = Json::array();
    // Existing keys may name or number the joint; either is the same joint.
    for (auto& k : keys) {
      if (!k.is_object() || !k.contains("t") || !k["t"].is_number() || k["t"].get<double>() != time) continue;
      const Json j = k.value("joint", Json());
      if ((j.is_string() && j.get<std::string>() == name) ||
          (j.is_number_integer() && j.get<int64_t>() == int64_t(joint))) {
        k["rotation"] = rotation;
        return;
      }
    }
    keys.push_back({{"joint", name}, {"t", time}, {"rotation", rotation}});
  });
}

double angleAbout(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& axis) {
  const glm::dvec3 n = glm::normalize(axis);
  const glm::dvec3 pa = a - n * glm::dot(a, n), pb = b - n * glm::dot(b, n);
  return std::atan2(glm::dot(n, glm::cross(pa, pb)), glm::dot(pa, pb));
}

}  // namespace pteryla::viewer
