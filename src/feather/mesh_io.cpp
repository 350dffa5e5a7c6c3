// OBJ and PLY export of TriMesh render meshes (feathers and coats) with texture coordinates.
#include "pteryla/feather/mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/finite.hpp"

namespace pteryla::feather {

namespace {

// Output through a temporary file renamed on success (a failed write keeps the previous file).
struct File {
  AtomicFile out;
  explicit File(const std::string& p) : out(p) {}
  void write(const void* data, size_t n) { out.write(data, n); }
  void close() { out.commit(); }
};

// Text accumulated in a buffer and flushed in large blocks.
struct TextOut {
  File& file;
  std::vector<char> buf;
  explicit TextOut(File& f) : file(f) { buf.reserve(1 << 20); }
  template <class... A>
  void printf(const char* fmt, A... args) {
    char tmp[256];
    const int n = std::snprintf(tmp, sizeof tmp, fmt, args...);
    buf.insert(buf.end(), tmp, tmp + std::min<int>(n, sizeof tmp - 1));
    if (buf.size() > (1u << 20) - 512) flush();
  }
  void flush() {
    file.write(buf.data(), buf.size());
    buf.clear();
  }
};

void checkMesh(const TriMesh& m, const std::string& path) {
  const size_t n = m.positions.size();
  auto ok = [n](size_t s) { return s == 0 || s == n; };
  PTERYLA_CHECK(ok(m.normals.size()) && ok(m.tangents.size()) && ok(m.uvGlobal.size()) && ok(m.uvBarb.size()) &&
                    ok(m.uvGrowth.size()) && ok(m.alpha.size()) && ok(m.sheath.size()) && ok(m.barbCount.size()) &&
                    ok(m.featherId.size()),
                "TriMesh attribute arrays must be empty or have one entry per vertex");
  PTERYLA_CHECK_EQ(m.indices.size() % 3, size_t(0), "TriMesh indices must come in triples");
  for (uint32_t i : m.indices) PTERYLA_CHECK(i < n, "TriMesh index out of range");
  // No NaN or infinity ever reaches a file: refuse before anything is written.
  requireFinite(m, path);
}

const std::vector<glm::vec2>& uvSet(const TriMesh& m, UvSet s) {
  switch (s) {
    case UvSet::Barb:
      return m.uvBarb;
    case UvSet::Growth:
      return m.uvGrowth;
    case UvSet::Global:
      break;
  }
  return m.uvGlobal;
}

bool littleEndian() {
  const uint16_t x = 1;
  unsigned char c;
  std::memcpy(&c, &x, 1);
  return c == 1;
}

}  // namespace

void writeObj(const std::string& path, const TriMesh& m, UvSet uv) {
  checkMesh(m, path);
  File file(path);
  TextOut out(file);
  const std::vector<glm::vec2>& t = uvSet(m, uv);
  const bool hasT = !t.empty(), hasN = !m.normals.empty();
  out.printf("# pteryla feather mesh: %zu vertices, %zu triangles\n", m.positions.size(), m.triangleCount());
  for (const auto& p : m.positions) out.printf("v %.7g %.7g %.7g\n", p.x, p.y, p.z);
  if (hasT)
    for (const auto& q : t) out.printf("vt %.7g %.7g\n", q.x, q.y);
  if (hasN)
    for (const glm::vec3 q : m.normals) out.printf("vn %.6g %.6g %.6g\n", q.x, q.y, q.z);
  for (size_t i = 0; i < m.indices.size(); i += 3) {
    const uint32_t a = m.indices[i] + 1, b = m.indices[i + 1] + 1, c = m.indices[i + 2] + 1;
    if (hasT && hasN)
      out.printf("f %u/%u/%u %u/%u/%u %u/%u/%u\n", a, a, a, b, b, b, c, c, c);
    else if (hasT)
      out.printf("f %u/%u %u/%u %u/%u\n", a, a, b, b, c, c);
    else if (hasN)
      out.printf("f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
    else
      out.printf("f %u %u %u\n", a, b, c);
  }
  out.flush();
  file.close();
}

void writePly(const std::string& path, const TriMesh& m, const PlyOptions& opt) {
  checkMesh(m, path);
  File file(path);
  const std::vector<glm::vec2>& t = uvSet(m, opt.uv);
  struct Prop {
    const char* name;
    const float* f;     // float source with stride
    const uint32_t* u;  // or uint source
    size_t stride;
    const PackedDir* d = nullptr;  // or component `comp` of a packed unit vector
    const Half* h = nullptr;       // or a half float
    int comp = 0;
    float value(size_t i) const {
      if (d) return PackedDir::unpack(d[i].q[comp]);
      if (h) return h[i];
      return f[i * stride];
    }
  };
  std::vector<Prop> props;
  const size_t n = m.positions.size();
  auto addVec = [&](const float* base, size_t comps, std::initializer_list<const char*> names) {
    size_t c = 0;
    for (const char* nm : names) props.push_back({nm, base + c++, nullptr, comps});
  };
  addVec(&m.positions.data()->x, 3, {"x", "y", "z"});
  if (!m.normals.empty()) {
    int c = 0;
    for (const char* nm : {"nx", "ny", "nz"})
      props.push_back({nm, nullptr, nullptr, 1, m.normals.data(), nullptr, c++});
  }
  if (!t.empty()) addVec(&t.data()->x, 2, {"u", "v"});
  if (!m.uvBarb.empty()) addVec(&m.uvBarb.data()->x, 2, {"u_barb", "v_barb"});
  if (!m.uvGrowth.empty()) addVec(&m.uvGrowth.data()->x, 2, {"u_growth", "v_growth"});
  auto addHalf = [&](const std::vector<Half>& v, const char* name) {
    if (!v.empty()) props.push_back({name, nullptr, nullptr, 1, nullptr, v.data()});
  };
  addHalf(m.alpha, "alpha");
  addHalf(m.sheath, "sheath");
  addHalf(m.barbCount, "barb_count");
  if (!m.featherId.empty()) props.push_back({"feather_id", nullptr, m.featherId.data(), 1});

  std::string header = "ply\nformat ";
  header += opt.binary ? (littleEndian() ? "binary_little_endian" : "binary_big_endian") : "ascii";
  header += " 1.0\ncomment pteryla feather mesh\nelement vertex " + std::to_string(n) + "\n";
  for (const Prop& p : props) header += std::string("property ") + (p.u ? "uint " : "float ") + p.name + "\n";
  header +=
      "element face " + std::to_string(m.triangleCount()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  file.write(header.data(), header.size());

  if (opt.binary) {
    const size_t vbytes = props.size() * 4;
    std::vector<char> buf;
    buf.reserve(1 << 20);
    auto flushIf = [&](size_t need) {
      if (buf.size() + need > (1u << 20)) {
        file.write(buf.data(), buf.size());
        buf.clear();
      }
    };
    for (size_t i = 0; i < n; ++i) {
      flushIf(vbytes);
      for (const Prop& p : props) {
        char b[4];
        if (p.u) {
          std::memcpy(b, p.u + i * p.stride, 4);
        } else {
          const float f = p.value(i);
          std::memcpy(b, &f, 4);
        }
        buf.insert(buf.end(), b, b + 4);
      }
    }
    for (size_t i = 0; i < m.indices.size(); i += 3) {
      flushIf(13);
      buf.push_back(3);
      const char* src = reinterpret_cast<const char*>(m.indices.data() + i);
      buf.insert(buf.end(), src, src + 12);
    }
    file.write(buf.data(), buf.size());
  } else {
    TextOut out(file);
    for (size_t i = 0; i < n; ++i) {
      for (size_t k = 0; k < props.size(); ++k) {
        const Prop& p = props[k];
        const char* sep = k + 1 < props.size() ? " " : "\n";
        if (p.u)
          out.printf("%u%s", p.u[i * p.stride], sep);
        else
          out.printf("%.7g%s", static_cast<double>(p.value(i)), sep);
      }
    }
    for (size_t i = 0; i < m.indices.size(); i += 3)
      out.printf("3 %u %u %u\n", m.indices[i], m.indices[i + 1], m.indices[i + 2]);
    out.flush();
  }
  file.close();
}

void writeMesh(const std::string& path, const TriMesh& mesh) {
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (ext == ".obj") return writeObj(path, mesh);
  if (ext == ".ply") return writePly(path, mesh);
  throw Error("unknown mesh format (expected a .obj or .ply file name)", path);
}

}  // namespace pteryla::feather
