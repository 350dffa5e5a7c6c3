#pragma once
// pteryla_meshgen: builds the bundled skin meshes in data/meshes/ (bird, wing, head, spheres, patch).
// Smooth shapes are hand-made quad cages (lofted rings plus extruded wings and legs) refined by
// Catmull-Clark subdivision and pushed to the limit surface, then split into triangles. Every face
// carries the cage coordinates it came from, so feather tracts (OBJ groups) are regions of the cage.
// Everything is deterministic: no randomness, fixed iteration counts.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pteryla::meshgen {

// Which cage component a face comes from, plus its corner coordinates in that component's own
// (s, a) coordinates: for a loft, s = ring index and a = position around the ring.
struct FaceTag {
  int part = 0;
  std::array<glm::dvec2, 4> param{};
  glm::dvec2 center() const { return (param[0] + param[1] + param[2] + param[3]) * 0.25; }
};

// Closed all-quad control mesh. `chains` are vertex paths along edges (e.g. a wing's trailing edge);
// subdivision refines them so they keep naming the same curve on the finer mesh.
struct QuadCage {
  std::vector<glm::dvec3> positions;
  std::vector<std::array<uint32_t, 4>> quads;
  std::vector<FaceTag> tags;
  std::vector<std::vector<uint32_t>> chains;

  uint32_t addVertex(const glm::dvec3& p);
  void addQuad(const std::array<uint32_t, 4>& q, int part, const std::array<glm::dvec2, 4>& param);
};

// Makes face orientation consistent across shared edges and outward (positive enclosed volume).
void orientOutward(QuadCage& cage);
// One Catmull-Clark step (closed quad meshes only). Vertex indices of the input are kept.
QuadCage subdivideCatmullClark(const QuadCage& cage);
// Moves every vertex to its Catmull-Clark limit position.
void projectToLimit(QuadCage& cage);

// Triangle mesh with exactly one group per face: what an OBJ file in data/meshes holds.
struct GroupedMesh {
  std::vector<glm::dvec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;
  std::vector<uint32_t> faceGroup;  // index into groupNames
  std::vector<std::string> groupNames;
  uint32_t groupIndex(const std::string& name);  // adds the group when missing
};

using Classifier = std::function<std::string(const FaceTag& tag, const glm::dvec3& centroid)>;
// Splits every quad along its shorter diagonal; both halves get classify(tag, quad centroid).
// Groups appear in `groupOrder` order first, then in order of first use.
GroupedMesh triangulate(const QuadCage& cage, const Classifier& classify,
                        const std::vector<std::string>& groupOrder = {});

// Max-min-angle edge flips (the Delaunay criterion on near-flat edges): an edge is flipped when both
// of its faces are in the same group, the faces bend by less than maxDihedralDeg, the flipped edge
// does not exist yet and the smallest angle of the pair grows. Returns the number of flips.
size_t improveByFlips(GroupedMesh& mesh, double maxDihedralDeg);

// Evens out the triangles: `iterations` Jacobi steps that move each vertex by `step` times the
// tangential part of its umbrella vector, then back onto the reference surface (closest point on
// `reference`, a finer subdivision of the same cage, among faces facing the same way).
// Connectivity and groups are unchanged.
void relaxOnSurface(GroupedMesh& mesh, const QuadCage& reference, int iterations, double step);

struct GroupStat {
  std::string name;
  size_t faces = 0;
  size_t facesBelow20Deg = 0;
  double area = 0;
};

struct MeshCheck {
  size_t vertices = 0, faces = 0, edges = 0;
  size_t boundaryEdges = 0, nonManifoldEdges = 0, misorientedEdges = 0, nonManifoldVertices = 0;
  size_t degenerateFaces = 0, nonFinite = 0, unusedVertices = 0, selfIntersections = 0;
  size_t boundaryLoops = 0;
  double area = 0, volume = 0;  // volume only meaningful for closed meshes
  double minAngleDeg = 180, meanMinAngleDeg = 0;
  size_t facesBelow20Deg = 0, facesBelow10Deg = 0;
  std::vector<GroupStat> groups;
  std::vector<std::string> problems;  // empty when the mesh passed
  bool ok() const { return problems.empty(); }
};

// Closed: every edge in exactly two faces, used once in each direction, every vertex a single disk
// fan, positive volume (outward normals). Open (expectClosed=false): edges in one or two faces,
// boundary loops allowed. Always: finite coordinates, no degenerate faces, no self-intersections.
MeshCheck checkMesh(const GroupedMesh& mesh, bool expectClosed);
std::string formatCheck(const std::string& title, const MeshCheck& check);

// OBJ with `v` and triangle `f` lines, faces written group by group under `g name`.
void writeObj(const GroupedMesh& mesh, const std::string& path, const std::string& comment);
// Reads v / g / f (triangles or convex polygons, fanned; `f a/b/c` forms accepted). Throws
// pteryla::Error with file and line on bad input.
GroupedMesh readObj(const std::string& path);

struct Joint {
  std::string name;
  int parent = -1;
  glm::dvec3 position{0.0};
};

struct SkinWeight {
  uint32_t vertex = 0, joint = 0;
  double weight = 0;
};

// docs/skeleton-format.md
struct Skeleton {
  std::vector<Joint> joints;
  std::vector<SkinWeight> weights;
};
void writeSkeletonJson(const Skeleton& skeleton, const std::string& path);

struct Polyline {
  std::string name;
  std::vector<glm::dvec3> points;
};
void writeAxesJson(const std::vector<Polyline>& lines, const std::string& path);

struct Generated {
  std::string name;  // file stem in data/meshes
  GroupedMesh mesh;
  bool closed = true;
  bool hasSkeleton = false;
  Skeleton skeleton;
  std::vector<Polyline> axes;  // written to <name>.axes.json when not empty
};

Generated makeBird();
Generated makeWing();
Generated makeHead();
Generated makeSphere(int pointCount, const std::string& name);  // 2*pointCount-4 triangles
Generated makePatch(int cellsPerSide);                          // 2*cells^2 triangles
std::vector<Generated> makeAll();

}  // namespace pteryla::meshgen
