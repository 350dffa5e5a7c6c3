#pragma once
// Feather acquisition from a flatbed scan (Streit 2003, 5.2.3 and 9.1.1). silhouette.hpp measures the
// silhouette and the lateral rachis curvature; this adds what the thesis says a scan can also give: the
// barb spacing, the barb angles, key barb shapes, the calamus, and the scan itself as the colour texture,
// resampled into the feather-global texture space (7.1.1). The ventral-dorsal curvature is not visible
// in a flat scan and is left 0 (thesis 5.2.3: "would still have to be added manually").
//
// What is measured and how (docs/feather-format.md, "Feathers from scans", gives the tolerances):
//  - rachis: marked by the user, or detectRachis(); refined and fitted as a circular arc (silhouette.hpp);
//  - spacing: the period of the intensity along lines parallel to the rachis inside each vane
//    (autocorrelation peak, sub-pixel), fitted linearly in rp;
//  - barb angles and key barbs: the dominant orientation (seeded by the structure tensor of the smoothed
//    image, refined to the sharpest projection) in windows at several rp and several distances from the
//    rachis, leaving out windows whose barbs are under 3.5 pixels apart; each window's barbs are traced back
//    to their root, and the model angle(rp, f) = a(rp) - bend(rp) f (f = fraction of the way across the
//    vane, a and bend linear in rp) is fitted by least squares. a(0), a(1) are the base and tip angles;
//    bend(0) and bend(1) become two key barbs, at rp 0 and rp 1, each a circular arc turning by its bend
//    (> 0 toward the feather tip), flat (z = 0), chord 1;
//  - calamus: the bare shaft beyond the rachis base: its length, and from its width half-way down (the
//    calamus tapers from calamusWidthRatio x the rachis width to the rachis width) the rachis width;
//  - silhouette: barb lengths along the fitted barb angles (extractSilhouette).
// Nothing here is random; the result's seed is ScanOptions::seed.
#include <glm/vec2.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/feather/params.hpp"
#include "pteryla/feather/silhouette.hpp"

namespace pteryla::feather {

// 300 dots per inch in pixels per centimetre (the library feathers are in centimetres).
inline constexpr double kDefaultScanPixelsPerUnit = 300.0 / 2.54;

struct ScanOptions {
  // Rachis in pixels (x right, y down), base (superior umbilicus) to tip, as for extractSilhouette; empty
  // = detectRachis().
  std::vector<glm::dvec2> rachis;
  double pixelsPerUnit = kDefaultScanPixelsPerUnit;  // scan pixels per scene unit, > 0
  int samples = 33;                                  // silhouette rp samples per vane, >= 2
  double gapTolerance = 2;                           // pixels of background tolerated inside a vane
  uint64_t seed = 1;                                 // FeatherParams::seed of the result
};

// Per-vane orientation fit: angle(rp, f) = baseAngle + (tipAngle - baseAngle) rp - bend(rp) f.
struct ScanVaneFit {
  double baseAngle = 0, tipAngle = 0;  // radians between the rachis (toward the tip) and the barb root
  double bendBase = 0, bendTip = 0;    // turning of the barb over its length, radians, > 0 toward the tip
  int windows = 0;                     // orientation windows the fit kept (coherent, not outliers)
  // false: too few windows, or a fit at its limits, keeping under half the windows or with residuals over
  // 4 degrees rms (barbs too fine for the resolution, or disordered): the default angles were kept.
  bool measured = false;
};

struct ScanResult {
  FeatherParams feather;           // the feather, scene units (lengths = pixels / pixelsPerUnit)
  bool rachisDetected = false;     // the rachis came from detectRachis()
  std::vector<glm::dvec2> rachis;  // fitted rachis arc, 33 samples base to tip, pixels
  double rachisLengthPixels = 0;
  double calamusLengthPixels = 0;                      // 0 when no calamus was seen
  double rachisWidthPixels = 0;                        // 0 when not measured
  double spacingBasePixels = 0, spacingTipPixels = 0;  // fitted barb spacing along the rachis at rp 0, 1
  int spacingWindows = 0;            // autocorrelation windows agreeing with the fitted spacing (0: not measured)
  ScanVaneFit vanes[2];              // left, right
  SilhouetteImageResult silhouette;  // the final silhouette pass (mask, background, relative lengths)
  std::vector<std::string> notes;    // what could not be measured and which default was kept
};

// The rachis of the largest segmented region, as a polyline from base to tip (pixels). The base end is
// the end of the region's principal axis with the longer stretch of bare shaft (the calamus: the region
// at most max(5 px, 6% of its widest) across), the base point the calamus centre where the vanes begin.
// From there the shaft's ridge (as dark or light against the background as the calamus) is followed
// until it fades; a circular arc fitted to the first 85% of that track, continued to where it leaves
// the feather, is the result (the track's end, where the shaft is thinner than the barbs, is not
// trusted). Throws Error (element "rachis") when neither end has a calamus at least 3% of the feather
// long and 1.5 times the other end's (then mark the rachis by hand), and Error (element "image") when
// nothing is segmented.
std::vector<glm::dvec2> detectRachis(const GrayImage& img);

// Measures a feather from a scan. Throws Error (element "image", "rachis" or an option name) for an
// image without a feather, a rachis outside the image, or invalid options.
ScanResult acquireScan(const GrayImage& img, const ScanOptions& opt);

// Pixels per centimetre from the image file's resolution metadata (PNG pHYs, TIFF/JPEG resolution);
// nothing when the file carries none.
std::optional<double> scanPixelsPerCentimetre(const std::string& path);

// RGBA8 image, row-major, row 0 at the top.
struct ScanTexture {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
};
// The colour scan resampled into the feather-global texture space of r.feather (mesh.hpp: u = 0.5 -
// across / (2 maxAcross), v = along / extent; texture row 0 = v 1, the tip): each texel is the scan
// pixel at that distance along and across the fitted rachis (the shaft's curvature is followed, so the
// texture is exact for a straight rachis and off by about curvature x barb length squared otherwise).
// Opaque; outside the scan the background level. At most maxSide texels on the longer side.
ScanTexture scanTexture(const std::string& scanPath, const ScanResult& r, int maxSide = 4096);
// Writes a texture as PNG through AtomicFile (an existing file is replaced only on success).
void saveScanTexture(const std::string& path, const ScanTexture& tex);

}  // namespace pteryla::feather
