#pragma once
// Mirror left/right (docs/viewer.md, "Mirror"): copies of tracts (their faces), packing brushes, expressive
// controls and styling vectors reflected about a plane, added to the scene as one undoable edit. The
// plane is x = 0 by default (axis-aligned at an offset), or the body's symmetry plane estimated from the
// rest skin. No GL, no ImGui (unit-tested in tests/viewer).
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "document.hpp"
#include "pteryla/coat/skin.hpp"

namespace pteryla::viewer {

struct MirrorPlane {
  int axis = 0;         // 0 x, 1 y, 2 z: the plane axis = offset
  double offset = 0.0;  // scene units
  glm::dvec3 reflect(const glm::dvec3& p) const {
    glm::dvec3 q = p;
    q[axis] = 2.0 * offset - q[axis];
    return q;
  }
  glm::dvec3 reflectVector(const glm::dvec3& v) const {
    glm::dvec3 q = v;
    q[axis] = -q[axis];
    return q;
  }
};

// The axis-aligned plane through the rest skin's bounding-box centre that maps its vertices closest onto
// vertices (mean distance of a reflected vertex to the nearest vertex, over a sample): the body's
// symmetry plane for a body modelled along the axes.
MirrorPlane symmetryPlane(const coat::SkinMesh& rest);

// "left" <-> "right" (also "Left", "LEFT", "l_"/"_l" and "r_"/"_r" affixes); a name with none gets
// "_mirror".
std::string mirroredName(const std::string& name);

struct MirrorRequest {
  std::vector<size_t> tracts;  // tracts to mirror into new tracts
  bool brushes = false;        // packing.styling spheres and combs
  bool controls = false;
  bool vectors = false;  // directions.vectors (comb strokes)
  MirrorPlane plane;
};

struct MirrorResult {
  size_t tracts = 0, brushes = 0, controls = 0, vectors = 0;  // copies added
};

// One Document edit adding the mirrored copies. A tract's copy is a new tract (mirroredName) of the faces
// nearest its faces' reflections (by triangle centroid), with its other keys copied and their points and
// directions reflected (pinned follicles, key feathers at points, bias vectors); key feathers given by
// follicle id are left out. Brushes, controls and vectors that lie on the plane (their points do), or
// whose reflection is already in the scene, get no copy (mirroring twice adds nothing). A control's `tracts` names the
// mirrored tracts when those exist. Throws pteryla::Error (scene unchanged) for an unknown tract or a
// copy whose name is taken; nothing to add is not an edit.
MirrorResult mirrorScene(Document& d, const coat::SkinMesh& rest, const MirrorRequest& request);

}  // namespace pteryla::viewer
