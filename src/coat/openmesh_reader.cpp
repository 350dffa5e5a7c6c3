// PLY / OFF / STL skin meshes through OpenMesh's readers. A capturing importer records the raw vertices
// and polygons exactly as the reader sees them, so our own validation (skin.cpp) reports problems such
// as non-manifold edges by face index instead of OpenMesh silently duplicating vertices.
// Note: OpenMesh's STL reader merges coincident vertices and skips faces with repeated vertices itself.
#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include "mesh_io.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/core/quiet.hpp"

namespace pteryla::coat::detail {
namespace {

using namespace OpenMesh;
using OpenMesh::IO::BaseImporter;

class CaptureImporter final : public BaseImporter {
 public:
  RawMesh raw;
  std::vector<glm::dvec2> vertexUV;
  bool anyUV = false, anyNormal = false;

  VertexHandle add_vertex(const Vec3f& p) override { return push({p[0], p[1], p[2]}); }
  VertexHandle add_vertex(const Vec3d& p) override { return push({p[0], p[1], p[2]}); }
  VertexHandle add_vertex() override { return push(glm::dvec3(0)); }
  HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
  FaceHandle add_face(const VHandles& idx) override {
    for (const auto& v : idx) raw.polyIndices.push_back(static_cast<uint32_t>(v.idx()));
    raw.polyOffsets.push_back(static_cast<uint32_t>(raw.polyIndices.size()));
    return FaceHandle(static_cast<int>(raw.polygonCount() - 1));
  }
  FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec2f>&) override {}
  void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec3f>&) override {}
  void set_face_texindex(FaceHandle, int) override {}
  void set_point(VertexHandle v, const Vec3f& p) override {
    if (valid(v)) raw.positions[static_cast<size_t>(v.idx())] = {p[0], p[1], p[2]};
  }
  void set_halfedge(VertexHandle, HalfedgeHandle) override {}
  void set_normal(VertexHandle v, const Vec3f& n) override { setNormal(v, {n[0], n[1], n[2]}); }
  void set_normal(VertexHandle v, const Vec3d& n) override { setNormal(v, {n[0], n[1], n[2]}); }
  void set_color(VertexHandle, const Vec3uc&) override {}
  void set_color(VertexHandle, const Vec4uc&) override {}
  void set_color(VertexHandle, const Vec3f&) override {}
  void set_color(VertexHandle, const Vec4f&) override {}
  void set_texcoord(VertexHandle v, const Vec2f& t) override {
    if (!valid(v)) return;
    vertexUV.resize(raw.positions.size(), glm::dvec2(0));
    vertexUV[static_cast<size_t>(v.idx())] = {t[0], t[1]};
    anyUV = true;
  }
  void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(HalfedgeHandle, HalfedgeHandle) override {}
  void set_face(HalfedgeHandle, FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HalfedgeHandle, const Vec2f&) override {}
  void set_texcoord(VertexHandle v, const Vec3f& t) override { set_texcoord(v, Vec2f(t[0], t[1])); }
  void set_texcoord(HalfedgeHandle, const Vec3f&) override {}
  void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(EdgeHandle, const Vec3uc&) override {}
  void set_color(EdgeHandle, const Vec4uc&) override {}
  void set_color(EdgeHandle, const Vec3f&) override {}
  void set_color(EdgeHandle, const Vec4f&) override {}
  void set_status(EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(FaceHandle, const Vec3f&) override {}
  void set_normal(FaceHandle, const Vec3d&) override {}
  void set_color(FaceHandle, const Vec3uc&) override {}
  void set_color(FaceHandle, const Vec4uc&) override {}
  void set_color(FaceHandle, const Vec3f&) override {}
  void set_color(FaceHandle, const Vec4f&) override {}
  void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}
  size_t n_vertices() const override { return raw.positions.size(); }
  size_t n_faces() const override { return raw.polygonCount(); }
  size_t n_edges() const override { return 0; }

 private:
  bool valid(VertexHandle v) const { return v.idx() >= 0 && static_cast<size_t>(v.idx()) < raw.positions.size(); }
  VertexHandle push(const glm::dvec3& p) {
    raw.positions.push_back(p);
    return VertexHandle(static_cast<int>(raw.positions.size() - 1));
  }
  void setNormal(VertexHandle v, const glm::dvec3& n) {
    if (!valid(v)) return;
    raw.vertexNormals.resize(raw.positions.size(), glm::dvec3(0));
    raw.vertexNormals[static_cast<size_t>(v.idx())] = n;
    anyNormal = true;
  }
};

}  // namespace

RawMesh readWithOpenMesh(const std::string& path) {
  if (!fileExists(path)) throw Error("cannot open mesh file (does it exist?)", path);
  checkMeshFileStructure(path);
  CaptureImporter imp;
  OpenMesh::IO::Options opt;
  opt += OpenMesh::IO::Options::VertexNormal;
  opt += OpenMesh::IO::Options::VertexTexCoord;
  bool ok = false;
  try {
    // OpenMesh's own log and error lines (omlog, omerr) would duplicate or precede pteryla's message.
    // OpenMesh buffers these streams and may flush them after our scope (or at exit): disable them.
    if (quiet()) {
      omerr().disable();
      omlog().disable();
      omout().disable();
    }
    const QuietThirdParty silence;
    ok = OpenMesh::IO::IOManager().read(path, imp, opt);
  } catch (const std::exception& e) {
    throw Error(std::string("mesh reader failed: ") + e.what(), path);
  }
  if (!ok) throw Error("OpenMesh could not read this file (malformed or unsupported " + extensionOf(path) + ")", path);
  RawMesh raw = std::move(imp.raw);
  if (!imp.anyNormal)
    raw.vertexNormals.clear();
  else
    raw.vertexNormals.resize(raw.positions.size(), glm::dvec3(0));
  if (imp.anyUV) {
    imp.vertexUV.resize(raw.positions.size(), glm::dvec2(0));
    raw.cornerUVs.reserve(raw.polyIndices.size());
    for (uint32_t v : raw.polyIndices)
      raw.cornerUVs.push_back(v < imp.vertexUV.size() ? imp.vertexUV[v] : glm::dvec2(0));
  }
  return raw;
}

}  // namespace pteryla::coat::detail
