// Synthesised feather colour patterns and barb alpha masks (Streit 2003, 7.1.1 texture mapping of
// acquired or synthesised patterns; 7.1.2 the barb alpha texture: opaque barb, translucent
// barbules, quadratic decrease near the tip starting earlier at the edges).
#include "pteryla/render/pattern.hpp"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"

namespace pteryla::render {
namespace {

constexpr float kPi = 3.14159265358979f;

float smoothstep(float e0, float e1, float x) {
  if (e1 <= e0) return x < e0 ? 0.0f : 1.0f;
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Smooth value noise in [0,1] on a lattice of the given frequency.
float valueNoise(uint64_t seed, float x, float y) {
  const float fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  auto h = [&](int64_t a, int64_t b) {
    return static_cast<float>(hashUniform(seed, static_cast<uint64_t>(a) * 0x9E3779B1ull, static_cast<uint64_t>(b)));
  };
  float tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const float a = h(ix, iy), b = h(ix + 1, iy), c = h(ix, iy + 1), d = h(ix + 1, iy + 1);
  return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
}

// Half-width of the vane (fraction of the half texture width) at v: the feather outline.
float vaneHalfWidth(float v) {
  if (v <= 0.0f || v >= 1.0f) return 0.0f;
  const float body = std::pow(std::sin(kPi * std::min(1.0f, 0.08f + 0.92f * v)), 0.5f);
  const float tip = v > 0.8f ? std::sqrt(std::max(0.0f, 1.0f - std::pow((v - 0.8f) / 0.2f, 2.0f))) : 1.0f;
  const float base = smoothstep(0.0f, 0.06f, v);
  return 0.96f * body * tip * base;
}

uint8_t toByte(float x) { return static_cast<uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f)); }

void checkParams(int w, int h, const char* what) {
  if (w <= 0 || h <= 0 || w > 8192 || h > 8192)
    throw Error(std::string(what) + " size must be in [1, 8192]", {}, "width/height");
}

}  // namespace

Image generatePattern(const PatternParams& p) {
  checkParams(p.width, p.height, "pattern");
  if (!(p.markWidth > 0.0f && p.markWidth < 1.0f)) throw Error("markWidth must be in (0, 1)", {}, "markWidth");
  if (!(p.frequency > 0.0f)) throw Error("frequency must be > 0", {}, "frequency");
  if (!(p.softness >= 0.0f)) throw Error("softness must be >= 0", {}, "softness");
  Image img(p.width, p.height);
  const float aspect = float(p.width) / float(p.height);
  const float soft = std::max(p.softness, 1e-4f);
  for (int y = 0; y < p.height; ++y) {
    const float v = 1.0f - (float(y) + 0.5f) / float(p.height);
    const float hw = vaneHalfWidth(v);
    for (int x = 0; x < p.width; ++x) {
      const float u = (float(x) + 0.5f) / float(p.width);
      const float r = std::abs(u - 0.5f) * 2.0f;  // 0 at the rachis, 1 at the texture edge
      float mark = 0.0f;                          // amount of markColor
      float accent = 0.0f;                        // amount of accentColor
      switch (p.kind) {
        case PatternKind::Plain:
          break;
        case PatternKind::Barred: {
          // Chevron bars pointing to the tip.
          const float phase = v * p.frequency - 0.6f * r;
          const float f = phase - std::floor(phase);
          const float e = soft * p.frequency;
          mark = smoothstep(0.0f, e, f) * (1.0f - smoothstep(p.markWidth - e, p.markWidth, f));
          break;
        }
        case PatternKind::Scalloped: {
          // Arcs concentric about the feather base: U-shaped bands that repeat as scallops across a
          // coat, with a pale fringe beyond the last band.
          const float rho = std::sqrt(r * r + v * v);
          const float phase = rho * p.frequency * 0.5f;
          const float f = phase - std::floor(phase);
          const float e = soft * p.frequency * 0.5f;
          const float w = p.markWidth * 0.5f;
          mark = rho < 0.93f ? smoothstep(0.0f, e, f) * (1.0f - smoothstep(w - e, w, f)) : 0.0f;
          break;
        }
        case PatternKind::Spotted: {
          const float gx = u * p.frequency * aspect * 2.0f, gy = v * p.frequency;
          for (int oy = -1; oy <= 1; ++oy) {
            for (int ox = -1; ox <= 1; ++ox) {
              const int64_t cx = static_cast<int64_t>(std::floor(gx)) + ox,
                            cy = static_cast<int64_t>(std::floor(gy)) + oy;
              const auto kx = static_cast<uint64_t>(cx), ky = static_cast<uint64_t>(cy);
              const float px = float(cx) + 0.2f + 0.6f * float(hashUniform(p.seed, kx * 7919u + 1u, ky));
              const float py = float(cy) + 0.2f + 0.6f * float(hashUniform(p.seed, kx * 7919u + 2u, ky));
              const float rad = 0.5f * p.markWidth * (0.6f + 0.8f * float(hashUniform(p.seed, kx * 7919u + 3u, ky)));
              const float d = std::hypot(gx - px, gy - py);
              mark = std::max(mark, 1.0f - smoothstep(rad * (1.0f - soft * 4.0f), rad, d));
            }
          }
          break;
        }
        case PatternKind::Eyespot: {
          // Ocellus near the tip: dark pupil, accent iris, dark ring, accent halo.
          const float dx = (u - 0.5f) * aspect * 2.0f, dy = v - 0.76f;
          const float d = std::hypot(dx, dy * 1.15f) / std::max(0.05f, 0.5f * p.markWidth);
          const float e = soft * 4.0f;
          const float pupil = 1.0f - smoothstep(0.30f - e, 0.30f, d);
          const float iris = smoothstep(0.30f - e, 0.30f, d) * (1.0f - smoothstep(0.55f - e, 0.55f, d));
          const float ring = smoothstep(0.55f - e, 0.55f, d) * (1.0f - smoothstep(0.78f - e, 0.78f, d));
          const float halo = smoothstep(0.78f - e, 0.78f, d) * (1.0f - smoothstep(1.0f - e, 1.0f, d));
          mark = pupil + ring;
          accent = iris + 0.6f * halo;
          break;
        }
      }
      glm::vec3 c = glm::mix(p.baseColor, p.markColor, std::clamp(mark, 0.0f, 1.0f));
      c = glm::mix(c, p.accentColor, std::clamp(accent, 0.0f, 1.0f));
      // Rachis stripe, tip darkening, seeded noise.
      const float shaft = 1.0f - smoothstep(0.015f, 0.04f, r);
      c *= 1.0f - p.shaftDarken * shaft;
      c *= 1.0f - p.tipDarken * smoothstep(0.6f, 1.0f, v);
      const float n = valueNoise(p.seed, u * 16.0f, v * 32.0f) - 0.5f;
      c *= 1.0f + 2.0f * p.noise * n;
      float alpha = 1.0f;
      if (p.outline) {
        const float edge = 1.5f / float(p.width);
        alpha = 1.0f - smoothstep(hw - edge, hw + edge, r);
      }
      uint8_t* px = img.pixel(x, y);
      px[0] = toByte(c.r);
      px[1] = toByte(c.g);
      px[2] = toByte(c.b);
      px[3] = toByte(alpha);
    }
  }
  return img;
}

Image generateBarbAlpha(const BarbAlphaParams& p) {
  checkParams(p.width, p.height, "barb alpha");
  if (!(p.barbWidth > 0.0f && p.barbWidth < 1.0f)) throw Error("barbWidth must be in (0, 1)", {}, "barbWidth");
  if (!(p.tipFalloff > 0.0f && p.tipFalloff <= 1.0f)) throw Error("tipFalloff must be in (0, 1]", {}, "tipFalloff");
  Image img(p.width, p.height);
  const float halfCore = 0.5f * p.barbWidth;
  for (int y = 0; y < p.height; ++y) {
    const float t = 1.0f - (float(y) + 0.5f) / float(p.height);
    for (int x = 0; x < p.width; ++x) {
      const float s = (float(x) + 0.5f) / float(p.width);
      const float off = std::abs(s - 0.5f);
      float a;
      float edgeness;  // 0 on the barb, 1 at the fringe edge
      if (off <= halfCore) {
        a = 1.0f;
        edgeness = 0.0f;
      } else {
        edgeness = std::clamp((off - halfCore) / (0.5f - halfCore), 0.0f, 1.0f);
        a = p.barbuleOpacity * (1.0f - 0.5f * edgeness * edgeness);
        if (p.fluff > 0.0f) {
          // Plumulaceous barbules: sparse wavy threads instead of a closed fringe.
          const float threads = 0.5f + 0.5f * std::sin(2.0f * kPi * (t * 18.0f + off * 6.0f));
          const float n = valueNoise(p.seed, s * 8.0f, t * 24.0f);
          const float sparse = smoothstep(0.45f, 0.75f, threads) * (0.5f + n);
          a *= (1.0f - p.fluff) + p.fluff * std::min(1.0f, sparse);
        }
      }
      // Quadratic decrease toward the tip, starting edgeLead earlier at the fringe edges (7.1.2).
      const float start = std::clamp(1.0f - p.tipFalloff - p.edgeLead * edgeness, 0.0f, 0.999f);
      const float q = std::max(0.0f, (t - start) / (1.0f - start));
      a *= std::max(0.0f, 1.0f - q * q);
      const uint8_t b = toByte(a);
      uint8_t* px = img.pixel(x, y);
      px[0] = px[1] = px[2] = px[3] = b;
    }
  }
  return img;
}

std::vector<NamedImage> standardTextures(uint64_t seed) {
  std::vector<NamedImage> out;
  auto add = [&](const char* name, PatternParams p) {
    p.seed = seed;
    out.push_back({name, generatePattern(p)});
  };
  PatternParams barred;
  barred.kind = PatternKind::Barred;
  barred.baseColor = {0.58f, 0.42f, 0.26f};
  barred.markColor = {0.20f, 0.12f, 0.07f};
  barred.frequency = 7.0f;
  barred.markWidth = 0.4f;
  add("barred_brown", barred);

  PatternParams scallop;
  scallop.kind = PatternKind::Scalloped;
  scallop.baseColor = {0.66f, 0.66f, 0.64f};
  scallop.markColor = {0.22f, 0.22f, 0.24f};
  scallop.frequency = 5.0f;
  scallop.markWidth = 0.45f;
  add("scalloped_grey", scallop);

  PatternParams spots;
  spots.kind = PatternKind::Spotted;
  spots.baseColor = {0.30f, 0.25f, 0.21f};
  spots.markColor = {0.92f, 0.90f, 0.84f};
  spots.frequency = 9.0f;
  spots.markWidth = 0.5f;
  spots.softness = 0.03f;
  add("spotted", spots);

  PatternParams eye;
  eye.kind = PatternKind::Eyespot;
  eye.baseColor = {0.16f, 0.36f, 0.24f};
  eye.markColor = {0.05f, 0.07f, 0.22f};
  eye.accentColor = {0.86f, 0.66f, 0.20f};
  eye.markWidth = 0.5f;
  eye.softness = 0.01f;
  add("eyespot", eye);

  PatternParams white;
  white.baseColor = {0.95f, 0.95f, 0.93f};
  white.shaftDarken = 0.05f;
  white.tipDarken = 0.03f;
  white.noise = 0.02f;
  add("plain_white", white);

  PatternParams down;
  down.baseColor = {0.70f, 0.70f, 0.72f};
  down.noise = 0.12f;
  down.shaftDarken = 0.0f;
  down.outline = false;
  add("down_grey", down);

  PatternParams flight;
  flight.baseColor = {0.13f, 0.12f, 0.11f};
  flight.shaftDarken = -1.5f;
  flight.tipDarken = 0.2f;
  flight.noise = 0.04f;
  add("flight_dark", flight);

  BarbAlphaParams barb;
  barb.seed = seed;
  out.push_back({"barb_alpha", generateBarbAlpha(barb)});
  BarbAlphaParams downBarb;
  downBarb.barbWidth = 0.08f;
  downBarb.barbuleOpacity = 0.6f;
  downBarb.tipFalloff = 0.4f;
  downBarb.fluff = 1.0f;
  downBarb.seed = seed;
  out.push_back({"down_alpha", generateBarbAlpha(downBarb)});
  return out;
}

std::vector<std::string> writeStandardTextures(const std::string& dir, uint64_t seed) {
  std::vector<std::string> paths;
  for (const NamedImage& t : standardTextures(seed)) {
    const std::string path = (dir.empty() ? std::string(".") : dir) + "/" + t.name + ".png";
    saveImage(path, t.image);
    paths.push_back(path);
  }
  return paths;
}

}  // namespace pteryla::render
