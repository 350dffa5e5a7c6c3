// Tracts as named, possibly overlapping face sets with set operators (Streit 2003, 6.1).
#include "pteryla/coat/tracts.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"

namespace pteryla::coat {

bool Tract::contains(uint32_t face) const { return std::binary_search(faces.begin(), faces.end(), face); }

namespace {

void normalise(std::vector<uint32_t>& f) {
  std::sort(f.begin(), f.end());
  f.erase(std::unique(f.begin(), f.end()), f.end());
}

std::string groupList(const SkinMesh& mesh) {
  if (mesh.groupNames.empty()) return "the mesh has no face groups";
  std::string s = "known groups: ";
  for (size_t i = 0; i < mesh.groupNames.size(); ++i) s += (i ? ", " : "") + ("'" + mesh.groupNames[i] + "'");
  return s;
}

// Triangles [begin,end) of source polygon p (sourceFace is non-decreasing by construction).
std::pair<size_t, size_t> trianglesOf(const SkinMesh& mesh, uint32_t p) {
  const auto r = std::equal_range(mesh.sourceFace.begin(), mesh.sourceFace.end(), p);
  return {static_cast<size_t>(r.first - mesh.sourceFace.begin()),
          static_cast<size_t>(r.second - mesh.sourceFace.begin())};
}

}  // namespace

Tract wholeMeshTract(const SkinMesh& mesh, const std::string& name) {
  Tract t{name, {}};
  t.faces.resize(mesh.faces.size());
  for (uint32_t f = 0; f < t.faces.size(); ++f) t.faces[f] = f;
  return t;
}

Tract tractFromGroups(const SkinMesh& mesh, const std::string& name, const std::vector<std::string>& groups) {
  Tract t{name, {}};
  std::vector<uint8_t> want(mesh.groupNames.size(), 0);
  for (const auto& g : groups) {
    bool found = false;
    for (size_t i = 0; i < mesh.groupNames.size(); ++i)
      if (mesh.groupMatches(static_cast<int32_t>(i), g)) want[i] = 1, found = true;
    if (!found)
      throw Error("unknown face group '" + g + "' (" + groupList(mesh) + ")", mesh.file, "tract '" + name + "'");
  }
  for (uint32_t f = 0; f < mesh.faceGroup.size(); ++f)
    if (mesh.faceGroup[f] >= 0 && want[static_cast<size_t>(mesh.faceGroup[f])]) t.faces.push_back(f);
  return t;
}

Tract tractFromSourceFaces(const SkinMesh& mesh, const std::string& name, const std::vector<int64_t>& sourceFaces) {
  Tract t{name, {}};
  for (int64_t p : sourceFaces) {
    if (p < 0 || static_cast<size_t>(p) >= mesh.sourceFaceCount)
      throw Error("face index " + std::to_string(p) + " is out of range (mesh has " +
                      std::to_string(mesh.sourceFaceCount) + " faces)",
                  mesh.file, "tract '" + name + "'");
    const auto [b, e] = trianglesOf(mesh, static_cast<uint32_t>(p));
    for (size_t k = b; k < e; ++k) t.faces.push_back(static_cast<uint32_t>(k));
  }
  normalise(t.faces);
  return t;
}

Tract tractFromLabels(const SkinMesh& mesh, const std::string& name, const std::vector<int64_t>& labels,
                      const std::vector<int64_t>& wanted) {
  if (labels.size() != mesh.sourceFaceCount)
    throw Error("label list has " + std::to_string(labels.size()) + " entries but the mesh has " +
                    std::to_string(mesh.sourceFaceCount) + " faces",
                mesh.file, "tract '" + name + "'");
  Tract t{name, {}};
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const int64_t l = labels[mesh.sourceFace[f]];
    if (l >= 0 && std::find(wanted.begin(), wanted.end(), l) != wanted.end()) t.faces.push_back(f);
  }
  return t;
}

std::vector<int64_t> readFaceLabels(const std::string& path, size_t expectedCount) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open label file (does it exist?)", path);
  std::vector<int64_t> out;
  out.reserve(expectedCount);
  std::string line;
  size_t lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ss(line);
    std::string tok;
    while (ss >> tok) {
      int64_t v = 0;
      const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (r.ec != std::errc() || r.ptr != tok.data() + tok.size())
        throw Error("'" + tok + "' is not an integer label (expected one integer per face)", path,
                    "line " + std::to_string(lineNo));
      out.push_back(v);
    }
  }
  if (out.size() != expectedCount)
    throw Error("label file has " + std::to_string(out.size()) + " labels but the mesh has " +
                    std::to_string(expectedCount) + " faces (one label per face, in file order)",
                path, "line " + std::to_string(lineNo));
  return out;
}

Tract tractUnion(const Tract& a, const Tract& b, const std::string& name) {
  Tract t{name.empty() ? a.name : name, {}};
  std::set_union(a.faces.begin(), a.faces.end(), b.faces.begin(), b.faces.end(), std::back_inserter(t.faces));
  return t;
}

Tract tractIntersection(const Tract& a, const Tract& b, const std::string& name) {
  Tract t{name.empty() ? a.name : name, {}};
  std::set_intersection(a.faces.begin(), a.faces.end(), b.faces.begin(), b.faces.end(), std::back_inserter(t.faces));
  return t;
}

Tract tractDifference(const Tract& a, const Tract& b, const std::string& name) {
  Tract t{name.empty() ? a.name : name, {}};
  std::set_difference(a.faces.begin(), a.faces.end(), b.faces.begin(), b.faces.end(), std::back_inserter(t.faces));
  return t;
}

namespace {

std::vector<std::string> stringList(JsonReader& r, const std::string& key) {
  const Json& v = r.raw(key);
  if (v.is_string()) return {v.get<std::string>()};
  if (!v.is_array()) r.fail(key, "expected a name or an array of names");
  std::vector<std::string> out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_string())
      throw Error("expected a name (string)", r.file(), r.pathOf(key) + "[" + std::to_string(i) + "]");
    out.push_back(v[i].get<std::string>());
  }
  return out;
}

std::vector<int64_t> intList(JsonReader& r, const std::string& key) {
  const Json& v = r.raw(key);
  if (v.is_number_integer()) return {v.get<int64_t>()};
  if (!v.is_array()) r.fail(key, "expected an integer or an array of integers");
  std::vector<int64_t> out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number_integer())
      throw Error("expected an integer", r.file(), r.pathOf(key) + "[" + std::to_string(i) + "]");
    out.push_back(v[i].get<int64_t>());
  }
  return out;
}

Tract resolveRef(JsonReader& r, const std::string& key, size_t idx, const std::string& ref, const SkinMesh& mesh,
                 const std::vector<Tract>& earlier) {
  for (const auto& t : earlier)
    if (t.name == ref) return t;
  if (mesh.findGroup(ref) >= 0) return tractFromGroups(mesh, ref, {ref});
  std::string known;
  for (const auto& t : earlier) known += (known.empty() ? "" : ", ") + ("'" + t.name + "'");
  throw Error("'" + ref + "' is neither an earlier tract (" + (known.empty() ? "none defined yet" : known) +
                  ") nor a face group (" + groupList(mesh) + ")",
              r.file(), r.pathOf(key) + "[" + std::to_string(idx) + "]");
}

}  // namespace

Tract readTract(JsonReader& r, const SkinMesh& mesh, const std::vector<Tract>& earlier) {
  Tract t;
  t.name = r.string("name");
  if (t.name.empty()) r.fail("name", "tract name must not be empty");
  bool additive = false;
  auto addAll = [&](const Tract& s) { t = tractUnion(t, s, t.name); };

  if (r.boolean("all", false)) {
    addAll(wholeMeshTract(mesh));
    additive = true;
  }
  if (r.has("groups")) {
    const auto names = stringList(r, "groups");
    for (size_t i = 0; i < names.size(); ++i) {
      bool found = false;
      for (size_t g = 0; g < mesh.groupNames.size() && !found; ++g)
        found = mesh.groupMatches(static_cast<int32_t>(g), names[i]);
      if (!found)
        throw Error("unknown face group '" + names[i] + "' (" + groupList(mesh) + ")", r.file(),
                    r.pathOf("groups") + "[" + std::to_string(i) + "]");
    }
    addAll(tractFromGroups(mesh, t.name, names));
    additive = true;
  }
  if (r.has("faces")) {
    const auto faces = intList(r, "faces");
    for (size_t i = 0; i < faces.size(); ++i)
      if (faces[i] < 0 || static_cast<size_t>(faces[i]) >= mesh.sourceFaceCount)
        throw Error("face index " + std::to_string(faces[i]) + " is out of range (mesh has " +
                        std::to_string(mesh.sourceFaceCount) + " faces)",
                    r.file(), r.pathOf("faces") + "[" + std::to_string(i) + "]");
    addAll(tractFromSourceFaces(mesh, t.name, faces));
    additive = true;
  }
  const bool hasFile = r.has("labels_file"), hasLabel = r.has("label");
  if (hasFile != hasLabel)
    r.fail(hasFile ? "labels_file" : "label", "'labels_file' and 'label' must be given together");
  if (hasFile) {
    const std::string path = resolveRelative(r.file(), r.string("labels_file"));
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
      r.fail("labels_file", "'" + path + "' is a directory; expected a file of face labels");
    if (!std::filesystem::exists(path, ec)) r.fail("labels_file", "label file '" + path + "' does not exist");
    const auto wanted = intList(r, "label");
    const auto labels = readFaceLabels(path, mesh.sourceFaceCount);
    addAll(tractFromLabels(mesh, t.name, labels, wanted));
    additive = true;
  } else {
    r.allow("labels_file");
    r.allow("label");
  }
  if (r.has("union")) {
    const auto refs = stringList(r, "union");
    for (size_t i = 0; i < refs.size(); ++i) addAll(resolveRef(r, "union", i, refs[i], mesh, earlier));
    additive = true;
  } else {
    r.allow("union");
  }
  if (!additive) t = wholeMeshTract(mesh, t.name);
  if (r.has("intersect")) {
    const auto refs = stringList(r, "intersect");
    for (size_t i = 0; i < refs.size(); ++i)
      t = tractIntersection(t, resolveRef(r, "intersect", i, refs[i], mesh, earlier), t.name);
  } else {
    r.allow("intersect");
  }
  if (r.has("subtract")) {
    const auto refs = stringList(r, "subtract");
    for (size_t i = 0; i < refs.size(); ++i)
      t = tractDifference(t, resolveRef(r, "subtract", i, refs[i], mesh, earlier), t.name);
  } else {
    r.allow("subtract");
  }
  if (!r.has("groups")) r.allow("groups");
  if (!r.has("faces")) r.allow("faces");
  if (t.faces.empty()) r.fail("", "tract '" + t.name + "' selects no faces");
  return t;
}

std::vector<Tract> readTracts(std::vector<JsonReader>& items, const SkinMesh& mesh) {
  std::vector<Tract> out;
  for (auto& r : items) {
    Tract t = readTract(r, mesh, out);
    for (const auto& o : out)
      if (o.name == t.name) r.fail("name", "duplicate tract name '" + t.name + "'");
    out.push_back(std::move(t));
  }
  return out;
}

std::vector<Tract> loadTractFile(const std::string& path, const SkinMesh& mesh) {
  const Json j = readJsonFile(path);
  JsonReader top(j, path);
  auto items = top.objects("tracts");
  top.finish();
  if (items.empty()) return {wholeMeshTract(mesh)};
  auto tracts = readTracts(items, mesh);
  for (const auto& r : items) r.finish();
  return tracts;
}

double tractArea(const SkinMesh& mesh, const Tract& tract) {
  double a = 0;
  for (uint32_t f : tract.faces) a += mesh.faceAreas[f];
  return a;
}

std::vector<uint8_t> tractFaceMask(const SkinMesh& mesh, const Tract& tract) {
  std::vector<uint8_t> m(mesh.faces.size(), 0);
  for (uint32_t f : tract.faces) {
    PTERYLA_CHECK(f < m.size(), "tract face index out of range");
    m[f] = 1;
  }
  return m;
}

std::vector<uint8_t> tractBoundaryEdgeBits(const SkinMesh& mesh, const Tract& tract) {
  const auto mask = tractFaceMask(mesh, tract);
  std::vector<uint8_t> bits(tract.faces.size(), 0);
  for (size_t k = 0; k < tract.faces.size(); ++k) {
    const uint32_t f = tract.faces[k];
    for (int c = 0; c < 3; ++c) {
      const int32_t g = mesh.faceNeighbors[f][c];
      if (g < 0 || !mask[static_cast<size_t>(g)]) bits[k] |= static_cast<uint8_t>(1u << c);
    }
  }
  return bits;
}

std::vector<std::array<glm::dvec3, 2>> tractBoundarySegments(const SkinMesh& mesh, const Tract& tract) {
  const auto bits = tractBoundaryEdgeBits(mesh, tract);
  std::vector<std::array<glm::dvec3, 2>> segs;
  for (size_t k = 0; k < tract.faces.size(); ++k)
    for (int c = 0; c < 3; ++c)
      if (bits[k] & (1u << c)) {
        const auto& f = mesh.faces[tract.faces[k]];
        segs.push_back({mesh.positions[f[c]], mesh.positions[f[(c + 1) % 3]]});
      }
  return segs;
}

}  // namespace pteryla::coat
