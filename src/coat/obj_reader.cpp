// Wavefront OBJ reader for skin meshes. Own reader because tracts (Streit 2003, 6.1: "groups of polygons
// that belong to each feather tract") come from the file's face groups, which OpenMesh's reader drops.
// Reads v, vt, vn, f (v, v/t, v//n, v/t/n, negative indices), g, o, usemtl; ignores everything else.
#include <charconv>
#include <cstring>
#include <string_view>
#include <fstream>
#include <map>
#include <sstream>

#include "mesh_io.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::coat::detail {
namespace {

struct Cursor {
  const char* p;
  const char* end;
  void skipSpace() {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
  }
  bool atEnd() {
    skipSpace();
    return p >= end;
  }
  std::string_view token() {
    skipSpace();
    const char* b = p;
    while (p < end && *p != ' ' && *p != '\t' && *p != '\r') ++p;
    return {b, static_cast<size_t>(p - b)};
  }
};

class ObjParser {
 public:
  explicit ObjParser(std::string path) : path_(std::move(path)) {}

  RawMesh parse() {
    std::ifstream in(path_, std::ios::binary);
    if (!in) throw Error("cannot open mesh file (does it exist?)", path_);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    const char* p = text.data();
    const char* end = p + text.size();
    std::string joined;
    while (p < end) {
      ++line_;
      const char* nl = static_cast<const char*>(memchr(p, '\n', static_cast<size_t>(end - p)));
      const char* le = nl ? nl : end;
      const char* next = nl ? nl + 1 : end;
      // Line continuation: a trailing backslash joins the next line.
      const char* trim = le;
      while (trim > p && (trim[-1] == '\r' || trim[-1] == ' ' || trim[-1] == '\t')) --trim;
      if (trim > p && trim[-1] == '\\') {
        joined.assign(p, trim - 1);
        const int startLine = line_;
        while (next < end) {
          ++line_;
          const char* nl2 = static_cast<const char*>(memchr(next, '\n', static_cast<size_t>(end - next)));
          const char* le2 = nl2 ? nl2 : end;
          const char* t2 = le2;
          while (t2 > next && (t2[-1] == '\r' || t2[-1] == ' ' || t2[-1] == '\t')) --t2;
          const bool more = t2 > next && t2[-1] == '\\';
          joined.push_back(' ');
          joined.append(next, more ? t2 - 1 : le2);
          next = nl2 ? nl2 + 1 : end;
          if (!more) break;
        }
        const int endLine = line_;
        line_ = startLine;
        parseLine(joined.data(), joined.data() + joined.size());
        line_ = endLine;
      } else {
        parseLine(p, le);
      }
      p = next;
    }
    return finish();
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw Error(what, path_, "line " + std::to_string(line_)); }

  double number(Cursor& c, const char* what) {
    const std::string_view t = c.token();
    if (t.empty()) fail(std::string("missing ") + what);
    double v = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size()) {
      // from_chars rejects "nan"/"inf" spellings some exporters write in other forms; accept a leading '+'.
      if (!t.empty() && t[0] == '+') {
        const auto r2 = std::from_chars(t.data() + 1, t.data() + t.size(), v);
        if (r2.ec == std::errc() && r2.ptr == t.data() + t.size()) return v;
      }
      fail(std::string("cannot parse ") + what + " '" + std::string(t) + "'");
    }
    return v;
  }

  // Resolves a 1-based (or negative, relative) OBJ index against `count` elements.
  uint32_t index(std::string_view t, size_t count, const char* what) {
    long long i = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), i);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      fail("face " + std::to_string(polyCount()) + ": cannot parse " + what + " index '" + std::string(t) + "'");
    long long resolved = i > 0 ? i - 1 : static_cast<long long>(count) + i;
    if (i == 0 || resolved < 0 || resolved >= static_cast<long long>(count))
      fail("face " + std::to_string(polyCount()) + ": " + what + " index " + std::to_string(i) + " is out of range (" +
           std::to_string(count) + " defined so far)");
    return static_cast<uint32_t>(resolved);
  }

  size_t polyCount() const { return raw_.polyOffsets.size() - 1; }

  void parseLine(const char* b, const char* e) {
    Cursor c{b, e};
    const std::string_view kw = c.token();
    if (kw.empty() || kw[0] == '#') return;
    if (kw == "v") {
      glm::dvec3 v;
      v.x = number(c, "vertex x coordinate");
      v.y = number(c, "vertex y coordinate");
      v.z = number(c, "vertex z coordinate");
      raw_.positions.push_back(v);  // extra values (w, vertex colours) are ignored
    } else if (kw == "vt") {
      glm::dvec2 t;
      t.x = number(c, "texture u coordinate");
      t.y = c.atEnd() ? 0.0 : number(c, "texture v coordinate");
      uvs_.push_back(t);
    } else if (kw == "vn") {
      glm::dvec3 n;
      n.x = number(c, "normal x");
      n.y = number(c, "normal y");
      n.z = number(c, "normal z");
      normals_.push_back(n);
    } else if (kw == "f" || kw == "fo") {
      parseFace(c);
    } else if (kw == "g") {
      std::string names;
      while (!c.atEnd()) {
        const std::string_view t = c.token();
        if (!names.empty()) names.push_back(' ');
        names.append(t);
      }
      sawG_ = true;
      curG_ = (names.empty() || names == "default") ? -1 : groupId(gNames_, names);
    } else if (kw == "o") {
      const std::string name = rest(c);
      sawO_ = true;
      curO_ = name.empty() ? -1 : groupId(oNames_, name);
    } else if (kw == "usemtl") {
      const std::string name = rest(c);
      sawM_ = true;
      curM_ = name.empty() ? -1 : groupId(mNames_, name);
    }
  }

  static std::string rest(Cursor& c) {
    std::string out;
    while (!c.atEnd()) {
      if (!out.empty()) out.push_back(' ');
      out.append(c.token());
    }
    return out;
  }

  static int32_t groupId(std::map<std::string, int32_t>& names, const std::string& n) {
    const auto it = names.find(n);
    if (it != names.end()) return it->second;
    const int32_t id = static_cast<int32_t>(names.size());
    names.emplace(n, id);
    return id;
  }

  void parseFace(Cursor& c) {
    size_t corners = 0;
    bool allUV = true;
    while (!c.atEnd()) {
      const std::string_view t = c.token();
      const size_t s1 = t.find('/');
      const std::string_view vs = t.substr(0, s1);
      raw_.polyIndices.push_back(index(vs, raw_.positions.size(), "vertex"));
      bool hasUV = false;
      if (s1 != std::string_view::npos) {
        const std::string_view r = t.substr(s1 + 1);
        const size_t s2 = r.find('/');
        const std::string_view ts = r.substr(0, s2);
        if (!ts.empty()) {
          cornerUV_.push_back(uvs_[index(ts, uvs_.size(), "texture")]);
          hasUV = true;
        }
        if (s2 != std::string_view::npos) {
          const std::string_view ns = r.substr(s2 + 1);
          if (!ns.empty()) {
            const uint32_t ni = index(ns, normals_.size(), "normal");
            const uint32_t vi = raw_.polyIndices.back();
            if (vertexNormalSum_.size() <= vi) vertexNormalSum_.resize(raw_.positions.size(), glm::dvec3(0));
            vertexNormalSum_[vi] += normals_[ni];
          }
        }
      }
      if (!hasUV) {
        cornerUV_.push_back(glm::dvec2(0));
        allUV = false;
      }
      ++corners;
    }
    if (!allUV) allCornersUV_ = false;
    raw_.polyOffsets.push_back(static_cast<uint32_t>(raw_.polyIndices.size()));
    polyG_.push_back(curG_);
    polyO_.push_back(curO_);
    polyM_.push_back(curM_);
    raw_.polyLine.push_back(static_cast<uint32_t>(line_));
    (void)corners;
  }

  RawMesh finish() {
    // One grouping kind: g if the file has any g statement with names, else o, else usemtl.
    const std::map<std::string, int32_t>* names = nullptr;
    const std::vector<int32_t>* ids = nullptr;
    if (sawG_ && !gNames_.empty()) {
      names = &gNames_;
      ids = &polyG_;
    } else if (sawO_ && !oNames_.empty()) {
      names = &oNames_;
      ids = &polyO_;
    } else if (sawM_ && !mNames_.empty()) {
      names = &mNames_;
      ids = &polyM_;
    }
    if (names) {
      raw_.groupNames.resize(names->size());
      for (const auto& [n, i] : *names) raw_.groupNames[static_cast<size_t>(i)] = n;
      raw_.polyGroup = *ids;
    }
    if (allCornersUV_ && !raw_.polyIndices.empty()) raw_.cornerUVs = std::move(cornerUV_);
    if (!vertexNormalSum_.empty()) {
      vertexNormalSum_.resize(raw_.positions.size(), glm::dvec3(0));
      raw_.vertexNormals = std::move(vertexNormalSum_);
    }
    return std::move(raw_);
  }

  std::string path_;
  int line_ = 0;
  RawMesh raw_;
  std::vector<glm::dvec2> uvs_, cornerUV_;
  std::vector<glm::dvec3> normals_, vertexNormalSum_;
  bool allCornersUV_ = true;
  bool sawG_ = false, sawO_ = false, sawM_ = false;
  int32_t curG_ = -1, curO_ = -1, curM_ = -1;
  std::map<std::string, int32_t> gNames_, oNames_, mNames_;
  std::vector<int32_t> polyG_, polyO_, polyM_;
};

}  // namespace

RawMesh readObj(const std::string& path) { return ObjParser(path).parse(); }

}  // namespace pteryla::coat::detail
