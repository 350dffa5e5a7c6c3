// writeFeather (include/pteryla/pteryla.hpp): one feather definition file as a mesh or an image, what
// `pteryla feather` writes.
#include <cmath>
#include <filesystem>

#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/feather/mesh_io.hpp"
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
      if (v < 1 || v > 16384) throw Error(std::string(name) + " must be in [1, 16384], got " + std::to_string(v), out, name);
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

}  // namespace pteryla
