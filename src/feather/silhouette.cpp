// Silhouette acquisition, Streit 2003 5.2.3 and 9.1.1: barb lengths from outline data, and from a feather
// image segmented from its background (basic thresholding after Gonzalez & Woods [GW92], here Otsu's
// threshold on the distance to the background level) with the rachis marked by the user; the rachis
// curvature is fitted as a circular arc, barb lengths are measured along the barb directions.
#include "pteryla/feather/silhouette.hpp"

#include <glm/geometric.hpp>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "scan_internal.hpp"

namespace pteryla::feather {

namespace {

// Point-in-polygon (even-odd).
bool inside(const std::vector<glm::dvec2>& poly, glm::dvec2 q) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const glm::dvec2 a = poly[i], b = poly[j];
    if ((a.y > q.y) != (b.y > q.y)) {
      const double x = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (q.x < x) in = !in;
    }
  }
  return in;
}

// Smallest t > tmin with o + t d on the polygon boundary; +inf when none.
double rayHit(const std::vector<glm::dvec2>& poly, glm::dvec2 o, glm::dvec2 d, double tmin) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const glm::dvec2 a = poly[j], e = poly[i] - poly[j];
    const double den = d.x * e.y - d.y * e.x;
    if (std::abs(den) < 1e-300) continue;
    const glm::dvec2 ao = a - o;
    const double t = (ao.x * e.y - ao.y * e.x) / den;
    const double s = (ao.x * d.y - ao.y * d.x) / den;
    if (t > tmin && s >= 0 && s <= 1) best = std::min(best, t);
  }
  return best;
}

using scanning::imageLeft;
using scanning::sample;  // bilinear, clamped to the border

// Circular arc in the image through a start point: chord direction e, turning angle theta (> 0 turns to
// the viewer's left), arc length len.
struct ImageArc {
  glm::dvec2 start{0.0}, t0{0.0}, n0{0.0};
  double theta = 0, len = 0;
  void at(double rp, glm::dvec2& p, glm::dvec2& t) const {
    if (std::abs(theta) < 1e-12) {
      p = start + len * rp * t0;
      t = t0;
      return;
    }
    const double phi = theta * rp, s = std::sin(phi), c = std::cos(phi);
    p = start + (len / theta) * (s * t0 + (s * s / (1 + c)) * n0);
    t = c * t0 + s * n0;
  }
};

}  // namespace

Silhouette silhouetteFromOutline(const std::vector<glm::dvec2>& outline, const FeatherParams& p, int samples) {
  if (outline.size() < 3) throw Error("an outline needs at least 3 points", p.sourceFile, "silhouette.outline");
  if (samples < 2) throw Error("need at least 2 samples", p.sourceFile, "silhouette.samples");
  for (const auto& q : outline)
    if (!std::isfinite(q.x) || !std::isfinite(q.y))
      throw Error("outline points must be finite", p.sourceFile, "silhouette.outline");
  FeatherParams flat;
  flat.calamusLength = p.calamusLength;
  flat.rachisLength = p.rachisLength;
  flat.rachisWidth = p.rachisWidth;
  flat.rachisLateralCurvature = std::clamp(p.rachisLateralCurvature, -kPi, kPi);
  flat.rachisVentralDorsalCurvature = 0;
  const double eps = 1e-9 * std::max(1e-300, p.totalLength());
  Silhouette out;
  for (int v = 0; v < 2; ++v) {
    const VaneParams& vp = p.vane(v);
    const double side = v == 0 ? 1.0 : -1.0;
    LengthProfile& prof = v == 0 ? out.left : out.right;
    for (int i = 0; i < samples; ++i) {
      const double rp = static_cast<double>(i) / (samples - 1);
      const RachisFrame f = rachisFrame(flat, rp);
      const double a = vp.baseAngle * (1 - rp) + vp.tipAngle * rp;
      const glm::dvec2 root = glm::dvec2(f.point) + side * 0.5 * f.width * glm::dvec2(f.left);
      const glm::dvec2 dir = std::cos(a) * glm::dvec2(f.tangent) + side * std::sin(a) * glm::dvec2(f.left);
      double len = 0;
      if (inside(outline, root + 4 * eps * dir)) {
        const double t = rayHit(outline, root, dir, eps);
        len = std::isfinite(t) ? t : 0.0;
      }
      prof.points.emplace_back(rp, len);
    }
  }
  return out;
}

GrayImage loadGrayImage(const std::string& path) {
  using namespace OIIO;
  auto in = ImageInput::open(path);
  if (!in) throw Error("cannot read image: " + OIIO::geterror(), path);
  const ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) throw Error("empty image", path);
  if (static_cast<int64_t>(spec.width) * spec.height > (int64_t(1) << 28)) throw Error("image too large", path);
  std::vector<float> data(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, data.data()))
    throw Error("cannot read image: " + in->geterror(), path);
  GrayImage img;
  img.width = spec.width;
  img.height = spec.height;
  img.pixels.resize(static_cast<size_t>(img.width) * img.height);
  const int nc = spec.nchannels;
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    const float* px = &data[i * nc];
    float lum = nc >= 3 ? 0.2126f * px[0] + 0.7152f * px[1] + 0.0722f * px[2] : px[0];
    if (nc == 2 || nc >= 4) {
      // Composite over white so transparent scans read as background.
      const float a = px[nc == 2 ? 1 : 3];
      lum = lum * a + (1 - a);
    }
    img.pixels[i] = std::clamp(lum, 0.0f, 1.0f);
  }
  return img;
}

void saveGrayImage(const std::string& path, const GrayImage& img) {
  using namespace OIIO;
  auto out = ImageOutput::create(path);
  if (!out) throw Error("cannot write image: " + OIIO::geterror(), path);
  ImageSpec spec(img.width, img.height, 1, TypeDesc::UINT8);
  if (!out->open(path, spec)) throw Error("cannot write image: " + out->geterror(), path);
  if (!out->write_image(TypeDesc::FLOAT, img.pixels.data()))
    throw Error("cannot write image: " + out->geterror(), path);
  out->close();
}

Segmentation segmentFeather(const GrayImage& img) {
  const int w = img.width, h = img.height;
  if (w < 4 || h < 4 || img.pixels.size() != static_cast<size_t>(w) * h)
    throw Error("image must be at least 4x4 pixels", {}, "image");
  Segmentation seg;
  // 1. Background level: median of the border pixels.
  std::vector<float> border;
  for (int x = 0; x < w; ++x) {
    border.push_back(img.at(x, 0));
    border.push_back(img.at(x, h - 1));
  }
  for (int y = 1; y + 1 < h; ++y) {
    border.push_back(img.at(0, y));
    border.push_back(img.at(w - 1, y));
  }
  std::nth_element(border.begin(), border.begin() + border.size() / 2, border.end());
  seg.background = border[border.size() / 2];

  // 2. Segmentation: Otsu threshold on the distance to the background.
  std::vector<float>& dist = seg.distance;
  dist.resize(img.pixels.size());
  float dmax = 0;
  for (size_t i = 0; i < dist.size(); ++i) {
    dist[i] = std::abs(img.pixels[i] - static_cast<float>(seg.background));
    dmax = std::max(dmax, dist[i]);
  }
  if (dmax <= 1e-6f) throw Error("the image has no feather: every pixel matches the background", {}, "image");
  constexpr int kBins = 256;
  std::vector<double> hist(kBins, 0.0);
  for (float d : dist) hist[std::min(kBins - 1, static_cast<int>(d / dmax * kBins))] += 1;
  double total = static_cast<double>(dist.size()), sumAll = 0;
  for (int i = 0; i < kBins; ++i) sumAll += i * hist[i];
  double wB = 0, sumB = 0, bestVar = -1;
  int bestBin = 0;
  for (int i = 0; i < kBins; ++i) {
    wB += hist[i];
    if (wB == 0) continue;
    const double wF = total - wB;
    if (wF == 0) break;
    sumB += i * hist[i];
    const double mB = sumB / wB, mF = (sumAll - sumB) / wF;
    const double var = wB * wF * (mB - mF) * (mB - mF);
    if (var > bestVar) {
      bestVar = var;
      bestBin = i;
    }
  }
  seg.threshold = (bestBin + 1.0) / kBins * dmax;
  seg.mask.resize(dist.size());
  for (size_t i = 0; i < dist.size(); ++i) seg.mask[i] = dist[i] > seg.threshold ? 1 : 0;
  return seg;
}

SilhouetteImageResult extractSilhouette(const GrayImage& img, const SilhouetteImageOptions& opt) {
  const int w = img.width, h = img.height;
  if (w < 4 || h < 4 || img.pixels.size() != static_cast<size_t>(w) * h)
    throw Error("image must be at least 4x4 pixels", {}, "image");
  if (opt.rachis.size() < 2) throw Error("mark the rachis with at least 2 points (base, tip)", {}, "rachis");
  for (const auto& q : opt.rachis)
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || q.x < 0 || q.y < 0 || q.x > w - 1 || q.y > h - 1)
      throw Error("rachis points must lie inside the image", {}, "rachis");
  if (opt.samples < 2) throw Error("need at least 2 samples", {}, "samples");
  SilhouetteImageResult res;

  // 1-2. Background level and segmentation.
  const Segmentation seg = segmentFeather(img);
  res.background = seg.background;
  res.threshold = seg.threshold;
  res.mask = seg.mask;
  const std::vector<float>& dist = seg.distance;

  // 3. Rachis: resample the marked polyline, optionally move samples onto the rachis ridge, fit an arc.
  std::vector<double> cum{0.0};
  for (size_t i = 1; i < opt.rachis.size(); ++i)
    cum.push_back(cum.back() + glm::length(opt.rachis[i] - opt.rachis[i - 1]));
  const double marked = cum.back();
  if (marked < 2) throw Error("the marked rachis is shorter than 2 pixels", {}, "rachis");
  const int nr = std::max(8, static_cast<int>(marked / 3));
  std::vector<glm::dvec2> pts(nr + 1);
  for (int i = 0; i <= nr; ++i) {
    const double s = marked * i / nr;
    size_t k = static_cast<size_t>(std::upper_bound(cum.begin(), cum.end(), s) - cum.begin());
    k = std::clamp<size_t>(k, 1, cum.size() - 1);
    const double seg = cum[k] - cum[k - 1];
    const double f = seg > 0 ? (s - cum[k - 1]) / seg : 0;
    pts[i] = opt.rachis[k - 1] * (1 - f) + opt.rachis[k] * f;
  }
  // Fits a circular arc to the samples: the deviation from the chord of a shallow arc is ~4h u(1-u).
  auto fitArc = [](const std::vector<glm::dvec2>& q) {
    const glm::dvec2 a = q.front(), b = q.back();
    const double chord = glm::length(b - a);
    const glm::dvec2 e = (b - a) / chord, nl = imageLeft(e);
    double num = 0, den = 0;
    for (const auto& x : q) {
      const double u = glm::dot(x - a, e) / chord;
      const double basis = 4 * u * (1 - u);
      num += glm::dot(x - a, nl) * basis;
      den += basis * basis;
    }
    const double sag = den > 0 ? num / den : 0;  // bulge toward the viewer's left
    // An arc turning left bulges to the right of its chord.
    ImageArc arc;
    arc.theta = std::clamp(-4 * std::atan(2 * sag / chord), -kPi, kPi);
    arc.start = a;
    arc.t0 = std::cos(-arc.theta / 2) * e + std::sin(-arc.theta / 2) * nl;
    arc.n0 = imageLeft(arc.t0);
    arc.len = std::abs(arc.theta) < 1e-9 ? chord : chord * (arc.theta / 2) / std::sin(arc.theta / 2);
    return arc;
  };
  ImageArc arc = fitArc(pts);
  if (opt.refineRachis && opt.searchRadius > 0) {
    // Move interior samples onto the rachis ridge (the line contrasting most with the vane around it),
    // refit, and search again around the fitted arc until it settles.
    std::vector<glm::dvec2> refined = pts;
    std::vector<double> window;
    for (int iter = 0; iter < 8; ++iter) {
      std::vector<glm::dvec2> guess(pts.size());
      for (int i = 0; i <= nr; ++i) {
        glm::dvec2 t;
        arc.at(static_cast<double>(i) / nr, guess[i], t);
      }
      guess.front() = pts.front();
      guess.back() = pts.back();
      refined = guess;
      for (int i = 1; i < nr; ++i) {
        const glm::dvec2 t = glm::normalize(guess[i + 1] - guess[i - 1]);
        const glm::dvec2 n = imageLeft(t);
        // Vane level: median intensity of foreground samples across a wider window.
        window.clear();
        for (double o = -3 * opt.searchRadius; o <= 3 * opt.searchRadius; o += 0.5) {
          const glm::dvec2 q = guess[i] + o * n;
          if (sample(dist, w, h, q.x, q.y) > res.threshold) window.push_back(sample(img.pixels, w, h, q.x, q.y));
        }
        if (window.size() < 4) continue;
        std::nth_element(window.begin(), window.begin() + window.size() / 2, window.end());
        const double vane = window[window.size() / 2];
        double best = 0, bestO = 0;
        for (double o = -opt.searchRadius; o <= opt.searchRadius; o += 0.25) {
          const glm::dvec2 q = guess[i] + o * n;
          const double c = std::abs(sample(img.pixels, w, h, q.x, q.y) - vane);
          if (c > best + 1e-9) {
            best = c;
            bestO = o;
          }
        }
        // Only trust a ridge that stands out from the vane.
        if (best > 0.25 * res.threshold) refined[i] = guess[i] + bestO * n;
      }
      const ImageArc next = fitArc(refined);
      const bool settled = std::abs(next.theta - arc.theta) < 1e-4;
      arc = next;
      if (settled) break;
    }
    pts = refined;
  }
  res.lateralCurvature = arc.theta;
  res.rachisLengthPixels = arc.len;
  res.rachis.clear();
  for (int i = 0; i <= 32; ++i) {
    glm::dvec2 p, t;
    arc.at(i / 32.0, p, t);
    res.rachis.push_back(p);
  }

  // 4. Barb lengths along the barb directions, measured from the rachis centre line.
  const double step = 0.25;
  for (int v = 0; v < 2; ++v) {
    const double side = v == 0 ? 1.0 : -1.0;
    const double aBase = v == 0 ? opt.leftBaseAngle : opt.rightBaseAngle;
    const double aTip = v == 0 ? opt.leftTipAngle : opt.rightTipAngle;
    LengthProfile& prof = v == 0 ? res.relative.left : res.relative.right;
    for (int i = 0; i < opt.samples; ++i) {
      const double rp = static_cast<double>(i) / (opt.samples - 1);
      glm::dvec2 p, t;
      arc.at(rp, p, t);
      const double ang = aBase * (1 - rp) + aTip * rp;
      const glm::dvec2 dir = std::cos(ang) * t + side * std::sin(ang) * imageLeft(t);
      double lastInside = 0, prevVal = sample(dist, w, h, p.x, p.y), prevS = 0;
      double edge = 0;
      for (double s = step;; s += step) {
        const glm::dvec2 q = p + s * dir;
        if (q.x < 0 || q.y < 0 || q.x > w - 1 || q.y > h - 1) break;
        const double val = sample(dist, w, h, q.x, q.y);
        if (val > res.threshold) {
          lastInside = s;
        } else if (prevVal > res.threshold) {
          // Sub-pixel crossing between the previous (inside) and this (outside) sample.
          edge = prevS + step * (prevVal - res.threshold) / std::max(1e-12, prevVal - val);
        }
        if (s - lastInside > opt.gapTolerance + step) break;
        prevVal = val;
        prevS = s;
      }
      if (edge < lastInside) edge = lastInside;
      prof.points.emplace_back(rp, edge / arc.len);
    }
  }
  return res;
}

SilhouetteImageResult applySilhouetteImage(FeatherParams& p, const std::string& imagePath, SilhouetteImageOptions opt) {
  opt.leftBaseAngle = p.left.baseAngle;
  opt.leftTipAngle = p.left.tipAngle;
  opt.rightBaseAngle = p.right.baseAngle;
  opt.rightTipAngle = p.right.tipAngle;
  SilhouetteImageResult res;
  try {
    res = extractSilhouette(loadGrayImage(imagePath), opt);
  } catch (const Error& e) {
    throw e.withFile(imagePath);
  }
  p.rachisLateralCurvature = std::clamp(res.lateralCurvature, -kPi, kPi);
  // Lengths from the rachis centre line, minus the half rachis width so barbs start at its edge.
  for (int v = 0; v < 2; ++v) {
    const LengthProfile& rel = v == 0 ? res.relative.left : res.relative.right;
    LengthProfile& dst = v == 0 ? p.silhouette.left : p.silhouette.right;
    const VaneParams& vp = p.vane(v);
    dst.points.clear();
    for (const auto& q : rel.points) {
      const double a = vp.baseAngle * (1 - q.x) + vp.tipAngle * q.x;
      const double halfWidth = 0.5 * p.rachisWidth * (1 - q.x) / std::max(1e-3, std::sin(a));
      dst.points.emplace_back(q.x, std::max(0.0, q.y * p.rachisLength - halfWidth));
    }
  }
  return res;
}

}  // namespace pteryla::feather
