// The scan as the feather's colour texture, Streit 2003 9.1.1 ("The only adjustment made to the texture
// was to the rachis placement and to re-sample the texture"): the scan resampled into the feather-global
// texture space of 7.1.1 (mesh.hpp, uvGlobal), and written as PNG through AtomicFile.
#include <glm/geometric.hpp>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/scan.hpp"
#include "scan_internal.hpp"

namespace pteryla::feather {

using scanning::PixelArc;
using scanning::sample;

std::optional<double> scanPixelsPerCentimetre(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return std::nullopt;
  const OIIO::ImageSpec& spec = in->spec();
  const float res = spec.get_float_attribute("XResolution", 0.0f);
  const std::string unit = spec.get_string_attribute("ResolutionUnit", "");
  in->close();
  if (!(res > 0) || !std::isfinite(res)) return std::nullopt;
  if (unit == "in" || unit == "inch") return res / 2.54;
  if (unit == "cm") return res;
  return std::nullopt;
}

ScanTexture scanTexture(const std::string& scanPath, const ScanResult& r, int maxSide) {
  const FeatherParams& p = r.feather;
  // Extents of the feather-global map, as the mesher computes them (mesh_plan.cpp, buildReference).
  GenerateOptions go;
  go.afterfeather = false;
  const FeatherCurves curves = generateBarbs(p, go);
  double alongMin = 0, alongMax = p.totalLength(), acrossMax = 0.5 * p.rachisWidth;
  for (const BarbCurve& b : curves.barbs) {
    const RachisFrame f = rachisFrame(p, b.rp);
    const double s0 = p.calamusLength + b.rp * p.rachisLength;
    for (uint16_t k = 0; k < b.cvCount; ++k) {
      const glm::dvec3 d = glm::dvec3(curves.cvs[b.cvOffset + k]) - f.point;
      alongMin = std::min(alongMin, s0 + glm::dot(d, f.tangent));
      alongMax = std::max(alongMax, s0 + glm::dot(d, f.tangent));
      acrossMax = std::max(acrossMax, std::abs(glm::dot(d, f.left)));
    }
  }
  // Scan pixels per scene unit of this feather.
  const double ppu = r.rachisLengthPixels / p.rachisLength;
  double tw = 2 * acrossMax * ppu, th = (alongMax - alongMin) * ppu;
  const double shrink = std::max({1.0, tw / maxSide, th / maxSide});
  ScanTexture tex;
  tex.width = std::max(1, static_cast<int>(std::ceil(tw / shrink)));
  tex.height = std::max(1, static_cast<int>(std::ceil(th / shrink)));

  // The colour scan.
  auto in = OIIO::ImageInput::open(scanPath);
  if (!in) throw Error("cannot read image: " + OIIO::geterror(), scanPath);
  const OIIO::ImageSpec& spec = in->spec();
  const int w = spec.width, h = spec.height, nc = spec.nchannels;
  if (w <= 0 || h <= 0 || nc <= 0) throw Error("empty image", scanPath);
  requireMemory(double(w) * h * (nc + 3) * 4.0 + double(tex.width) * tex.height * 4.0, "scan texture", scanPath, "");
  std::vector<float> raw(static_cast<size_t>(w) * h * nc);
  if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, raw.data()))
    throw Error("cannot read image: " + in->geterror(), scanPath);
  in->close();
  std::array<std::vector<float>, 3> rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c].resize(static_cast<size_t>(w) * h);
    for (size_t i = 0; i < rgb[c].size(); ++i) {
      const float* px = &raw[i * nc];
      float v = nc >= 3 ? px[c] : px[0];
      if (nc == 2 || nc >= 4) {
        const float a = px[nc == 2 ? 1 : 3];
        v = v * a + (1 - a);  // over white, as loadGrayImage
      }
      rgb[c][i] = std::clamp(v, 0.0f, 1.0f);
    }
  }
  std::array<float, 3> background{};
  for (int c = 0; c < 3; ++c) {
    std::vector<float> border;
    for (int x = 0; x < w; ++x)
      border.push_back(rgb[c][x]), border.push_back(rgb[c][static_cast<size_t>(h - 1) * w + x]);
    for (int y = 0; y < h; ++y)
      border.push_back(rgb[c][static_cast<size_t>(y) * w]),
          border.push_back(rgb[c][static_cast<size_t>(y) * w + w - 1]);
    std::nth_element(border.begin(), border.begin() + border.size() / 2, border.end());
    background[c] = border[border.size() / 2];
  }
  const PixelArc arc(r.rachis, p.rachisLateralCurvature, r.rachisLengthPixels);
  const double calamusPx = p.calamusLength * ppu;
  tex.rgba.resize(static_cast<size_t>(tex.width) * tex.height * 4);
  for (int j = 0; j < tex.height; ++j)
    for (int i = 0; i < tex.width; ++i) {
      const double u = (i + 0.5) / tex.width, v = 1 - (j + 0.5) / tex.height;
      const double along = (alongMin + v * (alongMax - alongMin)) * ppu - calamusPx;  // pixels from the rachis base
      const double across = (0.5 - u) * 2 * acrossMax * ppu;                          // pixels toward the left vane
      const glm::dvec2 q = arc.point(along) + across * arc.side(0, along);
      uint8_t* o = &tex.rgba[(static_cast<size_t>(j) * tex.width + i) * 4];
      const bool outside = q.x < 0 || q.y < 0 || q.x > w - 1 || q.y > h - 1;
      for (int c = 0; c < 3; ++c) {
        const double val = outside ? background[c] : sample(rgb[c], w, h, q.x, q.y);
        o[c] = static_cast<uint8_t>(std::lround(std::clamp(val, 0.0, 1.0) * 255));
      }
      o[3] = 255;
    }
  return tex;
}

void saveScanTexture(const std::string& path, const ScanTexture& tex) {
  if (tex.width <= 0 || tex.height <= 0 || tex.rgba.size() != static_cast<size_t>(tex.width) * tex.height * 4)
    throw Error("cannot save an empty or inconsistent texture", path);
  // Encoded in memory, then written through AtomicFile (as render::saveImage does).
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error("no image writer for this file type (" + OIIO::geterror() + ")", path);
  OIIO::ImageSpec spec(tex.width, tex.height, 4, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:UnassociatedAlpha", 1);
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  if (!out->supports("ioproxy") || !out->set_ioproxy(&memory))
    throw Error("this image type cannot be written atomically; use .png", path);
  if (!out->open(path, spec)) throw Error("cannot open image for writing: " + out->geterror(), path);
  if (!out->write_image(OIIO::TypeDesc::UINT8, tex.rgba.data()) || !out->close())
    throw Error("cannot write image: " + out->geterror() + " (any previous file is unchanged)", path);
  out.reset();
  if (encoded.empty()) throw Error("the image encoder produced no data", path);
  AtomicFile file(path);
  file.write(encoded.data(), encoded.size());
  file.commit();
}

}  // namespace pteryla::feather
