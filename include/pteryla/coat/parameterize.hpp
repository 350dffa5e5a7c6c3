#pragma once
// Tract parameterization (Streit 2003, 6.2.1 "Imposed Parameterization", 9.1.2): every follicle of a tract
// gets a (u,v) coordinate that relates it to its neighbours, used to interpolate key feathers (6.2) and
// to order the layers for packing (6.3, 9.2.1).
//
// Methods:
//  - Projection: the thesis' method, a grid projected from a view direction onto the tract (orthographic:
//    u along the screen's right, v along its up). Distorts where the tract is far from planar; faces
//    seen from behind are reported in `flippedFaces`.
//  - Lscm / Arap: automatic low-distortion parameterizations (least-squares conformal maps; as-rigid-
//    as-possible) of a disk-like tract: one connected component, one boundary loop, Euler
//    characteristic 1. Anything else is a pteryla::Error suggesting a split or the projection method.
//  - Auto: Lscm for disk-like tracts. A connected genus-0 tract that is not a disk (an annulus, a
//    cylinder around a leg, a band with holes, a closed sphere) is first cut open along seams: shortest
//    edge paths joining its boundary loops one after another (a closed tract: a shortest path between
//    two far-apart vertices), which makes it a disk; feathers on the two sides of a seam are far apart in
//    (u,v) and interpolate independently. Any other tract (several pieces, handles, non-manifold
//    vertices) is projected along its mean normal when that view sees (almost) all of it from the
//    front, else rejected with an Error suggesting a split or the projection method.
//
// (u,v) is computed per face corner (corners of one vertex agree except across seams); follicles
// interpolate their face's corners with their barycentric coordinates. The result is normalised to the
// unit square keeping the aspect ratio (min corner at 0, the longer side spans [0,1]) and oriented so that faces are
// counter-clockwise in (u,v) when seen from the normal side (a mirrored solution is flipped in u).
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/json.hpp"

namespace pteryla::coat {

enum class ParamMethod { Projection, Lscm, Arap, Auto };

// Grid distortion before projection (6.2.1: "if the surface is not close to planar or some non-linear
// interpolation of the feathers is desired, distortion of the grid before projection can be used"). One
// handle moves the parameter grid around `at` by `move`, fading to nothing at `radius` (a smooth bump,
// (1 - (d/radius)^2)^2), all in the tract's normalised (u,v). The grid point q is displaced to
// q + D(q) before it is laid on the surface, so a surface point that lands at g gets the grid coordinate
// q with q + D(q) = g: features of the interpolation (key feathers' influence, ordering rows) are
// carried along with the move. |move| <= 0.6 radius keeps one handle fold-free; overlapping handles
// that fold the grid are an Error.
struct GridDistortion {
  glm::dvec2 at{0.0};
  glm::dvec2 move{0.0};
  double radius = 0.1;
};

const char* paramMethodName(ParamMethod m);  // "projection", "lscm", "arap", "auto"

struct ParameterizeOptions {
  ParamMethod method = ParamMethod::Auto;
  // Projection only. viewDirection: the direction the (orthographic) camera looks along; zero = the
  // negated area-weighted mean normal of the tract (looking at it from outside). up: the screen's up
  // vector (made orthogonal to the view direction); zero = world +y, or +z when the view is along y.
  glm::dvec3 viewDirection{0.0};
  glm::dvec3 up{0.0};
  int arapIterations = 50;  // Arap only: local/global iterations
  // Auto only: largest fraction of the tract's area allowed to face away from the mean-normal view
  // before a non-disk tract is rejected instead of projected.
  double autoMaxBackfacing = 0.01;
  bool autoSeams = true;                   // Auto: cut non-disk genus-0 tracts open along seams (else project/reject)
  std::vector<GridDistortion> distortion;  // any method; applied to the normalised (u,v)
};

// The grid displacement D(q) of a set of handles.
glm::dvec2 gridDisplacement(const std::vector<GridDistortion>& handles, const glm::dvec2& q);
// The grid coordinate q that the distorted grid places at g (q + D(q) = g), by fixed-point iteration;
// throws pteryla::Error (naming `where`) when the handles fold the grid there and it does not converge.
glm::dvec2 undistortUv(const std::vector<GridDistortion>& handles, const glm::dvec2& g, const std::string& where);

struct TractParameterization {
  ParamMethod method = ParamMethod::Projection;  // the method actually used (never Auto)
  // Tract faces (= Tract::faces, ascending) and the (u,v) of each of their corners. Corners of one skin
  // vertex agree except across seams (see seamEdges).
  std::vector<uint32_t> faces;
  std::vector<std::array<glm::dvec2, 3>> cornerUv;
  // With a grid distortion: the corners before it (uvAt interpolates these, then undistorts the point,
  // so a handle smaller than a face still acts exactly) and the handles. Empty / equal to cornerUv without.
  std::vector<std::array<glm::dvec2, 3>> projectedCornerUv;
  std::vector<GridDistortion> distortion;
  // Follicles of the tract (indices into Follicles, ascending) and their (u,v).
  std::vector<uint32_t> follicles;
  std::vector<glm::dvec2> follicleUv;
  // Diagnostics.
  size_t flippedFaces = 0;        // tract faces with non-positive signed (u,v) area
  size_t seamEdges = 0;           // Auto on a non-disk genus-0 tract: interior edges cut open
  double scale = 1.0;             // scene units per unit of normalised (u,v) (sqrt of the area ratio)
  glm::dvec3 viewDirection{0.0};  // Projection: the view direction used
  std::string note;               // why Auto chose what it chose

  // (u,v) at a point of a tract face; PTERYLA_CHECKs that the face belongs to the tract.
  glm::dvec2 uvAt(uint32_t face, const glm::dvec3& bary) const;
  const std::array<glm::dvec2, 3>& faceUv(uint32_t face) const;
};

// Topology of a tract's faces as a surface: for the disk check and error messages.
struct TractTopology {
  size_t vertices = 0, edges = 0, faces = 0;
  size_t boundaryLoops = 0;
  size_t components = 0;
  bool nonManifold = false;  // a vertex whose faces do not form a single fan/disk (bow-tie)
  long eulerCharacteristic() const {
    return static_cast<long>(vertices) - static_cast<long>(edges) + static_cast<long>(faces);
  }
  bool isDisk() const { return components == 1 && boundaryLoops == 1 && eulerCharacteristic() == 1 && !nonManifold; }
};

TractTopology tractTopology(const SkinMesh& skin, const Tract& tract);

// Parameterizes tract `tractIndex` (= tracts[tractIndex]); follicles are those with
// follicles.tract[i] == tractIndex. Throws pteryla::Error (element "tracts.<name>") for an empty tract,
// a non-disk tract with Lscm/Arap (or with Auto, see above), a degenerate projection, or a follicle on a
// face outside the tract.
TractParameterization parameterizeTract(const SkinMesh& skin, const Tract& tract, uint32_t tractIndex,
                                        const Follicles& follicles, const ParameterizeOptions& options = {});

// Signed area of each tract face in (u,v) (positive = counter-clockwise = not flipped); param.faces order.
std::vector<double> uvFaceAreas(const TractParameterization& param);

// Reads a "parameterization" object: {"method": "auto"|"projection"|"lscm"|"arap",
// "view_direction": [x,y,z], "up": [x,y,z], "arap_iterations": n, "auto_max_backfacing": f,
// "auto_seams": bool, "distortion": [{"at": [u,v], "move": [du,dv], "radius": r}, ...]}.
// Calls r.finish() (unknown keys rejected).
ParameterizeOptions parseParameterization(JsonReader& r);

}  // namespace pteryla::coat
