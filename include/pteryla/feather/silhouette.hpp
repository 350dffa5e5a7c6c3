#pragma once
// Silhouette acquisition (Streit 2003, 5.2.3 and 9.1.1): barb lengths from an outline polyline, or from
// an image of a feather (flatbed scan): segment the feather from the background, take the rachis line the
// user marked, estimate the rachis curvature and measure per-position barb lengths along the barb
// directions.
#include <glm/vec2.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

// Barb length profiles from a closed outline polygon in the feather plane (feather-local x, y; the
// ventral-dorsal curvature is ignored). For each of `samples` rp values per vane a ray leaves the
// rachis at the barb angle; its length to the outline is the barb length (0 where the rachis point is
// outside the outline).
Silhouette silhouetteFromOutline(const std::vector<glm::dvec2>& outline, const FeatherParams& p, int samples = 33);

// Single-channel image, row-major, row 0 at the top; values in [0,1].
struct GrayImage {
  int width = 0, height = 0;
  std::vector<float> pixels;
  float at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
};
// Loads any OpenImageIO-readable image as luminance. Throws Error(path) on failure.
GrayImage loadGrayImage(const std::string& path);
void saveGrayImage(const std::string& path, const GrayImage& img);

// Feather/background segmentation (basic thresholding, [GW92]): the background level is the median of the
// border pixels, the threshold Otsu's on |pixel - background|; mask = 1 where the distance exceeds it.
// Throws Error (element "image") for images under 4x4 pixels or without any pixel off the background.
struct Segmentation {
  double background = 0;
  double threshold = 0;
  std::vector<float> distance;  // |pixel - background|, width*height
  std::vector<uint8_t> mask;    // 1 = feather, width*height
};
Segmentation segmentFeather(const GrayImage& img);

struct SilhouetteImageOptions {
  // Rachis as marked by the user, pixel coordinates (x right, y down), from the rachis base (superior
  // umbilicus) to the tip; 2 points = a straight line. The left vane is on the viewer's left when the
  // tip points up (image shows the dorsal side).
  std::vector<glm::dvec2> rachis;
  bool refineRachis = true;  // search the image for the rachis ridge near the marked line
  double searchRadius = 6;   // pixels, for refineRachis
  int samples = 33;          // rp samples per vane
  double gapTolerance = 2;   // pixels of background tolerated inside a vane (gaps between barbs)
  // Barb angles used to cast rays; taken from `angles` of the feather being built.
  double leftBaseAngle = kPi / 2, leftTipAngle = kPi / 2, rightBaseAngle = kPi / 2, rightTipAngle = kPi / 2;
};

struct SilhouetteImageResult {
  double threshold = 0;            // segmentation threshold on |pixel - background|
  double background = 0;           // estimated background level
  double rachisLengthPixels = 0;   // arc length of the (refined) rachis
  double lateralCurvature = 0;     // turning angle, radians, > 0 bends toward the left vane
  std::vector<glm::dvec2> rachis;  // refined rachis samples, pixels
  // Barb lengths as fractions of the rachis length (multiply by rachisLength for scene units).
  Silhouette relative;
  std::vector<uint8_t> mask;  // 1 = feather, width*height
};
SilhouetteImageResult extractSilhouette(const GrayImage& img, const SilhouetteImageOptions& opt);

// Convenience: loads the image, copies barb angles from p, writes p.silhouette (scaled by p.rachisLength)
// and p.rachisLateralCurvature. Returns the raw result.
SilhouetteImageResult applySilhouetteImage(FeatherParams& p, const std::string& imagePath, SilhouetteImageOptions opt);

}  // namespace pteryla::feather
