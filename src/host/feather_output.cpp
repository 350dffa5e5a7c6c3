// writeFeather and writeFeatherFromScan (include/pteryla/pteryla.hpp): one feather definition file as a
// mesh or an image, and a feather file measured from a scan: what `pteryla feather` writes.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/feather/mesh_io.hpp"
#include "pteryla/feather/scan.hpp"
#include "pteryla/pteryla.hpp"
#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/scene_view.hpp"

namespace pteryla {
namespace {

void createParentDirectory(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(parent, ec);
  if (ec) throw Error("cannot create output directory '" + parent.string() + "': " + ec.message(), path);
}

}  // namespace

size_t writeFeather(const std::string& featherFile, const std::string& out, const FeatherOutput& output) {
  const std::string ext = extensionOf(out);
  if (ext != ".obj" && ext != ".ply" && ext != ".png")
    throw Error("unsupported output type '" + ext + "': expected a mesh or an image (.obj, .ply, .png)", out, "out");
  if (!(output.lod > 0 && output.lod <= 1)) throw Error("expected a fraction in (0, 1]", "", "lod");
  if (!(output.age >= 0 && std::isfinite(output.age))) throw Error("expected a finite age >= 0", "", "age");
  const bool image = ext == ".png";
  if (image)
    for (const auto& [v, name] : {std::pair{output.width, "width"}, {output.height, "height"}})
      if (v < 1 || v > 16384)
        throw Error(std::string(name) + " must be in [1, 16384], got " + std::to_string(v), out, name);
  const feather::FeatherParams p = feather::loadFeather(featherFile);
  const TriMesh mesh = feather::buildFeatherMesh(p, output.age, output.lod, {}, feather::growthScheduleOf(p));
  if (!image) {
    createParentDirectory(out);
    feather::writeMesh(out, mesh);
    return mesh.triangleCount();
  }
  render::OsMesaContext context(output.width, output.height);
  const render::Image picture = render::renderFeatherImage(context, p, mesh, output.width, output.height);
  createParentDirectory(out);
  render::saveImage(out, picture);
  return mesh.triangleCount();
}

namespace {

// `target` as written in a file at `from`: relative to its directory when both are on one root.
std::string pathRelativeTo(const std::string& target, const std::string& from) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path abs = fs::absolute(target, ec);
  const fs::path dir = fs::absolute(from, ec).parent_path();
  const fs::path rel = ec ? fs::path() : abs.lexically_relative(dir);
  return rel.empty() ? abs.generic_string() : rel.generic_string();
}

}  // namespace

ScanSummary writeFeatherFromScan(const std::string& scanImage, const std::string& out, const ScanSettings& settings) {
  if (extensionOf(out) != ".json")
    throw Error("a scan is written as a feather file: expected a .json output", out, "out");
  if (!fileExists(scanImage)) throw Error("scan image not found", scanImage, "scan");
  feather::GrayImage img;
  try {
    img = feather::loadGrayImage(scanImage);
  } catch (const Error& e) {
    throw Error(e.detail() + " (expected an image OpenImageIO reads: .png, .jpg, .tif, ...)", scanImage, "scan");
  }
  // The measurement keeps about a dozen float copies of the scan.
  requireMemory(double(img.width) * img.height * 48.0,
                "measuring a " + std::to_string(img.width) + "x" + std::to_string(img.height) + " scan", scanImage,
                "scan");
  feather::ScanOptions opt;
  for (const auto& q : settings.rachis) {
    if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || q[0] < 0 || q[1] < 0 || q[0] > img.width - 1 ||
        q[1] > img.height - 1) {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "point (%g, %g) lies outside the %dx%d image (expected x in [0, %d], y in [0, %d])", q[0], q[1],
                    img.width, img.height, img.width - 1, img.height - 1);
      throw Error(msg, scanImage, "rachis");
    }
    opt.rachis.emplace_back(q[0], q[1]);
  }
  if (!settings.rachis.empty() && settings.rachis.size() < 2)
    throw Error("expected at least two points (base and tip)", scanImage, "rachis");
  ScanSummary summary;
  if (settings.pixelsPerUnit != 0) {
    if (!(settings.pixelsPerUnit > 0 && std::isfinite(settings.pixelsPerUnit)))
      throw Error("expected scan pixels per scene unit > 0", "", "pixelsPerUnit");
    opt.pixelsPerUnit = settings.pixelsPerUnit;
    summary.resolution = "pixelsPerUnit";
  } else if (const auto ppcm = feather::scanPixelsPerCentimetre(scanImage)) {
    opt.pixelsPerUnit = *ppcm;
    summary.resolution = "the image's resolution";
  } else {
    summary.resolution = "300 dpi assumed";
  }
  std::string texture;
  if (settings.writeTexture) {
    texture = settings.texture;
    if (texture.empty()) texture = std::filesystem::path(out).replace_extension().string() + "_texture.png";
    if (extensionOf(texture) != ".png") throw Error("expected a .png texture file", texture, "texture");
  }
  feather::ScanResult r;
  try {
    r = feather::acquireScan(img, opt);
  } catch (const Error& e) {
    throw Error(e.detail(), scanImage, e.element() == "rachis" ? "rachis" : "scan");
  }
  feather::FeatherParams& p = r.feather;
  p.name = "scan of " + std::filesystem::path(scanImage).filename().string();
  if (!texture.empty()) {
    createParentDirectory(texture);
    feather::saveScanTexture(texture, feather::scanTexture(scanImage, r));
    p.material.texture = pathRelativeTo(texture, out);
  }
  createParentDirectory(out);
  feather::saveFeather(out, p);
  summary.rachisDetected = r.rachisDetected;
  summary.pixelsPerUnit = opt.pixelsPerUnit;
  summary.rachisLength = p.rachisLength;
  summary.lateralCurvature = p.rachisLateralCurvature;
  summary.spacingBase = p.spacingBase;
  summary.spacingTip = p.spacingTip;
  summary.leftBaseAngle = p.left.baseAngle;
  summary.leftTipAngle = p.left.tipAngle;
  summary.rightBaseAngle = p.right.baseAngle;
  summary.rightTipAngle = p.right.tipAngle;
  summary.texture = texture;
  summary.notes = r.notes;
  return summary;
}

}  // namespace pteryla
