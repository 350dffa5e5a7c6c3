// USD text (.usda) writer, specified by the UsdGeom schemas (Mesh, BasisCurves, PointInstancer) and the
// usda layer syntax; OpenUSD itself is not needed. One layer:
//
//   /pteryla                 Xform, defaultPrim
//     skin                   Mesh (points, faceVertexCounts, faceVertexIndices, normals, displayColor)
//     coat                   Xform
//       rachises, barbs      BasisCurves (--as curves): type "linear", wrap "nonperiodic" (basis is
//                            ignored for linear curves and not authored); one rachis per present feather
//                            through its shaft rings' centres, one barb per kept barb along its card's
//                            centre row
//       cards                Mesh (--as cards): the vane cards and shafts as triangles
//       feathers             PointInstancer (--as instances), prototypes under feathers/Prototypes
//
// Units: upAxis "Y", metersPerUnit from ExportOptions. A frame range authors every attribute that can
// change as timeSamples keyed by time code = scene time x fps (timeCodesPerSecond = fps). Float text is
// the shortest decimal that reads back as the same float, so a reader gets the exact values.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>

#include "frames.hpp"
#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::exchange::detail {
namespace {

// Formatted text in pieces, in order: a large array is formatted in chunks and written chunk by chunk,
// never joined into one string.
struct Text {
  std::vector<std::string> parts;
};

// The file as it is written: small text gathers in a buffer, large pieces go straight to the file. Nothing
// of the size of the whole file is ever held in memory.
struct Out {
  AtomicFile& file;
  std::string s;
  size_t bytes = 0;
  explicit Out(AtomicFile& f) : file(f) {}
  void flush() {
    if (s.empty()) return;
    file.write(s);
    bytes += s.size();
    s.clear();
  }
  void flushIfFull() {
    if (s.size() >= (size_t(1) << 20)) flush();
  }
  void line(int indent, const std::string& text) {
    s.append(size_t(indent) * 4, ' ');
    s += text;
    s += '\n';
    flushIfFull();
  }
  void append(const std::string& text) {
    if (text.size() < (size_t(1) << 16)) {
      s += text;
      flushIfFull();
      return;
    }
    flush();
    file.write(text);
    bytes += text.size();
  }
  void append(const Text& t) {
    for (const std::string& p : t.parts) append(p);
  }
};

// Numbers are formatted straight into a preallocated buffer (no temporary string per value): the cards of
// a full-detail bird are hundreds of megabytes of text. fmt() writes at most kMaxChars<T> characters.
struct Quat {
  float w, x, y, z;
};
template <class T>
constexpr size_t kMaxChars = 0;
template <>
constexpr size_t kMaxChars<float> = 16;  // shortest round-trip float: "-1.1754944e-38"
template <>
constexpr size_t kMaxChars<int64_t> = 20;  // "-9223372036854775808"
template <>
constexpr size_t kMaxChars<glm::vec2> = 2 + 2 * 16 + 2;
template <>
constexpr size_t kMaxChars<glm::vec3> = 2 + 3 * 16 + 4;
template <>
constexpr size_t kMaxChars<Quat> = 2 + 4 * 16 + 6;

char* fmt(char* p, float v) { return std::to_chars(p, p + kMaxChars<float>, v).ptr; }
char* fmt(char* p, int64_t v) { return std::to_chars(p, p + kMaxChars<int64_t>, v).ptr; }
template <size_t N>
char* tuple(char* p, const float (&c)[N]) {
  *p++ = '(';
  for (size_t i = 0; i < N; ++i) {
    if (i) *p++ = ',', *p++ = ' ';
    p = fmt(p, c[i]);
  }
  *p++ = ')';
  return p;
}
char* fmt(char* p, const glm::vec2& v) { return tuple(p, {v.x, v.y}); }
char* fmt(char* p, const glm::vec3& v) { return tuple(p, {v.x, v.y, v.z}); }
char* fmt(char* p, const Quat& q) { return tuple(p, {q.w, q.x, q.y, q.z}); }

template <class T>
void put(std::string& o, const T& v) {
  static_assert(kMaxChars<T> > 0, "no fmt() bound for this type");
  char buf[kMaxChars<T>];
  o.append(buf, fmt(buf, v));
}

// "[a, b, ...]". Large arrays are formatted in chunks on every core, kept in order: the same bytes as
// formatting them one by one. A value equal (bit for bit: -0 is not 0) to the one before it copies its
// text, which makes per-face colours, ids and counts cheap.
template <class T>
Text array(const std::vector<T>& v) {
  static_assert(kMaxChars<T> > 0, "no fmt() bound for this type");
  constexpr size_t kChunk = 1 << 14;
  const size_t chunks = (v.size() + kChunk - 1) / kChunk;
  auto format = [&](size_t c, std::string& o) {
    const size_t begin = c * kChunk, end = std::min(v.size(), (c + 1) * kChunk);
    const size_t at = o.size();
    o.resize(at + (end - begin) * (kMaxChars<T> + 2));
    char* const base = o.data();
    char* p = base + at;
    const char* prev = nullptr;
    size_t prevLength = 0;
    for (size_t i = begin; i < end; ++i) {
      if (i) *p++ = ',', *p++ = ' ';
      if (prev && std::memcmp(&v[i], &v[i - 1], sizeof(T)) == 0) {
        std::memcpy(p, prev, prevLength);
        prev = p;
        p += prevLength;
      } else {
        prev = p;
        p = fmt(p, v[i]);
        prevLength = size_t(p - prev);
      }
    }
    o.resize(size_t(p - base));
  };
  Text t;
  t.parts.resize(std::max<size_t>(1, chunks));
  t.parts.front() = "[";
  if (chunks <= 1) {
    if (chunks == 1) format(0, t.parts.front());
  } else {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t c = r.begin(); c != r.end(); ++c) format(c, t.parts[c]);
    });
  }
  t.parts.back() += ']';
  return t;
}

// One attribute over the frames: a default value for one frame, timeSamples for several. `meta` is the
// attribute's metadata text ("interpolation = \"vertex\"") or empty. Values are formatted when written,
// so only one attribute's text is alive at a time.
struct Attr {
  std::string decl;  // "point3f[] points"
  std::string meta;
  std::vector<std::function<Text()>> values;  // per frame
};

void emit(Out& o, int indent, const Attr& a, const std::vector<double>& codes) {
  const std::string meta = a.meta.empty() ? "" : " (" + a.meta + ")";
  if (a.values.size() == 1) {  // appended piece by piece: values can be hundreds of megabytes
    o.s.append(size_t(indent) * 4, ' ');
    o.s += a.decl;
    o.s += " = ";
    o.append(a.values[0]());
    o.s += meta;
    o.s += '\n';
    o.flushIfFull();
    return;
  }
  if (!a.meta.empty()) o.line(indent, a.decl + meta);
  o.line(indent, a.decl + ".timeSamples = {");
  for (size_t k = 0; k < a.values.size(); ++k) {
    o.s.append(size_t(indent + 1) * 4, ' ');
    o.s += shortest(codes[k]);
    o.s += ": ";
    o.append(a.values[k]());
    o.s += ",\n";
    o.flushIfFull();
  }
  o.line(indent, "}");
}

Text extentOf(const std::vector<glm::vec3>& p, const std::vector<float>* widths) {
  glm::vec3 lo(0.0f), hi(0.0f);
  for (size_t i = 0; i < p.size(); ++i) {
    const float r = widths ? 0.5f * (*widths)[i] : 0.0f;
    const glm::vec3 a = p[i] - glm::vec3(r), b = p[i] + glm::vec3(r);
    lo = i ? glm::min(lo, a) : a;
    hi = i ? glm::max(hi, b) : b;
  }
  return array(std::vector<glm::vec3>{lo, hi});
}

// Curves of one frame: per curve its points, widths (diameters), st and per-feather values.
struct Curves {
  std::vector<int64_t> counts;
  std::vector<glm::vec3> points;
  std::vector<float> widths;
  std::vector<glm::vec2> st;
  std::vector<int64_t> fid, tract, layer;
  std::vector<float> age;
  std::vector<glm::vec3> color;
  void addFeather(const FeatherRecord& r, const glm::vec3& c) {
    fid.push_back(r.id);
    tract.push_back(r.tract);
    layer.push_back(r.layer);
    age.push_back(r.age);
    color.push_back(c);
  }
};

// st for curves (Yeti, Houdini): s along the rachis (uvGlobal v), t across: 0-0.5 left vane, 0.5-1 right
// (uvGlobal u runs 0 at the left edge to 1 at the right edge, feather/mesh.hpp).
glm::vec2 curveSt(const TriMesh& m, uint32_t v) {
  return m.uvGlobal.empty() ? glm::vec2(0.0f) : glm::vec2(m.uvGlobal[v].y, m.uvGlobal[v].x);
}

void buildCurves(const ExportScene& s, const ExportFrame& f, Curves& rachis, Curves& barbs) {
  const TriMesh& m = f.coat;
  std::vector<glm::vec3> pts;
  std::vector<float> w;
  std::vector<uint32_t> verts;
  std::vector<BarbRow> vane;
  for (const pipeline::CoatDrawRange& r : f.ranges) {
    const FeatherRecord& rec = f.feathers[r.feather];
    const glm::vec3 colour = r.material < s.materials.size() ? s.materials[r.material].baseColor : glm::vec3(0.8f);
    rachisCurve(m, r.firstIndex, r.partCount[0], pts, w, verts);
    if (!pts.empty()) {
      rachis.counts.push_back(int64_t(pts.size()));
      rachis.points.insert(rachis.points.end(), pts.begin(), pts.end());
      rachis.widths.insert(rachis.widths.end(), w.begin(), w.end());
      for (uint32_t v : verts) rachis.st.push_back(glm::vec2(curveSt(m, v).x, 0.5f));
      rachis.addFeather(rec, colour);
    }
    // Vanes: left, right, then the afterfeather's range (its own shaft is not a rachis here).
    uint32_t first = r.firstIndex + r.partCount[0];
    for (int part = 1; part <= 2; ++part) {
      vane.clear();
      vaneBarbs(m, first, r.partCount[part], vane);
      first += r.partCount[part];
      for (const BarbRow& b : vane) {
        barbs.counts.push_back(int64_t(b.count));
        for (uint32_t k = 0; k < b.count; ++k) {
          const uint32_t v = b.centre + k;
          barbs.points.push_back(m.positions[v]);
          // The card's width here: between the side rows around the centre row, so the curves cover
          // what the cards cover.
          barbs.widths.push_back(glm::length(m.positions[v + b.rowLength] - m.positions[v - b.rowLength]));
          barbs.st.push_back(curveSt(m, v));
        }
        barbs.addFeather(rec, colour);
      }
    }
  }
}

struct MeshData {
  std::vector<int64_t> counts, indices;
  std::vector<glm::vec3> points, normals;
  std::vector<glm::vec2> st;
  std::vector<float> opacity;
  std::vector<int64_t> fid, tract, layer;
  std::vector<float> age;
  std::vector<glm::vec3> color;
};

// Triangles of `tris` with compacted vertices; per-face feather values when `feathers`.
void buildMesh(const TriMesh& m, const std::vector<uint32_t>& tris, const ExportFrame* f, const ExportScene* s,
               MeshData& d, const glm::dvec3* localOrigin = nullptr, const glm::dvec3* axes = nullptr,
               double invScale = 1) {
  // New vertex index per mesh vertex in first-use order. A flat table when the triangles touch much of the
  // mesh (the cards of a full-detail bird: millions of vertices), a map for one prototype feather.
  const bool dense = 3 * tris.size() * 8 >= m.positions.size() || (!f && !localOrigin);
  std::vector<int64_t> table(dense ? m.positions.size() : 0, -1);
  std::map<uint32_t, int64_t> sparse;
  std::vector<uint32_t> order;
  auto indexOf = [&](uint32_t v) {
    int64_t* slot = dense ? &table[v] : &sparse.try_emplace(v, -1).first->second;
    if (*slot < 0) {
      *slot = int64_t(order.size());
      order.push_back(v);
    }
    return *slot;
  };
  if (!f && !localOrigin)  // the skin keeps its vertex order (a host's poses and weights index it)
    for (uint32_t v = 0; v < m.positions.size(); ++v) indexOf(v);
  d.counts.reserve(d.counts.size() + tris.size());
  d.indices.reserve(d.indices.size() + 3 * tris.size());
  for (uint32_t t : tris) {
    d.counts.push_back(3);
    for (int c = 0; c < 3; ++c) d.indices.push_back(indexOf(m.indices[3 * size_t(t) + size_t(c)]));
    if (f) {
      const FeatherRecord& r = f->feathers[m.featherId.empty() ? 0 : m.featherId[m.indices[3 * size_t(t)]]];
      d.fid.push_back(r.id);
      d.tract.push_back(r.tract);
      d.layer.push_back(r.layer);
      d.age.push_back(r.age);
      d.color.push_back(r.material < s->materials.size() ? s->materials[r.material].baseColor : glm::vec3(0.8f));
    }
  }
  for (uint32_t v : order) {
    glm::vec3 p = m.positions[v], n = m.normals.empty() ? glm::vec3(0, 0, 1) : m.normals[v].get();
    if (localOrigin) {  // into the feather's local frame, scaled to unit length
      const glm::dvec3 q = glm::dvec3(p) - *localOrigin;
      p = glm::vec3(float(glm::dot(q, axes[0]) * invScale), float(glm::dot(q, axes[1]) * invScale),
                    float(glm::dot(q, axes[2]) * invScale));
      const glm::dvec3 nd(n);
      n = glm::vec3(float(glm::dot(nd, axes[0])), float(glm::dot(nd, axes[1])), float(glm::dot(nd, axes[2])));
    }
    d.points.push_back(p);
    d.normals.push_back(n);
    if (!m.uvGlobal.empty()) d.st.push_back(m.uvGlobal[v]);
    if (!m.alpha.empty()) d.opacity.push_back(m.alpha[v]);
  }
}

std::vector<uint32_t> liveTriangles(const TriMesh& m, uint32_t first, uint32_t count) {
  std::vector<uint32_t> t;
  for (uint32_t i = first / 3; i < (first + count) / 3; ++i)
    if (!collapsed(&m.indices[3 * size_t(i)])) t.push_back(i);
  return t;
}

Quat quatOf(const glm::dvec3& x, const glm::dvec3& y, const glm::dvec3& z) {
  // Rotation whose columns are x, y, z (orthonormal, right-handed).
  const double tr = x.x + y.y + z.z;
  double w, qx, qy, qz;
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2;
    w = 0.25 * s;
    qx = (y.z - z.y) / s;
    qy = (z.x - x.z) / s;
    qz = (x.y - y.x) / s;
  } else if (x.x > y.y && x.x > z.z) {
    const double s = std::sqrt(1.0 + x.x - y.y - z.z) * 2;
    w = (y.z - z.y) / s;
    qx = 0.25 * s;
    qy = (y.x + x.y) / s;
    qz = (z.x + x.z) / s;
  } else if (y.y > z.z) {
    const double s = std::sqrt(1.0 + y.y - x.x - z.z) * 2;
    w = (z.x - x.z) / s;
    qx = (y.x + x.y) / s;
    qy = 0.25 * s;
    qz = (z.y + y.z) / s;
  } else {
    const double s = std::sqrt(1.0 + z.z - x.x - y.y) * 2;
    w = (x.y - y.x) / s;
    qx = (z.x + x.z) / s;
    qy = (z.y + y.z) / s;
    qz = 0.25 * s;
  }
  const double l = std::sqrt(w * w + qx * qx + qy * qy + qz * qz);
  return {float(w / l), float(qx / l), float(qy / l), float(qz / l)};
}

// Length of a present feather along its shaft axis (the largest local x of its vertices).
double featherLength(const ExportFrame& f, const pipeline::CoatDrawRange& r) {
  const FeatherRecord& rec = f.feathers[r.feather];
  double len = 0;
  for (uint32_t i = r.firstIndex; i < r.firstIndex + r.indexCount; ++i)
    len = std::max(len, glm::dot(glm::dvec3(f.coat.positions[f.coat.indices[i]]) - rec.origin, rec.x));
  return len;
}

// The attributes refer to `d`, which must outlive their emit().
void meshAttrs(std::vector<Attr>& attrs, const std::vector<MeshData>& d, bool perFeather) {
  auto add = [&](const std::string& decl, const std::string& meta, auto get) {
    Attr a{decl, meta, {}};
    for (const MeshData& m : d) a.values.push_back([&m, get] { return get(m); });
    attrs.push_back(std::move(a));
  };
  add("float3[] extent", "", [](const MeshData& m) { return extentOf(m.points, nullptr); });
  add("int[] faceVertexCounts", "", [](const MeshData& m) { return array(m.counts); });
  add("int[] faceVertexIndices", "", [](const MeshData& m) { return array(m.indices); });
  add("point3f[] points", "", [](const MeshData& m) { return array(m.points); });
  add("normal3f[] normals", "interpolation = \"vertex\"", [](const MeshData& m) { return array(m.normals); });
  if (!d.front().st.empty())
    add("texCoord2f[] primvars:st", "interpolation = \"vertex\"", [](const MeshData& m) { return array(m.st); });
  if (!d.front().opacity.empty())
    add("float[] primvars:displayOpacity", "interpolation = \"vertex\"",
        [](const MeshData& m) { return array(m.opacity); });
  if (perFeather) {
    add("color3f[] primvars:displayColor", "interpolation = \"uniform\"",
        [](const MeshData& m) { return array(m.color); });
    add("int[] primvars:feather_id", "interpolation = \"uniform\"", [](const MeshData& m) { return array(m.fid); });
    add("int[] primvars:tract", "interpolation = \"uniform\"", [](const MeshData& m) { return array(m.tract); });
    add("int[] primvars:layer", "interpolation = \"uniform\"", [](const MeshData& m) { return array(m.layer); });
    add("float[] primvars:age", "interpolation = \"uniform\"", [](const MeshData& m) { return array(m.age); });
  }
}

// The attributes refer to `d`, which must outlive their emit().
void curveAttrs(std::vector<Attr>& attrs, const std::vector<Curves>& d) {
  auto add = [&](const std::string& decl, const std::string& meta, auto get) {
    Attr a{decl, meta, {}};
    for (const Curves& c : d) a.values.push_back([&c, get] { return get(c); });
    attrs.push_back(std::move(a));
  };
  add("float3[] extent", "", [](const Curves& c) { return extentOf(c.points, &c.widths); });
  add("int[] curveVertexCounts", "", [](const Curves& c) { return array(c.counts); });
  add("point3f[] points", "", [](const Curves& c) { return array(c.points); });
  add("float[] widths", "interpolation = \"vertex\"", [](const Curves& c) { return array(c.widths); });
  add("texCoord2f[] primvars:st", "interpolation = \"vertex\"", [](const Curves& c) { return array(c.st); });
  add("color3f[] primvars:displayColor", "interpolation = \"uniform\"", [](const Curves& c) { return array(c.color); });
  add("int[] primvars:feather_id", "interpolation = \"uniform\"", [](const Curves& c) { return array(c.fid); });
  add("int[] primvars:tract", "interpolation = \"uniform\"", [](const Curves& c) { return array(c.tract); });
  add("int[] primvars:layer", "interpolation = \"uniform\"", [](const Curves& c) { return array(c.layer); });
  add("float[] primvars:age", "interpolation = \"uniform\"", [](const Curves& c) { return array(c.age); });
}

std::string quoted(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (c == '\n') {
      o += "\\n";
      continue;
    }
    o += c;
  }
  return o + "\"";
}

}  // namespace

size_t writeUsda(const ExportScene& s, const std::string& path, CoatAs as, int prototypesPerMaterial,
                 UsdCounts& counts) {
  const size_t nf = s.frames.size();
  std::vector<double> codes;
  for (const auto& f : s.frames) codes.push_back(f.time * s.fps);
  AtomicFile file(path);
  Out o(file);
  o.line(0, "#usda 1.0");
  o.line(0, "(");
  o.line(1, "defaultPrim = \"pteryla\"");
  o.line(1, "doc = \"pteryla feather coat (docs/export.md)\"");
  if (nf > 1) {
    o.line(1, "endTimeCode = " + shortest(codes.back()));
  }
  o.line(1, "metersPerUnit = " + shortest(s.metersPerUnit));
  if (nf > 1) {
    o.line(1, "startTimeCode = " + shortest(codes.front()));
    o.line(1, "timeCodesPerSecond = " + shortest(s.fps));
  }
  o.line(1, "upAxis = \"Y\"");
  o.line(0, ")");
  o.line(0, "");
  o.line(0, "def Xform \"pteryla\" (");
  o.line(1, "kind = \"component\"");
  o.line(0, ")");
  o.line(0, "{");
  {
    std::string names = "[";
    for (size_t i = 0; i < s.tractNames.size(); ++i) names += (i ? ", " : "") + quoted(s.tractNames[i]);
    o.line(1, "custom string[] pteryla:tractNames = " + names + "]");
  }
  // Skin.
  {
    std::vector<MeshData> d(nf);
    for (size_t k = 0; k < nf; ++k) {
      std::vector<uint32_t> all(s.frames[k].skin.triangleCount());
      for (size_t t = 0; t < all.size(); ++t) all[t] = uint32_t(t);
      buildMesh(s.frames[k].skin, all, nullptr, nullptr, d[k]);
    }
    o.line(0, "");
    o.line(1, "def Mesh \"skin\"");
    o.line(1, "{");
    std::vector<Attr> attrs;
    meshAttrs(attrs, d, false);
    for (const Attr& a : attrs) emit(o, 2, a, codes);
    o.line(
        2, "color3f[] primvars:displayColor = [" + [&] {
          std::string c;
          put(c, s.skinColor);
          return c;
        }() + "] (interpolation = \"constant\")");
    o.line(2, "uniform token subdivisionScheme = \"none\"");
    o.line(1, "}");
  }
  o.line(0, "");
  o.line(1, "def Xform \"coat\"");
  o.line(1, "{");
  if (as == CoatAs::Curves) {
    std::vector<Curves> rachis(nf), barbs(nf);
    for (size_t k = 0; k < nf; ++k) buildCurves(s, s.frames[k], rachis[k], barbs[k]);
    for (size_t k = 0; k < nf; ++k) {
      counts.curves += rachis[k].counts.size() + barbs[k].counts.size();
    }
    for (int which = 0; which < 2; ++which) {
      const std::vector<Curves>& c = which == 0 ? rachis : barbs;
      o.line(2, std::string("def BasisCurves \"") + (which == 0 ? "rachises" : "barbs") + "\"");
      o.line(2, "{");
      std::vector<Attr> attrs;
      curveAttrs(attrs, c);
      for (const Attr& a : attrs) emit(o, 3, a, codes);
      o.line(3, "uniform token type = \"linear\"");
      o.line(3, "uniform token wrap = \"nonperiodic\"");
      o.line(2, "}");
    }
  } else if (as == CoatAs::Cards) {
    std::vector<MeshData> d(nf);
    for (size_t k = 0; k < nf; ++k) {
      const ExportFrame& f = s.frames[k];
      std::vector<uint32_t> tris;
      for (const auto& r : f.ranges) {
        const auto t = liveTriangles(f.coat, r.firstIndex, r.indexCount);
        tris.insert(tris.end(), t.begin(), t.end());
      }
      buildMesh(f.coat, tris, &f, &s, d[k]);
    }
    o.line(2, "def Mesh \"cards\"");
    o.line(2, "{");
    std::vector<Attr> attrs;
    meshAttrs(attrs, d, true);
    for (const Attr& a : attrs) emit(o, 3, a, codes);
    o.line(3, "uniform bool doubleSided = 1");
    o.line(3, "uniform token subdivisionScheme = \"none\"");
    o.line(2, "}");
  } else {
    // Prototypes from the first frame: per material, its present feathers sorted by length and split into
    // equal-count buckets; each bucket's median feather, in its own frame scaled to unit length.
    const ExportFrame& f0 = s.frames.front();
    const size_t nFeathers = f0.feathers.size();
    std::vector<int64_t> protoOf(nFeathers, 0);
    struct Proto {
      uint32_t feather;
      double length;
    };
    std::vector<Proto> protos;
    std::vector<std::vector<std::pair<double, uint32_t>>> byMaterial(std::max<size_t>(1, s.materials.size()));
    std::vector<const pipeline::CoatDrawRange*> rangeOf(nFeathers, nullptr);
    for (const auto& r : f0.ranges) {
      rangeOf[r.feather] = &r;
      byMaterial[std::min<size_t>(f0.feathers[r.feather].material, byMaterial.size() - 1)].push_back(
          {featherLength(f0, r), r.feather});
    }
    std::vector<int64_t> firstProtoOfMaterial(byMaterial.size(), 0);
    std::vector<double> medianLength(byMaterial.size(), 1.0);
    for (size_t m = 0; m < byMaterial.size(); ++m) {
      auto& list = byMaterial[m];
      std::sort(list.begin(), list.end());
      firstProtoOfMaterial[m] = int64_t(protos.size());
      if (list.empty()) continue;
      medianLength[m] = std::max(1e-12, list[list.size() / 2].first);
      const size_t buckets = std::min<size_t>(size_t(prototypesPerMaterial), list.size());
      for (size_t b = 0; b < buckets; ++b) {
        const size_t lo = b * list.size() / buckets, hi = (b + 1) * list.size() / buckets;
        const auto& mid = list[(lo + hi) / 2];
        protos.push_back({mid.second, std::max(1e-12, mid.first)});
        for (size_t i = lo; i < hi; ++i) protoOf[list[i].second] = int64_t(protos.size() - 1);
      }
    }
    for (size_t i = 0; i < nFeathers; ++i)
      if (!rangeOf[i])
        protoOf[i] = firstProtoOfMaterial[std::min<size_t>(f0.feathers[i].material, byMaterial.size() - 1)];
    if (protos.empty()) throw Error("nothing to instance: the first frame has no feathers", path, "--as");
    if (size_t(protoOf.size()) && protos.size()) {
      for (auto& p : protoOf) p = std::min<int64_t>(p, int64_t(protos.size() - 1));
    }
    counts.prototypes = protos.size();
    counts.instances = nFeathers;
    o.line(2, "def PointInstancer \"feathers\"");
    o.line(2, "{");
    std::vector<std::string> targets;
    for (size_t p = 0; p < protos.size(); ++p)
      targets.push_back("</pteryla/coat/feathers/Prototypes/p" + std::to_string(p) + ">");
    std::string rel = "rel prototypes = [";
    for (size_t p = 0; p < targets.size(); ++p) rel += (p ? ", " : "") + targets[p];
    o.line(3, rel + "]");
    std::vector<Attr> attrs;
    Attr ids{"int64[] ids", "", {}}, proto{"int[] protoIndices", "", {}}, pos{"point3f[] positions", "", {}},
        ori{"quath[] orientations", "", {}}, scl{"float3[] scales", "", {}}, inv{"int64[] invisibleIds", "", {}};
    Attr fid{"int[] primvars:feather_id", "interpolation = \"vertex\"", {}},
        tract{"int[] primvars:tract", "interpolation = \"vertex\"", {}},
        layer{"int[] primvars:layer", "interpolation = \"vertex\"", {}},
        age{"float[] primvars:age", "interpolation = \"vertex\"", {}};
    for (size_t k = 0; k < nf; ++k) {
      const ExportFrame& f = s.frames[k];
      PTERYLA_CHECK_EQ(f.feathers.size(), nFeathers, "the feather count changed between frames");
      std::vector<double> length(nFeathers, 0);
      for (size_t i = 0; i < nFeathers; ++i)
        length[i] = medianLength[std::min<size_t>(f.feathers[i].material, byMaterial.size() - 1)];
      for (const auto& r : f.ranges) length[r.feather] = std::max(1e-12, featherLength(f, r));
      std::vector<int64_t> idv, invisible, fv, tv, lv;
      std::vector<glm::vec3> pv, sv;
      std::vector<Quat> qv;
      std::vector<float> av;
      for (size_t i = 0; i < nFeathers; ++i) {
        const FeatherRecord& r = f.feathers[i];
        idv.push_back(int64_t(r.id));
        if (!r.present) invisible.push_back(int64_t(r.id));
        pv.push_back(glm::vec3(r.origin));
        qv.push_back(quatOf(r.x, r.y, r.z));
        sv.push_back(glm::vec3(float(length[i])));
        fv.push_back(r.id);
        tv.push_back(r.tract);
        lv.push_back(r.layer);
        av.push_back(r.age);
      }
      ids.values.push_back([t = array(idv)] { return t; });
      proto.values.push_back([t = array(protoOf)] { return t; });
      pos.values.push_back([t = array(pv)] { return t; });
      ori.values.push_back([t = array(qv)] { return t; });
      scl.values.push_back([t = array(sv)] { return t; });
      inv.values.push_back([t = array(invisible)] { return t; });
      fid.values.push_back([t = array(fv)] { return t; });
      tract.values.push_back([t = array(tv)] { return t; });
      layer.values.push_back([t = array(lv)] { return t; });
      age.values.push_back([t = array(av)] { return t; });
    }
    for (const Attr* a : {&ids, &inv, &ori, &pos, &fid, &tract, &layer, &age, &proto, &scl}) emit(o, 3, *a, codes);
    o.line(0, "");
    o.line(3, "def Scope \"Prototypes\"");
    o.line(3, "{");
    for (size_t p = 0; p < protos.size(); ++p) {
      const FeatherRecord& r = f0.feathers[protos[p].feather];
      const pipeline::CoatDrawRange& range = *rangeOf[protos[p].feather];
      const glm::dvec3 axes[3] = {r.x, r.y, r.z};
      std::vector<MeshData> d(1);
      buildMesh(f0.coat, liveTriangles(f0.coat, range.firstIndex, range.indexCount), nullptr, nullptr, d[0], &r.origin,
                axes, 1.0 / protos[p].length);
      o.line(4, "def Mesh \"p" + std::to_string(p) + "\"");
      o.line(4, "{");
      std::vector<Attr> pa;
      meshAttrs(pa, d, false);
      for (const Attr& a : pa) emit(o, 5, a, codes);
      std::string c;
      put(c, r.material < s.materials.size() ? s.materials[r.material].baseColor : glm::vec3(0.8f));
      o.line(5, "color3f[] primvars:displayColor = [" + c + "] (interpolation = \"constant\")");
      o.line(5, "uniform bool doubleSided = 1");
      o.line(5, "custom string pteryla:material = " +
                    quoted(r.material < s.materials.size() ? s.materials[r.material].name : ""));
      o.line(5, "uniform token subdivisionScheme = \"none\"");
      o.line(4, "}");
    }
    o.line(3, "}");
    o.line(2, "}");
  }
  o.line(1, "}");
  o.line(0, "}");
  o.flush();
  file.commit();
  return o.bytes;
}

}  // namespace pteryla::exchange::detail
