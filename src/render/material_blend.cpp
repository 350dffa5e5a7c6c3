// Blended feather looks (material_blend.hpp): the CPU side of "materials blend between key feathers by
// the same weights as the geometry" (issue #30 item 2).
#include "pteryla/render/material_blend.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "pteryla/core/error.hpp"

namespace pteryla::render {
namespace {

bool sameImage(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.rgba == b.rgba;
}

size_t heaviest(const std::vector<double>& w) {
  return static_cast<size_t>(std::max_element(w.begin(), w.end()) - w.begin());
}

// Weighted sum of one field over the parts, or the field itself when every part has the same value
// (so equal inputs stay exact whatever the rounding of the weights).
template <class T, class Get>
T blendField(const std::vector<FeatherMaterial>& parts, const std::vector<double>& w, Get get) {
  bool same = true;
  for (const FeatherMaterial& p : parts) same = same && get(p) == get(parts[0]);
  if (same) return get(parts[0]);
  using Scalar = std::conditional_t<std::is_same_v<T, double>, double, float>;
  T acc = get(parts[0]) * static_cast<Scalar>(w[0]);
  for (size_t k = 1; k < parts.size(); ++k) acc += get(parts[k]) * static_cast<Scalar>(w[k]);
  return acc;
}

uint8_t toByte(double v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

// One part's texture (file or in-memory), or null when it has none.
const Image* colorSource(const FeatherMaterial& m, const ImageLoader& load) {
  if (!m.colorTexture.empty()) return &load(m.colorTexture);
  return m.colorImage.empty() ? nullptr : &m.colorImage;
}
const Image* alphaSource(const FeatherMaterial& m, const ImageLoader& load) {
  if (!m.alphaTexture.empty()) return &load(m.alphaTexture);
  return m.alphaImage.empty() ? nullptr : &m.alphaImage;
}

// Same texture: the same file, or no file and the same in-memory image (both empty included).
bool sameColorSource(const FeatherMaterial& a, const FeatherMaterial& b) {
  if (!a.colorTexture.empty() || !b.colorTexture.empty()) return a.colorTexture == b.colorTexture;
  return sameImage(a.colorImage, b.colorImage);
}
bool sameAlphaSource(const FeatherMaterial& a, const FeatherMaterial& b) {
  if (!a.alphaTexture.empty() || !b.alphaTexture.empty()) return a.alphaTexture == b.alphaTexture;
  return sameImage(a.alphaImage, b.alphaImage);
}

// Every part's image (by `source`; null for a part without one), resampled to the largest size among them.
// (Sized at construction: vector::assign of Images instantiates a fill that libpteryla.so would export.)
struct SizedSources {
  explicit SizedSources(size_t n) : src(n), sized(n) {}
  std::vector<const Image*> src;
  std::vector<Image> sized;  // the resampled copies src points into
  int width = 1, height = 1;
};
template <class Source>
void sizeSources(const std::vector<FeatherMaterial>& parts, const ImageLoader& load, Source source, SizedSources& s) {
  for (size_t k = 0; k < parts.size(); ++k) {
    s.src[k] = source(parts[k], load);
    if (s.src[k]) {
      s.width = std::max(s.width, s.src[k]->width);
      s.height = std::max(s.height, s.src[k]->height);
    }
  }
  for (size_t k = 0; k < parts.size(); ++k)
    if (s.src[k] && (s.src[k]->width != s.width || s.src[k]->height != s.height)) {
      s.sized[k] = resampleImage(*s.src[k], s.width, s.height);
      s.src[k] = &s.sized[k];
    }
}

// Base colour x texture of every part, blended with the texture alpha as weight.
Image bakeColor(const std::vector<FeatherMaterial>& parts, const std::vector<double>& w, const ImageLoader& load) {
  SizedSources s(parts.size());
  sizeSources(parts, load, colorSource, s);
  const std::vector<const Image*>& src = s.src;
  const int width = s.width, height = s.height;
  Image out(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double rgb[3] = {0, 0, 0}, plain[3] = {0, 0, 0}, alpha = 0;
      for (size_t k = 0; k < parts.size(); ++k) {
        const glm::vec3& base = parts[k].baseColor;
        double c[3] = {base.x, base.y, base.z}, a = 1.0;
        if (src[k]) {
          const uint8_t* t = src[k]->pixel(x, y);
          for (int ch = 0; ch < 3; ++ch) c[ch] *= t[ch] / 255.0;
          a = t[3] / 255.0;
        }
        for (int ch = 0; ch < 3; ++ch) {
          rgb[ch] += w[k] * a * c[ch];
          plain[ch] += w[k] * c[ch];
        }
        alpha += w[k] * a;
      }
      uint8_t* o = out.pixel(x, y);
      // Where every part is transparent the colour is never seen; keep the plain blend there (mipmaps).
      for (int ch = 0; ch < 3; ++ch) o[ch] = toByte(alpha > 0 ? rgb[ch] / alpha : plain[ch]);
      o[3] = toByte(alpha);
    }
  return out;
}

// The parts' barb alpha masks (red channel; a part without one is opaque) blended, in all four channels.
Image bakeAlpha(const std::vector<FeatherMaterial>& parts, const std::vector<double>& w, const ImageLoader& load) {
  SizedSources s(parts.size());
  sizeSources(parts, load, alphaSource, s);
  const std::vector<const Image*>& src = s.src;
  const int width = s.width, height = s.height;
  Image out(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double v = 0;
      for (size_t k = 0; k < parts.size(); ++k) v += w[k] * (src[k] ? src[k]->pixel(x, y)[0] / 255.0 : 1.0);
      uint8_t* o = out.pixel(x, y);
      o[0] = o[1] = o[2] = o[3] = toByte(v);
    }
  return out;
}

}  // namespace

Image resampleImage(const Image& src, int width, int height) {
  if (src.empty()) throw Error("cannot resample an empty image");
  if (width <= 0 || height <= 0) throw Error("resampled image size must be positive", {}, "width/height");
  if (src.width == width && src.height == height) return src;
  Image out(width, height);
  for (int y = 0; y < height; ++y) {
    const double sy = std::clamp((y + 0.5) * src.height / height - 0.5, 0.0, double(src.height - 1));
    const int y0 = static_cast<int>(sy), y1 = std::min(y0 + 1, src.height - 1);
    const double fy = sy - y0;
    for (int x = 0; x < width; ++x) {
      const double sx = std::clamp((x + 0.5) * src.width / width - 0.5, 0.0, double(src.width - 1));
      const int x0 = static_cast<int>(sx), x1 = std::min(x0 + 1, src.width - 1);
      const double fx = sx - x0;
      const uint8_t *a = src.pixel(x0, y0), *b = src.pixel(x1, y0), *c = src.pixel(x0, y1), *d = src.pixel(x1, y1);
      uint8_t* o = out.pixel(x, y);
      for (int ch = 0; ch < 4; ++ch) {
        const double top = a[ch] + fx * (b[ch] - a[ch]), bottom = c[ch] + fx * (d[ch] - c[ch]);
        o[ch] = static_cast<uint8_t>(std::lround(std::clamp(top + fy * (bottom - top), 0.0, 255.0)));
      }
    }
  }
  return out;
}

bool sameLook(const FeatherMaterial& a, const FeatherMaterial& b) {
  return a.baseColor == b.baseColor && sameColorSource(a, b) && a.colorUv == b.colorUv && sameAlphaSource(a, b) &&
         a.useBrdf == b.useBrdf && a.barbules.d == b.barbules.d && a.barbules.h == b.barbules.h &&
         a.barbules.sigma == b.barbules.sigma && a.barbuleAngle == b.barbuleAngle && a.specular == b.specular &&
         a.coneSigma == b.coneSigma && a.translucency == b.translucency && a.sheathColor == b.sheathColor;
}

FeatherMaterial blendFeatherMaterials(const std::vector<FeatherMaterial>& parts, const std::vector<double>& weights,
                                      const std::string& name, const ImageLoader& load) {
  if (parts.empty() || parts.size() != weights.size())
    throw Error("a material blend needs one weight per part and at least one part");
  double sum = 0;
  for (size_t k = 0; k < weights.size(); ++k) {
    if (!(weights[k] > 0) || !std::isfinite(weights[k]))
      throw Error("material blend weights must be finite and > 0", {}, "weights[" + std::to_string(k) + "]");
    sum += weights[k];
  }
  if (std::abs(sum - 1.0) > 1e-9) throw Error("material blend weights must sum to 1", {}, "weights");
  bool allSame = true;
  for (const FeatherMaterial& p : parts) allSame = allSame && sameLook(p, parts[0]);
  FeatherMaterial out = parts[heaviest(weights)];
  out.name = name;
  if (allSame) {
    out = parts[0];
    out.name = name;
    return out;
  }
  const auto& w = weights;
  // Colour.
  bool sameColor = true;
  for (const FeatherMaterial& p : parts) sameColor = sameColor && sameColorSource(p, parts[0]);
  if (sameColor) {
    out.colorTexture = parts[0].colorTexture;
    out.colorImage = parts[0].colorImage;
    out.baseColor = blendField<glm::vec3>(parts, w, [](const FeatherMaterial& m) { return m.baseColor; });
  } else {
    out.colorTexture.clear();
    out.colorImage = bakeColor(parts, w, load);
    out.baseColor = glm::vec3(1.0f);
  }
  // Barb alpha mask.
  bool sameAlpha = true;
  for (const FeatherMaterial& p : parts) sameAlpha = sameAlpha && sameAlphaSource(p, parts[0]);
  if (sameAlpha) {
    out.alphaTexture = parts[0].alphaTexture;
    out.alphaImage = parts[0].alphaImage;
  } else {
    out.alphaTexture.clear();
    out.alphaImage = bakeAlpha(parts, w, load);
  }
  // Reflection.
  out.barbules.d = blendField<double>(parts, w, [](const FeatherMaterial& m) { return m.barbules.d; });
  out.barbules.h = blendField<double>(parts, w, [](const FeatherMaterial& m) { return m.barbules.h; });
  out.barbules.sigma = blendField<double>(parts, w, [](const FeatherMaterial& m) { return m.barbules.sigma; });
  out.barbuleAngle = blendField<float>(parts, w, [](const FeatherMaterial& m) { return m.barbuleAngle; });
  out.specular = blendField<float>(parts, w, [](const FeatherMaterial& m) { return m.specular; });
  out.coneSigma = blendField<float>(parts, w, [](const FeatherMaterial& m) { return m.coneSigma; });
  out.translucency = blendField<float>(parts, w, [](const FeatherMaterial& m) { return m.translucency; });
  out.sheathColor = blendField<glm::vec3>(parts, w, [](const FeatherMaterial& m) { return m.sheathColor; });
  return out;
}

}  // namespace pteryla::render
