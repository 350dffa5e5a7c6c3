// Coat export: samples the pipeline at each export time and hands the frames to the glTF or USD writer
// (or to the OBJ/PLY mesh writer for one frame). Shared helpers: shortest float text, a small PNG
// encoder, material images and the curves recovered from the card mesh.
#include "pteryla/exchange/coat_export.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "frames.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/data_dir.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/finite.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/feather/mesh_io.hpp"
#include "pteryla/render/pattern.hpp"

namespace pteryla::exchange {

namespace detail {

std::string shortest(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}
std::string shortest(double v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

namespace {

uint32_t crc32(const unsigned char* p, size_t n, uint32_t crc = 0) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put32(std::vector<unsigned char>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<unsigned char>(v >> s));
}

void chunk(std::vector<unsigned char>& out, const char type[4], const std::vector<unsigned char>& data) {
  put32(out, static_cast<uint32_t>(data.size()));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put32(out, crc32(out.data() + start, out.size() - start));
}

std::vector<unsigned char> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read texture", path);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

std::vector<unsigned char> encodePng(int width, int height, const std::vector<uint8_t>& rgba) {
  PTERYLA_CHECK(width > 0 && height > 0 && rgba.size() == size_t(width) * size_t(height) * 4, "PNG image size");
  // Scanlines with filter byte 0, in zlib stored (uncompressed) deflate blocks of at most 65535 bytes.
  std::vector<unsigned char> raw;
  raw.reserve((size_t(width) * 4 + 1) * size_t(height));
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);
    const uint8_t* row = rgba.data() + size_t(y) * size_t(width) * 4;
    raw.insert(raw.end(), row, row + size_t(width) * 4);
  }
  std::vector<unsigned char> z = {0x78, 0x01};
  for (size_t pos = 0; pos < raw.size() || raw.empty();) {
    const size_t n = std::min<size_t>(65535, raw.size() - pos);
    const bool last = pos + n == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<unsigned char>(n & 0xFF));
    z.push_back(static_cast<unsigned char>(n >> 8));
    z.push_back(static_cast<unsigned char>(~n & 0xFF));
    z.push_back(static_cast<unsigned char>((~n >> 8) & 0xFF));
    z.insert(z.end(), raw.begin() + std::ptrdiff_t(pos), raw.begin() + std::ptrdiff_t(pos + n));
    pos += n;
    if (last) break;
  }
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521u;
    b = (b + a) % 65521u;
  }
  put32(z, (b << 16) | a);
  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<unsigned char> ihdr;
  put32(ihdr, uint32_t(width));
  put32(ihdr, uint32_t(height));
  ihdr.insert(ihdr.end(), {8, 6, 0, 0, 0});  // 8 bits, RGBA, deflate, adaptive filters, no interlace
  chunk(png, "IHDR", ihdr);
  chunk(png, "IDAT", z);
  chunk(png, "IEND", {});
  return png;
}

bool materialImage(const pipeline::CoatMaterial& m, std::vector<unsigned char>& bytes, std::string& mime) {
  std::string file = m.texture;
  if (file.empty() && !m.pattern.empty()) {
    const std::string bundled = dataDirectory() + "/textures/" + m.pattern + ".png";
    if (fileExists(bundled)) file = bundled;
  }
  if (!file.empty()) {
    const std::string ext = extensionOf(file);
    if (ext == ".png")
      mime = "image/png";
    else if (ext == ".jpg" || ext == ".jpeg")
      mime = "image/jpeg";
    else
      throw Error("glTF carries PNG or JPEG textures only", file);
    bytes = readBytes(file);
    return true;
  }
  if (m.pattern.empty()) return false;
  // Synthesised as the renderer does (render/scene_view.cpp) for a pattern with no bundled file.
  static const std::pair<const char*, render::PatternKind> kinds[] = {{"plain", render::PatternKind::Plain},
                                                                      {"barred", render::PatternKind::Barred},
                                                                      {"scalloped", render::PatternKind::Scalloped},
                                                                      {"spotted", render::PatternKind::Spotted},
                                                                      {"eyespot", render::PatternKind::Eyespot}};
  render::PatternParams pp;
  pp.kind = render::PatternKind::Barred;
  for (const auto& k : kinds)
    if (m.pattern == k.first) pp.kind = k.second;
  pp.baseColor = m.baseColor;
  pp.markColor = m.baseColor * 0.35f;
  const render::Image img = render::generatePattern(pp);
  bytes = encodePng(img.width, img.height, img.rgba);
  mime = "image/png";
  return true;
}

void vaneBarbs(const TriMesh& coat, uint32_t firstIndex, uint32_t indexCount, std::vector<BarbRow>& barbs) {
  // Per kept barb: strip 0 over rows (c - n, c) and strip 1 over (c, c + n), 2 (n - 1) triangles each,
  // where c is the centre row's first vertex and n the samples per barb. Every triangle's first index is
  // kept by the drape's collapse, and within a strip it runs lo, lo+1, lo+1, lo+2, ..., lo+n-1.
  const uint32_t* idx = coat.indices.data();
  const size_t end = size_t(firstIndex) + indexCount;
  size_t t = firstIndex / 3;
  const size_t tEnd = end / 3;
  while (t < tEnd) {
    const uint32_t lo = idx[3 * t];
    size_t m = 1;  // triangle pairs in strip 0
    while (t + 2 * m < tEnd && idx[3 * (t + 2 * m)] == idx[3 * (t + 2 * m - 1)]) ++m;
    const size_t n = m + 1;
    const size_t tris = 4 * m;
    if (t + tris > tEnd || idx[3 * (t + 2 * m)] != lo + n) return;  // not the vane layout: stop
    if (size_t(lo) + 3 * n > coat.positions.size()) return;
    const uint32_t c = lo + uint32_t(n);
    BarbRow barb{c, uint32_t(n), 0};
    for (size_t k = 0; k < n; ++k) {
      // Segment k - 1 .. k is kept when any of its four triangles survived.
      if (k > 0) {
        bool kept = false;
        for (size_t s = 0; s < 2; ++s)
          for (size_t q = 0; q < 2; ++q) kept = kept || !collapsed(idx + 3 * (t + s * 2 * m + 2 * (k - 1) + q));
        if (!kept) break;
      }
      ++barb.count;
    }
    if (barb.count >= 2) barbs.push_back(barb);
    t += tris;
  }
}

void rachisCurve(const TriMesh& coat, uint32_t firstIndex, uint32_t indexCount, std::vector<glm::vec3>& points,
                 std::vector<float>& widths, std::vector<uint32_t>& vertexOfPoint) {
  points.clear();
  widths.clear();
  vertexOfPoint.clear();
  const uint32_t sides = uint32_t(feather::MeshOptions{}.shaftSides);  // what the pipeline meshes with
  const size_t tris = indexCount / 3;
  if (tris < sides || tris % sides != 0 || (tris / sides) % 2 == 0) return;
  const size_t rings = (tris / sides + 1) / 2;
  const uint32_t* idx = coat.indices.data() + firstIndex;
  const uint32_t base = idx[0];
  if (size_t(base) + rings * (sides + 1) + sides > coat.positions.size()) return;  // not the shaft layout
  for (size_t r = 0; r < rings; ++r) {
    // Stop at the first ring band whose triangles were all trimmed.
    const size_t band = r + 1 < rings ? 2 * sides : sides;
    bool kept = false;
    for (size_t q = 0; q < band; ++q) kept = kept || !collapsed(idx + 3 * (r * 2 * sides + q));
    if (!kept) break;
    const uint32_t v0 = base + uint32_t(r) * (sides + 1);
    glm::vec3 c(0.0f);
    for (uint32_t j = 0; j < sides; ++j) c += coat.positions[v0 + j];
    c /= float(sides);
    float rad = 0;
    for (uint32_t j = 0; j < sides; ++j) rad += glm::length(coat.positions[v0 + j] - c);
    points.push_back(c);
    widths.push_back(2.0f * rad / float(sides));
    vertexOfPoint.push_back(v0);
    if (r + 1 == rings) {
      const uint32_t apex = base + uint32_t(rings) * (sides + 1);
      points.push_back(coat.positions[apex]);
      widths.push_back(0.0f);
      vertexOfPoint.push_back(apex);
    }
  }
  if (points.size() < 2) {
    points.clear();
    widths.clear();
    vertexOfPoint.clear();
  }
}

}  // namespace detail

Format formatOf(const std::string& path) {
  const std::string e = extensionOf(path);
  if (e == ".glb") return Format::Glb;
  if (e == ".gltf") return Format::Gltf;
  if (e == ".usda") return Format::Usda;
  if (e == ".obj") return Format::Obj;
  if (e == ".ply") return Format::Ply;
  throw Error("unsupported output type '" + e + "': expected .glb, .gltf, .usda, .obj or .ply", path, "--out");
}

CoatAs coatAsOf(const std::string& name) {
  if (name == "curves") return CoatAs::Curves;
  if (name == "cards") return CoatAs::Cards;
  if (name == "instances") return CoatAs::Instances;
  throw Error("expected cards, curves or instances, got '" + name + "'", "", "--as");
}

std::vector<double> frameTimes(double from, double to, double fps) {
  if (!std::isfinite(from)) throw Error("expected a finite time", "", "--from");
  if (!std::isfinite(to)) throw Error("expected a finite time", "", "--to");
  if (!(fps > 0 && std::isfinite(fps))) throw Error("expected frames per unit of time > 0", "", "--fps");
  if (!(to >= from)) throw Error("--from is later than --to", "", "--from");
  const double countD = std::floor((to - from) * fps + 1e-9) + 1;
  constexpr double kMaxFrames = 100000;
  if (!(countD <= kMaxFrames)) throw Error("too many frames (at most 100000); lower --fps or the range", "", "--to");
  std::vector<double> t(static_cast<size_t>(countD));
  for (size_t k = 0; k < t.size(); ++k) t[k] = from + double(k) / fps;
  return t;
}

namespace {

detail::ExportFrame sample(pipeline::Pipeline& p) {
  detail::ExportFrame f;
  f.time = p.time();
  const pipeline::CoatMesh& cm = p.coatMesh();
  f.coat = cm.mesh;
  f.ranges = cm.ranges;
  f.skin = p.skinTriMesh();
  const coat::CoatFeathers& cf = p.feathers();
  const std::vector<double>& elev = p.elevations();
  f.feathers.resize(cf.size());
  for (size_t i = 0; i < cf.size(); ++i) {
    detail::FeatherRecord& r = f.feathers[i];
    r.id = uint32_t(i);
    r.tract = cf.tract[i];
    r.age = float(cf.age[i]);
    r.present = cf.present[i] != 0;
    const coat::FeatherFrame& fr = cf.frames[i];
    const auto pl =
        feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, i < elev.size() ? elev[i] : 0.0);
    r.origin = pl.origin;
    r.x = pl.x;
    r.y = pl.y;
    r.z = pl.z;
    r.material = 0;
    for (size_t m = 0; m < cm.materials.size(); ++m)
      if (cm.materials[m].name == cf.params[i].name) r.material = uint32_t(m);
  }
  for (size_t k = 0; k < cf.layerOrder.size(); ++k) f.feathers[cf.layerOrder[k]].layer = uint32_t(k);
  requireFinite(f.coat, "");
  requireFinite(f.skin, "");
  return f;
}

}  // namespace

ExportResult exportCoat(pipeline::Pipeline& p, const std::string& path, const ExportOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const Format fmt = formatOf(path);
  if ((fmt == Format::Obj || fmt == Format::Ply) && opt.times.size() > 1)
    throw Error("OBJ and PLY hold one frame: export a range as .glb, .gltf or .usda", path, "--from");
  if (!(opt.fps > 0 && std::isfinite(opt.fps))) throw Error("expected frames per unit of time > 0", "", "--fps");
  if (!(opt.metersPerUnit > 0 && std::isfinite(opt.metersPerUnit)))
    throw Error("expected metres per unit > 0", "", "metersPerUnit");
  if (opt.instancePrototypes < 1) throw Error("expected at least one prototype per material", "", "instancePrototypes");
  ExportResult res;
  if (fmt == Format::Obj || fmt == Format::Ply) {
    if (!opt.times.empty()) p.setTime(opt.times.front());
    TriMesh all = p.skinTriMesh();
    all.append(p.coatMesh().mesh);
    const auto w0 = std::chrono::steady_clock::now();
    feather::writeMesh(path, all);
    res.writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    res.frames = 1;
    res.feathers = p.coatMesh().ranges.size();
    res.triangles = all.triangleCount();
    res.bytes = size_t(std::filesystem::file_size(path));
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  }
  detail::ExportScene s;
  s.fps = opt.fps;
  s.metersPerUnit = opt.metersPerUnit;
  s.skinColor = glm::vec3(p.scene().render.skinColor);
  for (const auto& t : p.tracts()) s.tractNames.push_back(t.name);
  const double savedTime = p.time();
  try {
    if (opt.times.empty()) {
      s.frames.push_back(sample(p));
    } else {
      for (double t : opt.times) {
        p.setTime(t);
        s.frames.push_back(sample(p));
      }
    }
  } catch (const Error& e) {
    p.setTime(savedTime);
    if (e.file().empty()) throw Error(e.detail(), path, e.element());
    throw;
  }
  p.setTime(savedTime);
  s.materials = p.coatMesh().materials;
  const auto w0 = std::chrono::steady_clock::now();
  if (fmt == Format::Usda) {
    detail::UsdCounts c;
    res.bytes = detail::writeUsda(s, path, opt.as, opt.instancePrototypes, c);
    res.curves = c.curves;
    res.instances = c.instances;
    res.prototypes = c.prototypes;
  } else {
    res.bytes = detail::writeGltf(s, path, fmt == Format::Glb);
  }
  res.writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  res.frames = s.frames.size();
  res.feathers = s.frames.front().ranges.size();
  for (const auto& f : s.frames) {
    res.triangles += f.skin.triangleCount();
    for (size_t t = 0; t < f.coat.triangleCount(); ++t)
      res.triangles += detail::collapsed(&f.coat.indices[3 * t]) ? 0 : 1;
  }
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace pteryla::exchange
