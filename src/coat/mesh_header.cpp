// Structural check of PLY, OFF and STL files before OpenMesh reads them. OpenMesh's readers trust the
// header: a PLY header cut after "property" makes its reader loop forever, an OFF declaring 1e9 vertices
// or a PLY list count mistyped as 3000000000 makes it allocate gigabytes. This pass walks the file with
// bounded work (every step consumes input), checks every declared count against the bytes actually
// present, and throws pteryla::Error naming the file and the line or element before anything is allocated.
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "mesh_io.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/core/paths.hpp"

namespace pteryla::coat::detail {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open mesh file (does it exist?)", path);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error("cannot read mesh file (is it a directory?)", path);
  in.seekg(0);
  std::string data(static_cast<size_t>(size), '\0');
  in.read(data.data(), size);
  if (!in) throw Error("cannot read mesh file", path);
  return data;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
  return out;
}

bool parseCount(std::string_view t, uint64_t& v) {
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}

// Size in bytes of a PLY scalar type, 0 when unknown.
int plyTypeSize(std::string_view t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}
bool plyIntegral(std::string_view t) { return t != "float" && t != "float32" && t != "double" && t != "float64"; }

struct PlyProp {
  std::string name;
  int size = 0;      // scalar size, or item size of a list
  int countSize = 0; // > 0 for a list
  bool countSigned = false;
};
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProp> props;
};

constexpr uint64_t kMaxListLength = 1u << 16;  // polygons with more corners are refused

void checkPly(const std::string& path, const std::string& d) {
  size_t pos = 0;
  int lineNo = 0;
  auto nextLine = [&](std::string_view& line) {
    if (pos >= d.size()) return false;
    const size_t nl = d.find('\n', pos);
    const size_t e = nl == std::string::npos ? d.size() : nl;
    line = std::string_view(d).substr(pos, e - pos);
    pos = nl == std::string::npos ? d.size() : nl + 1;
    ++lineNo;
    return true;
  };
  auto fail = [&](const std::string& what) { throw Error(what, path, "header line " + std::to_string(lineNo)); };
  std::string_view line;
  if (!nextLine(line) || split(line).empty() || split(line)[0] != "ply") fail("expected 'ply' on the first line");
  std::string format;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (!ended && nextLine(line)) {
    if (lineNo > 10000) fail("header longer than 10000 lines");
    const auto t = split(line);
    if (t.empty()) continue;
    if (t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "end_header") {
      ended = true;
    } else if (t[0] == "format") {
      if (t.size() != 3 || (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian"))
        fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      format = std::string(t[1]);
    } else if (t[0] == "element") {
      PlyElement e;
      if (t.size() != 3 || !parseCount(t[2], e.count)) fail("expected 'element <name> <count>'");
      e.name = std::string(t[1]);
      elements.push_back(e);
    } else if (t[0] == "property") {
      if (elements.empty()) fail("property before any element");
      PlyProp p;
      if (t.size() == 3 && plyTypeSize(t[1])) {
        p.size = plyTypeSize(t[1]);
      } else if (t.size() == 5 && t[1] == "list" && plyTypeSize(t[2]) && plyIntegral(t[2]) && plyTypeSize(t[3])) {
        p.countSize = plyTypeSize(t[2]);
        p.countSigned = t[2][0] != 'u';
        p.size = plyTypeSize(t[3]);
      } else {
        fail("expected 'property <type> <name>' or 'property list <count type> <item type> <name>' with PLY types");
      }
      p.name = std::string(t.back());
      elements.back().props.push_back(p);
    } else {
      fail("unknown header keyword '" + std::string(t[0]) + "'");
    }
  }
  if (!ended) fail("the header ends without 'end_header' (file truncated?)");
  if (format.empty()) fail("the header has no 'format' line");
  for (const auto& e : elements)
    if (e.count > 0 && e.props.empty())
      throw Error("element '" + e.name + "' has no properties", path, "element " + e.name);

  // Declared counts against the bytes present (each ASCII value takes at least 2 bytes, a binary one its size).
  const double rest = double(d.size() - pos);
  double need = 0, vertices = 0, faces = 0;
  for (const auto& e : elements) {
    double item = 0;
    for (const auto& p : e.props) item += format == "ascii" ? 2.0 : double(p.countSize ? p.countSize : p.size);
    need += double(e.count) * item;
    if (e.name == "vertex") vertices = double(e.count);
    if (e.name == "face") faces = double(e.count);
  }
  if (need > rest)
    throw Error("the header declares more data than the file holds (" + std::to_string(d.size() - pos) +
                    " bytes after the header; truncated file or wrong counts)",
                path, "element " + (elements.empty() ? std::string("?") : elements.front().name));
  requireMemory(vertices * 64.0 + faces * 128.0, "a mesh of " + std::to_string(uint64_t(vertices)) + " vertices and " +
                std::to_string(uint64_t(faces)) + " faces", path, "header");

  // Walk the body: every list count must be sane and all data present.
  if (format == "ascii") {
    size_t p = pos;
    auto token = [&](std::string_view& tok) {
      while (p < d.size() && (d[p] == ' ' || d[p] == '\t' || d[p] == '\r' || d[p] == '\n')) ++p;
      const size_t b = p;
      while (p < d.size() && d[p] != ' ' && d[p] != '\t' && d[p] != '\r' && d[p] != '\n') ++p;
      tok = std::string_view(d).substr(b, p - b);
      return p > b;
    };
    std::string_view tok;
    for (const auto& e : elements)
      for (uint64_t i = 0; i < e.count; ++i) {
        auto where = [&] { return e.name + " " + std::to_string(i); };
        for (const auto& pr : e.props) {
          uint64_t n = 1;
          if (pr.countSize) {
            if (!token(tok)) throw Error("file ends inside the data (truncated?)", path, where());
            if (!parseCount(tok, n) || n > kMaxListLength)
              throw Error("expected a list length in [0, " + std::to_string(kMaxListLength) + "] for '" + pr.name +
                              "', got '" + std::string(tok) + "'",
                          path, where());
          }
          for (uint64_t k = 0; k < n; ++k) {
            if (!token(tok)) throw Error("file ends inside the data (truncated?)", path, where());
            double v = 0;
            const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
            if (r.ec != std::errc() && r.ec != std::errc::result_out_of_range)
              throw Error("expected a number for '" + pr.name + "', got '" + std::string(tok) + "'", path, where());
          }
        }
      }
  } else {
    const bool big = format == "binary_big_endian";
    size_t p = pos;
    for (const auto& e : elements) {
      bool fixed = true;
      size_t item = 0;
      for (const auto& pr : e.props) {
        fixed = fixed && !pr.countSize;
        item += static_cast<size_t>(pr.size);
      }
      if (fixed) {  // checked above: count * item <= rest
        p += static_cast<size_t>(e.count) * item;
        continue;
      }
      for (uint64_t i = 0; i < e.count; ++i)
        for (const auto& pr : e.props) {
          if (!pr.countSize) {
            p += static_cast<size_t>(pr.size);
            continue;
          }
          if (p + static_cast<size_t>(pr.countSize) > d.size())
            throw Error("file ends inside the data (truncated?)", path, e.name + " " + std::to_string(i));
          uint64_t n = 0;
          for (int b = 0; b < pr.countSize; ++b) {
            const int byte = big ? b : pr.countSize - 1 - b;
            n = (n << 8) | static_cast<unsigned char>(d[p + static_cast<size_t>(byte)]);
          }
          const bool negative = pr.countSigned && (n >> (8 * pr.countSize - 1)) & 1u;
          p += static_cast<size_t>(pr.countSize);
          if (negative || n > kMaxListLength)
            throw Error("list length " + (negative ? std::string("< 0") : std::to_string(n)) + " for '" + pr.name +
                            "' is not in [0, " + std::to_string(kMaxListLength) + "]",
                        path, e.name + " " + std::to_string(i));
          p += static_cast<size_t>(n) * static_cast<size_t>(pr.size);
        }
      if (p > d.size()) throw Error("file ends inside the data (truncated?)", path, "element " + e.name);
    }
    if (p > d.size()) throw Error("file ends inside the data (truncated?)", path, "body");
  }
}

void checkOff(const std::string& path, const std::string& d) {
  // [ST][C][N][4][n]OFF, optional dimension, then "nv nf ne" (comments with '#').
  size_t p = 0;
  int line = 1;
  auto token = [&](std::string_view& tok) {
    for (;;) {
      while (p < d.size() && (d[p] == ' ' || d[p] == '\t' || d[p] == '\r' || d[p] == '\n')) line += d[p++] == '\n';
      if (p < d.size() && d[p] == '#') {
        while (p < d.size() && d[p] != '\n') ++p;
        continue;
      }
      break;
    }
    const size_t b = p;
    while (p < d.size() && d[p] != ' ' && d[p] != '\t' && d[p] != '\r' && d[p] != '\n') ++p;
    tok = std::string_view(d).substr(b, p - b);
    return p > b;
  };
  std::string_view kw;
  if (!token(kw) || kw.size() < 3 || kw.substr(kw.size() - 3) != "OFF")
    throw Error("expected an OFF keyword ('OFF', 'COFF', 'NOFF', ...) at the start", path, "line 1");
  if (kw.find('n') != std::string_view::npos || kw.find('4') != std::string_view::npos)
    throw Error("only 3-D OFF files are supported (got '" + std::string(kw) + "')", path, "line 1");
  const bool binary = [&] {
    const size_t save = p;
    std::string_view t;
    const bool b = token(t) && t == "BINARY";
    if (!b) p = save;
    return b;
  }();
  uint64_t counts[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    std::string_view t;
    if (!token(t) || !parseCount(t, counts[k]))
      throw Error("expected the counts 'vertices faces edges' after the keyword", path, "line " + std::to_string(line));
  }
  const double rest = double(d.size() - p);
  // Each vertex needs 3 values, each face a corner count and at least 3 indices (>= 2 bytes each as text).
  const double need = binary ? double(counts[0]) * 12.0 + double(counts[1]) * 16.0
                             : double(counts[0]) * 6.0 + double(counts[1]) * 8.0;
  if (need > rest)
    throw Error("the header declares " + std::to_string(counts[0]) + " vertices and " + std::to_string(counts[1]) +
                    " faces but only " + std::to_string(d.size() - p) +
                    " bytes follow (truncated file or wrong counts)",
                path, "header counts");
  requireMemory(double(counts[0]) * 64.0 + double(counts[1]) * 128.0,
                "a mesh of " + std::to_string(counts[0]) + " vertices and " + std::to_string(counts[1]) + " faces",
                path, "header counts");
  if (binary) return;
  // Face corner counts must be sane.
  for (uint64_t v = 0; v < counts[0]; ++v) {
    // Skip the rest of the vertex line (colours may follow the coordinates).
    std::string_view t;
    for (int k = 0; k < 3; ++k)
      if (!token(t)) throw Error("file ends inside the vertices (truncated?)", path, "vertex " + std::to_string(v));
    while (p < d.size() && d[p] != '\n') ++p;
  }
  for (uint64_t f = 0; f < counts[1]; ++f) {
    std::string_view t;
    uint64_t n = 0;
    if (!token(t)) throw Error("file ends inside the faces (truncated?)", path, "face " + std::to_string(f));
    if (!parseCount(t, n) || n > kMaxListLength)
      throw Error("expected a corner count in [0, " + std::to_string(kMaxListLength) + "], got '" + std::string(t) +
                      "'",
                  path, "face " + std::to_string(f) + " (line " + std::to_string(line) + ")");
    for (uint64_t k = 0; k < n; ++k)
      if (!token(t)) throw Error("file ends inside the faces (truncated?)", path, "face " + std::to_string(f));
    while (p < d.size() && d[p] != '\n') ++p;
  }
}

void checkStl(const std::string& path, const std::string& d) {
  const bool ascii = d.compare(0, 5, "solid") == 0 && d.find("facet", 0) != std::string::npos;
  if (ascii) return;  // text: OpenMesh reads facet by facet, nothing declared up front
  if (d.size() < 84) throw Error("binary STL shorter than its 84-byte header (truncated?)", path, "header");
  uint32_t n = 0;
  for (int b = 3; b >= 0; --b) n = (n << 8) | static_cast<unsigned char>(d[80 + static_cast<size_t>(b)]);
  if (84.0 + 50.0 * double(n) > double(d.size()))
    throw Error("binary STL declares " + std::to_string(n) + " triangles but holds only " +
                    std::to_string((d.size() - 84) / 50) + " (truncated file or wrong count)",
                path, "triangle count");
  requireMemory(double(n) * 3.0 * 64.0 + double(n) * 128.0, "an STL of " + std::to_string(n) + " triangles", path,
                "triangle count");
}

}  // namespace

void checkMeshFileStructure(const std::string& path) {
  const std::string ext = extensionOf(path);
  const std::string data = slurp(path);
  if (ext == ".ply") checkPly(path, data);
  else if (ext == ".off") checkOff(path, data);
  else if (ext == ".stl") checkStl(path, data);
}

}  // namespace pteryla::coat::detail
