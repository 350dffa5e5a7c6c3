// Structural check of PLY, OFF and STL files before OpenMesh reads them. OpenMesh's readers trust the
// file: a PLY header cut after "property" or with a version it cannot read makes its reader loop
// forever, an OFF declaring 1e9 vertices or a PLY list count mistyped as 3000000000 makes it allocate
// gigabytes. This pass walks the file with bounded work (every step consumes input), checks every
// declared count against the bytes actually present, refuses every layout that OpenMesh would read
// differently from what the file says (so the counts checked here are the ones OpenMesh reads; fuzzed
// by tests/fuzz/fuzz_mesh.cpp), and throws pteryla::Error naming the file and the line or element
// before anything is allocated.
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
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

// Whitespace as a C++ stream (and so OpenMesh) sees it: space, \t, \n, \v, \f, \r.
bool streamSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && streamSpace(line[i])) ++i;
    const size_t b = i;
    while (i < line.size() && !streamSpace(line[i])) ++i;
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

// A text token that a C++ stream reads whole as a number (OpenMesh reads ASCII PLY and OFF with
// operator>>): a token it reads only in part ("1.5" into an integer, "1-5", "2.0.1") leaves the rest
// as the next value and shifts everything after it, so the checks below would no longer see what
// OpenMesh reads.
// A value the stream cannot hold (beyond int, beyond float) fails it, and a failed stream keeps the
// last counts it read for every face that follows: such values are refused too.
bool integerToken(std::string_view t) {
  if (!t.empty() && (t[0] == '-' || t[0] == '+')) t.remove_prefix(1);
  uint64_t v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return !t.empty() && t[0] != '-' && r.ec == std::errc() && r.ptr == t.data() + t.size() && v <= 2147483647u;
}
bool floatToken(std::string_view t) {
  if (t.size() > 1 && t[0] == '+' && t[1] != '-') t.remove_prefix(1);
  if (t.empty() || !(std::isdigit(static_cast<unsigned char>(t.back())) || t.back() == '.'))
    return false;  // "1e", "inf"
  double v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return (r.ec == std::errc() || r.ec == std::errc::result_out_of_range) && r.ptr == t.data() + t.size() &&
         std::fabs(v) <= 3.4e38;  // FLT_MAX: OpenMesh reads coordinates into float
}

struct PlyProp {
  std::string name;
  int size = 0;       // scalar size, or item size of a list
  int countSize = 0;  // > 0 for a list
  bool countSigned = false;
  bool integral = true;  // scalar or list item type
};
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProp> props;
};

constexpr uint64_t kMaxListLength = 1u << 16;        // polygons with more corners are refused
constexpr uint64_t kMaxOpenMeshCount = 0xFFFFFFFFu;  // OpenMesh reads counts into unsigned int

// PLY as OpenMesh 9 reads it (Debian 12). Its header parser is token based, checks only for a bad
// stream and loops until it reads "end_header": a count or version it cannot read, or a missing
// "end_header", leaves it looping forever. Its body readers skip a list property they do not know
// as a single value, read the face element with the count of the last "face" element and start
// binary data 12 bytes after the last header token (14 after "\r\n"). Every header and layout
// where OpenMesh would read something else than the file says is refused here, so the counts and
// list lengths checked below are the ones OpenMesh reads.
void checkPly(const std::string& path, const std::string& d) {
  size_t pos = 0, lineStart = 0;
  int lineNo = 0;
  auto nextLine = [&](std::string_view& line) {
    if (pos >= d.size()) return false;
    const size_t nl = d.find('\n', pos);
    const size_t e = nl == std::string::npos ? d.size() : nl;
    lineStart = pos;
    line = std::string_view(d).substr(pos, e - pos);
    pos = nl == std::string::npos ? d.size() : nl + 1;
    ++lineNo;
    return true;
  };
  auto fail = [&](const std::string& what) { throw Error(what, path, "header line " + std::to_string(lineNo)); };
  std::string_view line;
  if (!nextLine(line) || split(line).size() != 1 || (split(line)[0] != "ply" && split(line)[0] != "PLY"))
    fail("expected 'ply' alone on the first line");
  std::string format;
  std::vector<PlyElement> elements;
  bool ended = false;
  // Where OpenMesh's header parser stands before it reads "end_header": after the last token of the
  // line before it, or at the start of the next line after a comment (read with getline).
  size_t lastTokenEnd = pos;
  while (!ended && nextLine(line)) {
    if (lineNo > 10000) fail("header longer than 10000 lines");
    const auto t = split(line);
    if (t.empty()) continue;
    // OpenMesh reads the three tokens after "ply" as the format line, whatever they are.
    if (format.empty() && t[0] != "format") fail("expected the 'format' line right after 'ply'");
    if (t[0] == "comment") {
      lastTokenEnd = pos;
      continue;
    }
    if (t[0] == "end_header") {
      if (t.size() != 1) fail("expected 'end_header' alone on its line");
      ended = true;
      continue;
    }
    lastTokenEnd = lineStart + static_cast<size_t>(t.back().data() + t.back().size() - line.data());
    if (t[0] == "obj_info") {
      for (size_t i = 1; i < t.size(); ++i)
        if (t[i] == "element" || t[i] == "property" || t[i] == "end_header" || t[i] == "format")
          fail("'" + std::string(t[i]) + "' inside an obj_info line (OpenMesh would read it as a header keyword)");
    } else if (t[0] == "format") {
      if (!format.empty()) fail("a second 'format' line");
      if (t.size() != 3 || (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian") ||
          !floatToken(t[2]))
        fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      format = std::string(t[1]);
    } else if (t[0] == "element") {
      PlyElement e;
      if (t.size() != 3 || !parseCount(t[2], e.count)) fail("expected 'element <name> <count>'");
      if (e.count > kMaxOpenMeshCount) fail("element count above 4294967295");
      e.name = std::string(t[1]);
      for (const auto& o : elements)
        if (o.name == e.name && (e.name == "vertex" || e.name == "face")) fail("a second '" + e.name + "' element");
      elements.push_back(e);
    } else if (t[0] == "property") {
      if (elements.empty()) fail("property before any element");
      PlyProp p;
      if (t.size() == 3 && plyTypeSize(t[1])) {
        p.size = plyTypeSize(t[1]);
        p.integral = plyIntegral(t[1]);
      } else if (t.size() == 5 && t[1] == "list" && plyTypeSize(t[2]) && plyTypeSize(t[3])) {
        // The count types OpenMesh reads; it refuses the others.
        if (t[2] != "uchar" && t[2] != "uint8" && t[2] != "uint16" && t[2] != "int")
          fail("list count type '" + std::string(t[2]) + "' (expected uchar, uint8, uint16 or int)");
        p.countSize = plyTypeSize(t[2]);
        p.countSigned = t[2] == "int";
        p.size = plyTypeSize(t[3]);
        p.integral = plyIntegral(t[3]);
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
  const bool ascii = format == "ascii";

  // OpenMesh reads list properties right only as the face element's vertex indices; it stops after
  // the face element, so lists after it are never read.
  size_t faceIndex = elements.size();
  for (size_t i = 0; i < elements.size(); ++i) {
    if (elements[i].name == "face") faceIndex = i;
    if (elements[i].count > 0 && elements[i].props.empty())
      throw Error("element '" + elements[i].name + "' has no properties", path, "element " + elements[i].name);
  }
  for (size_t i = 0; i < elements.size() && i <= faceIndex; ++i) {
    const auto& e = elements[i];
    for (const auto& p : e.props) {
      if (!p.countSize) continue;
      const bool indices = i == faceIndex && (p.name == "vertex_indices" || p.name == "vertex_index");
      if (!indices)
        throw Error("list property '" + p.name + "' (lists are read only as the face's vertex_indices)", path,
                    "element " + e.name);
      if (!p.integral) throw Error("vertex_indices with a floating-point item type", path, "element " + e.name);
    }
  }
  if (!ascii) {
    const bool crlf = lastTokenEnd + 1 < d.size() && d[lastTokenEnd] == '\r' && d[lastTokenEnd + 1] == '\n';
    const size_t openMeshStart = lastTokenEnd + (crlf ? 14 : 12);
    if (openMeshStart != pos)
      throw Error("binary data would be read from byte " + std::to_string(openMeshStart) + " instead of " +
                      std::to_string(pos) +
                      " (end the header with a line break and 'end_header' and one line break, no spaces or "
                      "comment just before it)",
                  path, "header line " + std::to_string(lineNo));
  }

  // Declared counts against the bytes present (each ASCII value takes at least 2 bytes, a binary one its size).
  const double rest = double(d.size() - pos);
  double need = 0, vertices = 0, faces = 0;
  for (const auto& e : elements) {
    double item = 0;
    for (const auto& p : e.props) item += ascii ? 2.0 : double(p.countSize ? p.countSize : p.size);
    need += double(e.count) * item;
    if (e.name == "vertex") vertices = double(e.count);
    if (e.name == "face") faces = double(e.count);
  }
  if (need > rest)
    throw Error("the header declares more data than the file holds (" + std::to_string(d.size() - pos) +
                    " bytes after the header; truncated file or wrong counts)",
                path, "element " + (elements.empty() ? std::string("?") : elements.front().name));
  requireMemory(
      vertices * 64.0 + faces * 128.0,
      "a mesh of " + std::to_string(uint64_t(vertices)) + " vertices and " + std::to_string(uint64_t(faces)) + " faces",
      path, "header");

  // Walk the body: every value readable whole, every list count sane and all data present.
  if (ascii) {
    size_t p = pos;
    auto token = [&](std::string_view& tok) {
      while (p < d.size() && streamSpace(d[p])) ++p;
      const size_t b = p;
      while (p < d.size() && !streamSpace(d[p])) ++p;
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
            if (!(pr.integral ? integerToken(tok) : floatToken(tok)))
              throw Error(std::string("expected ") + (pr.integral ? "an integer" : "a number") + " for '" + pr.name +
                              "', got '" + std::string(tok) + "'",
                          path, where());
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
          if (p > d.size())
            throw Error("file ends inside the data (truncated?)", path, e.name + " " + std::to_string(i));
        }
      if (p > d.size()) throw Error("file ends inside the data (truncated?)", path, "element " + e.name);
    }
    if (p > d.size()) throw Error("file ends inside the data (truncated?)", path, "body");
  }
}

// OFF as OpenMesh 9 reads it: the keyword line ([ST][C][N]OFF, " BINARY" right after it for binary)
// is read whole and skipped, so the counts must start on the next line. ASCII values are read with
// operator>> as one stream of tokens (no '#' comments): a vertex is 3 coordinates (6 with N) and the
// rest of its line; a face is a corner count and its indices, plus the rest of its line only when
// the keyword has C (face colours), so without C anything after the indices is the next face's
// corner count. Binary OFF holds little-endian 32-bit counts, vertices of 3 floats (+3 normals with
// N, +3 ints with C, +2 floats with ST) and faces of a 32-bit corner count and 32-bit indices.
void checkOff(const std::string& path, const std::string& d) {
  const size_t nl = d.find('\n');
  std::string_view first = std::string_view(d).substr(0, nl == std::string::npos ? d.size() : nl);
  if (!first.empty() && first.back() == '\r') first.remove_suffix(1);
  // The prefixes in OpenMesh's order: [ST][C][N][4][n]OFF.
  size_t k = 0;
  bool st = false, colour = false, normals = false, notThreeD = false;
  if (first.substr(k, 2) == "ST") st = true, k += 2;
  if (first.substr(k, 1) == "C") colour = true, k += 1;
  if (first.substr(k, 1) == "N") normals = true, k += 1;
  if (first.substr(k, 1) == "4") notThreeD = true, k += 1;
  if (first.substr(k, 1) == "n") notThreeD = true, k += 1;
  if (notThreeD && first.substr(k, 3) == "OFF")
    throw Error("only 3-D OFF files are supported (got '" + std::string(first) + "')", path, "line 1");
  if (first.substr(k, 3) != "OFF")
    throw Error("expected an OFF keyword ('OFF', 'COFF', 'NOFF', 'STOFF', ...) at the start of the first line", path,
                "line 1");
  const std::string_view after = first.substr(k + 3);
  const bool binary = after == " BINARY";
  if (!after.empty() && !binary)
    throw Error("expected the keyword alone on the first line (the counts go on the next line), or 'OFF BINARY'", path,
                "line 1");
  if (nl == std::string::npos)
    throw Error("expected the counts 'vertices faces edges' on the second line", path, "line 2");
  size_t p = nl + 1;

  if (binary) {
    auto u32 = [&](uint64_t& v) {
      if (p + 4 > d.size()) return false;
      v = 0;
      for (int b = 3; b >= 0; --b) v = (v << 8) | static_cast<unsigned char>(d[p + static_cast<size_t>(b)]);
      p += 4;
      return true;
    };
    uint64_t nv = 0, nf = 0, ne = 0;
    if (!u32(nv) || !u32(nf) || !u32(ne))
      throw Error("binary OFF shorter than its counts (truncated?)", path, "header counts");
    const uint64_t vertexBytes = 12 + (normals ? 12 : 0) + (colour ? 12 : 0) + (st ? 8 : 0);
    if (double(nv) * double(vertexBytes) + double(nf) * 16.0 > double(d.size() - p))
      throw Error("the header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                      " faces but only " + std::to_string(d.size() - p) +
                      " bytes follow (truncated file or wrong counts)",
                  path, "header counts");
    requireMemory(double(nv) * 64.0 + double(nf) * 128.0,
                  "a mesh of " + std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces", path,
                  "header counts");
    p += static_cast<size_t>(nv * vertexBytes);
    for (uint64_t f = 0; f < nf; ++f) {
      uint64_t n = 0;
      if (!u32(n)) throw Error("file ends inside the faces (truncated?)", path, "face " + std::to_string(f));
      if (n > kMaxListLength)
        throw Error("corner count " + std::to_string(n) + " is not in [0, " + std::to_string(kMaxListLength) + "]",
                    path, "face " + std::to_string(f));
      p += static_cast<size_t>(4 * n);
      if (p > d.size()) throw Error("file ends inside the faces (truncated?)", path, "face " + std::to_string(f));
    }
    return;
  }

  int line = 2;
  auto token = [&](std::string_view& tok) {
    while (p < d.size() && streamSpace(d[p])) line += d[p++] == '\n';
    const size_t b = p;
    while (p < d.size() && !streamSpace(d[p])) ++p;
    tok = std::string_view(d).substr(b, p - b);
    return p > b;
  };
  auto skipLine = [&] {
    while (p < d.size() && d[p] != '\n') ++p;
  };
  uint64_t counts[3] = {0, 0, 0};
  for (int c = 0; c < 3; ++c) {
    std::string_view t;
    if (!token(t) || !parseCount(t, counts[c]) || counts[c] > kMaxOpenMeshCount)
      throw Error("expected the counts 'vertices faces edges' on the second line (no comments)", path,
                  "line " + std::to_string(line));
  }
  const double rest = double(d.size() - p);
  // Each vertex needs 3 values, each face a corner count and at least 3 indices (>= 2 bytes each as text).
  if (double(counts[0]) * 6.0 + double(counts[1]) * 8.0 > rest)
    throw Error("the header declares " + std::to_string(counts[0]) + " vertices and " + std::to_string(counts[1]) +
                    " faces but only " + std::to_string(d.size() - p) +
                    " bytes follow (truncated file or wrong counts)",
                path, "header counts");
  requireMemory(double(counts[0]) * 64.0 + double(counts[1]) * 128.0,
                "a mesh of " + std::to_string(counts[0]) + " vertices and " + std::to_string(counts[1]) + " faces",
                path, "header counts");
  for (uint64_t v = 0; v < counts[0]; ++v) {
    std::string_view t;
    for (int c = 0; c < (normals ? 6 : 3); ++c) {
      if (!token(t)) throw Error("file ends inside the vertices (truncated?)", path, "vertex " + std::to_string(v));
      if (!floatToken(t))
        throw Error("expected a number, got '" + std::string(t) + "'", path,
                    "vertex " + std::to_string(v) + " (line " + std::to_string(line) + ")");
    }
    skipLine();  // colours and texture coordinates: OpenMesh reads the rest of the line on its own
  }
  for (uint64_t f = 0; f < counts[1]; ++f) {
    std::string_view t;
    uint64_t n = 0;
    if (!token(t)) throw Error("file ends inside the faces (truncated?)", path, "face " + std::to_string(f));
    if (!parseCount(t, n) || n > kMaxListLength)
      throw Error(
          "expected a corner count in [0, " + std::to_string(kMaxListLength) + "], got '" + std::string(t) + "'" +
              (colour ? "" : " (without C in the keyword, values after a face's indices are read as the next face)"),
          path, "face " + std::to_string(f) + " (line " + std::to_string(line) + ")");
    for (uint64_t c = 0; c < n; ++c) {
      if (!token(t)) throw Error("file ends inside the faces (truncated?)", path, "face " + std::to_string(f));
      if (!integerToken(t))
        throw Error("expected a vertex index, got '" + std::string(t) + "'", path,
                    "face " + std::to_string(f) + " (line " + std::to_string(line) + ")");
    }
    if (colour) skipLine();
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
  if (ext == ".ply")
    checkPly(path, data);
  else if (ext == ".off")
    checkOff(path, data);
  else if (ext == ".stl")
    checkStl(path, data);
}

}  // namespace pteryla::coat::detail
