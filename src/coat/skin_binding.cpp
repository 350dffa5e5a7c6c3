// SkinBinding: points tied to their nearest skin point and carried in its local frame (skin_binding.hpp).
#include "pteryla/coat/skin_binding.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>
#include <limits>

#include "pteryla/core/error.hpp"
#include "spatial.hpp"

namespace pteryla::coat {

namespace {

struct LocalFrame {
  glm::dvec3 t, b, n;
};

// The frame at a surface point: interpolated normal, the face's first edge made orthogonal to it.
LocalFrame frameAt(const SkinMesh& skin, const SurfacePoint& s) {
  LocalFrame f;
  f.n = normalAt(skin, s.face, s.bary);
  const auto& tri = skin.faces[s.face];
  glm::dvec3 e = skin.positions[tri[1]] - skin.positions[tri[0]];
  e -= glm::dot(e, f.n) * f.n;
  double len = glm::length(e);
  if (!(len > 0)) {  // the edge is along the normal (a degenerate pose): any direction in the plane
    e = glm::abs(f.n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    e -= glm::dot(e, f.n) * f.n;
    len = glm::length(e);
  }
  f.t = e / len;
  f.b = glm::cross(f.n, f.t);
  return f;
}

template <class F>
void forEach(size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

template <class V>
void bindPoints(const SkinMesh& skin, const std::vector<V>& points, std::vector<SurfacePoint>& at,
                std::vector<glm::dvec3>& offset) {
  if (skin.faces.empty()) throw Error("cannot bind to a skin with no faces", skin.file, "skin");
  detail::TriangleBvh bvh;
  bvh.build(skin.positions.data(), skin.faces[0].data(), skin.faces.size());
  at.assign(points.size(), SurfacePoint{});
  offset.assign(points.size(), glm::dvec3(0));
  forEach(points.size(), [&](size_t i) {
    const glm::dvec3 p(points[i]);
    glm::dvec3 bary(1.0 / 3.0);
    double d2 = 0;
    const int64_t f = bvh.nearest(p, std::numeric_limits<double>::infinity(), bary, d2);
    PTERYLA_CHECK_GE(f, 0, "no nearest skin face");
    at[i] = {static_cast<uint32_t>(f), bary};
    const LocalFrame fr = frameAt(skin, at[i]);
    const glm::dvec3 d = p - pointAt(skin, at[i]);
    offset[i] = {glm::dot(d, fr.t), glm::dot(d, fr.b), glm::dot(d, fr.n)};
  });
}

template <class V>
void deformPoints(const SkinMesh& posed, const std::vector<SurfacePoint>& at, const std::vector<glm::dvec3>& offset,
                  std::vector<V>& out) {
  out.resize(at.size());
  forEach(at.size(), [&](size_t i) {
    const LocalFrame fr = frameAt(posed, at[i]);
    const glm::dvec3& o = offset[i];
    out[i] = V(pointAt(posed, at[i]) + o.x * fr.t + o.y * fr.b + o.z * fr.n);
  });
}

template <class V>
std::vector<glm::dvec3> toLocal(const SkinMesh& skin, const std::vector<SurfacePoint>& at, const std::vector<V>& dirs) {
  if (dirs.size() != at.size())
    throw Error("expected " + std::to_string(at.size()) + " directions (one per bound point), got " +
                    std::to_string(dirs.size()),
                "", "directions");
  std::vector<glm::dvec3> local(dirs.size());
  forEach(dirs.size(), [&](size_t i) {
    const LocalFrame fr = frameAt(skin, at[i]);
    const glm::dvec3 d(dirs[i]);
    local[i] = {glm::dot(d, fr.t), glm::dot(d, fr.b), glm::dot(d, fr.n)};
  });
  return local;
}

template <class V>
void carryDirections(const SkinMesh& posed, const std::vector<SurfacePoint>& at, const std::vector<glm::dvec3>& local,
                     std::vector<V>& out) {
  if (local.size() != at.size())
    throw Error("expected " + std::to_string(at.size()) + " directions (one per bound point), got " +
                    std::to_string(local.size()),
                "", "directions");
  out.resize(at.size());
  forEach(at.size(), [&](size_t i) {
    const LocalFrame fr = frameAt(posed, at[i]);
    const glm::dvec3& d = local[i];
    out[i] = V(d.x * fr.t + d.y * fr.b + d.z * fr.n);
  });
}

void requireSameSkin(const SkinMesh& posed, size_t faceCount) {
  if (posed.faces.size() != faceCount)
    throw Error("the posed skin has " + std::to_string(posed.faces.size()) + " faces, the skin bound to " +
                    std::to_string(faceCount),
                posed.file, "faces");
}

}  // namespace

void SkinBinding::bind(const SkinMesh& skin, const std::vector<glm::dvec3>& points) {
  bindPoints(skin, points, at_, offset_);
  faceCount_ = skin.faces.size();
}
void SkinBinding::bind(const SkinMesh& skin, const std::vector<glm::vec3>& points) {
  bindPoints(skin, points, at_, offset_);
  faceCount_ = skin.faces.size();
}
void SkinBinding::bind(const SkinMesh& skin, std::vector<SurfacePoint> onSkin) {
  for (size_t i = 0; i < onSkin.size(); ++i)
    if (onSkin[i].face >= skin.faces.size())
      throw Error("face " + std::to_string(onSkin[i].face) + " is not a face of the skin (" +
                      std::to_string(skin.faces.size()) + " faces)",
                  skin.file, "point " + std::to_string(i));
  at_ = std::move(onSkin);
  offset_.assign(at_.size(), glm::dvec3(0));
  faceCount_ = skin.faces.size();
}

void SkinBinding::deform(const SkinMesh& posed, std::vector<glm::dvec3>& out) const {
  requireSameSkin(posed, faceCount_);
  deformPoints(posed, at_, offset_, out);
}
void SkinBinding::deform(const SkinMesh& posed, std::vector<glm::vec3>& out) const {
  requireSameSkin(posed, faceCount_);
  deformPoints(posed, at_, offset_, out);
}

std::vector<glm::dvec3> SkinBinding::localDirections(const SkinMesh& bindSkin,
                                                     const std::vector<glm::dvec3>& dirs) const {
  return toLocal(bindSkin, at_, dirs);
}
std::vector<glm::dvec3> SkinBinding::localDirections(const SkinMesh& bindSkin,
                                                     const std::vector<glm::vec3>& dirs) const {
  return toLocal(bindSkin, at_, dirs);
}

void SkinBinding::carry(const SkinMesh& posed, const std::vector<glm::dvec3>& local,
                        std::vector<glm::dvec3>& out) const {
  requireSameSkin(posed, faceCount_);
  carryDirections(posed, at_, local, out);
}
void SkinBinding::carry(const SkinMesh& posed, const std::vector<glm::dvec3>& local,
                        std::vector<glm::vec3>& out) const {
  requireSameSkin(posed, faceCount_);
  carryDirections(posed, at_, local, out);
}

}  // namespace pteryla::coat
