#pragma once
// Carrying a laid coat along with a deforming skin (the host API's PoseMode::Follow).
//
// Repacking a coat on every pose (Streit 2003, 8.3) keeps it free of interpenetrations but costs a full
// pack and drape per frame. Production systems instead lay the coat once and let the skin carry it: MPC's
// mesh-driven feathers keep their groomed shape while the body deforms, and Houdini's feather surface
// blend bends feathers with the surface (../shared/reference/how-others-lay-feathers.md). A SkinBinding
// does that per point: each bound point (a coat vertex, a follicle) is tied to its nearest point on the
// skin it was laid on, as (face, barycentric) plus its offset in that point's local frame
//   n = interpolated vertex normal, t = the face's first edge projected onto the plane of n, b = n x t.
// Under a pose the same frame is rebuilt on the posed skin and the offset re-applied, so a feather lying
// h above the skin stays h above it and bends where the skin bends, and the layer order of a coat (its
// heights over the skin) is kept. Directions (normals, feather frames) are carried by the same rotation.
// Nothing is searched per frame: the cost is one pass over the bound points.
#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "pteryla/coat/skin.hpp"

namespace pteryla::coat {

class SkinBinding {
 public:
  // Ties each of `points` to its nearest point on `skin` (ties: the lower face index; deterministic,
  // parallel). Throws Error when the skin has no faces.
  void bind(const SkinMesh& skin, const std::vector<glm::dvec3>& points);
  void bind(const SkinMesh& skin, const std::vector<glm::vec3>& points);
  // Points already on the skin, given by their surface coordinates (follicles): no search, offset 0.
  void bind(const SkinMesh& skin, std::vector<SurfacePoint> onSkin);
  size_t size() const { return at_.size(); }
  const std::vector<SurfacePoint>& surfacePoints() const { return at_; }

  // Where the bound points are on `posed`, a deformation of the skin they were bound to (same faces).
  void deform(const SkinMesh& posed, std::vector<glm::dvec3>& out) const;
  void deform(const SkinMesh& posed, std::vector<glm::vec3>& out) const;

  // Directions at the bound points (e.g. vertex normals), one per point, expressed in the bind frames:
  // call once with the skin the points were bound to ...
  std::vector<glm::dvec3> localDirections(const SkinMesh& bindSkin, const std::vector<glm::dvec3>& dirs) const;
  std::vector<glm::dvec3> localDirections(const SkinMesh& bindSkin, const std::vector<glm::vec3>& dirs) const;
  // ... then carry them onto `posed` (unit directions stay unit).
  void carry(const SkinMesh& posed, const std::vector<glm::dvec3>& local, std::vector<glm::dvec3>& out) const;
  void carry(const SkinMesh& posed, const std::vector<glm::dvec3>& local, std::vector<glm::vec3>& out) const;

 private:
  std::vector<SurfacePoint> at_;
  std::vector<glm::dvec3> offset_;  // in the bind frame (t, b, n)
  size_t faceCount_ = 0;            // of the skin bound to: a pose must have as many faces
};

}  // namespace pteryla::coat
