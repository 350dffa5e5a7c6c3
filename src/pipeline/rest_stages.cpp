// The rest stages of the pipeline (Streit 2003, Ch.6): the skin and the feather library, the tracts,
// follicle distribution (with overlapping tracts, 9.2.1), key-feather interpolation, and the feather
// directions with the layer order. Each runs only when its section of the scene changed
// (scene_stages.hpp); the time stages are in pipeline.cpp.
#include <algorithm>
#include <filesystem>
#include <limits>

#include <glm/common.hpp>

#include "pipeline_impl.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/io.hpp"
#include "scene_sections.hpp"

namespace pteryla::pipeline {

namespace {

// Memory estimates checked against the ceiling (core/limits.hpp, docs/limits.md).
constexpr double kTrianglesPerBarb = 16;
constexpr double kBytesPerTriangle = 200;

// Axes of the rest skin's bounding box, longest first.
void boxAxes(const coat::SkinMesh& m, glm::dvec3& lo, glm::dvec3& hi, int axes[3]) {
  lo = hi = m.positions.empty() ? glm::dvec3(0) : m.positions[0];
  for (const auto& p : m.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 ext = hi - lo;
  axes[0] = 0;
  axes[1] = 1;
  axes[2] = 2;
  std::sort(axes, axes + 3, [&](int a, int b) { return ext[a] > ext[b]; });
}

// The scene's painted density factor (docs/scene-format.md, "Density map") as a multiplier over the rest
// skin, linear across each face; empty without a map. Throws when it does not fit the mesh.
std::function<double(uint32_t, const glm::dvec3&)> densityFactorField(const Scene& scene, const coat::SkinMesh& rest) {
  if (!scene.densityFactor) return {};
  const std::shared_ptr<const std::vector<float>> f = scene.densityFactor;
  if (f->size() != rest.positions.size())
    throw Error("the density map has " + std::to_string(f->size()) + " factors for a mesh of " +
                    std::to_string(rest.positions.size()) + " vertices (paint it again on this mesh)",
                scene.densityMap.empty() ? scene.file : scene.densityMap,
                scene.densityMap.empty() ? "density_map" : "factor");
  const coat::SkinMesh* mesh = &rest;
  return [f, mesh](uint32_t face, const glm::dvec3& b) {
    const auto& t = mesh->faces[face];
    return b.x * double((*f)[t[0]]) + b.y * double((*f)[t[1]]) + b.z * double((*f)[t[2]]);
  };
}

}  // namespace

void Pipeline::Impl::computeSkin() {
  report(progress, "load", 0);
  coat::MeshLoadOptions o;
  o.repair = scene.meshRepair;
  if (memorySkin) {
    rest = *memorySkin;
  } else {
    if (!scene.fromBareMesh && !std::filesystem::is_regular_file(scene.meshPath))
      throw Error("mesh file '" + scene.meshPath + "' " +
                      (std::filesystem::exists(scene.meshPath) ? "is not a regular file" : "does not exist"),
                  scene.file, "mesh");
    rest = coat::loadSkinMesh(scene.meshPath, o);
  }
  // Feather library: every named feather of the scene.
  library.clear();
  materialNames.clear();
  // A scene without feathers gets the bundled contour feather, as a bare mesh does.
  const Json feathers =
      scene.feathers.empty()
          ? Json{{"contour", (std::filesystem::path(dataDir()) / "feathers" / "contour.json").string()}}
          : scene.feathers;
  for (auto it = feathers.begin(); it != feathers.end(); ++it) {
    feather::FeatherParams p;
    if (it->is_string()) {
      try {
        p = feather::loadFeather(it->get<std::string>());
      } catch (const Error& e) {
        throw Error(e.detail(), e.file().empty() ? scene.file : e.file(),
                    e.file().empty() ? "feathers." + it.key() : e.element());
      }
    } else {
      JsonReader r(*it, scene.file, "feathers." + it.key());
      p = feather::readFeather(r);
      p.sourceFile = scene.file;
    }
    p.name = it.key();
    library[it.key()] = std::move(p);
    materialNames.push_back(it.key());
  }
  if (library.empty()) throw Error("the scene defines no feathers", scene.file, "feathers");
  report(progress, "load", 1);
}

void Pipeline::Impl::computeTracts() {
  tractSettings.clear();
  tracts.clear();
  // The scene's growth schedule (docs/growth.md), read with the tracts: feathers whose file and tract
  // give none grow and wear by it.
  sceneGrowth.reset();
  sceneGrowth = settings.growth(scene);
  tractSettings = settings.tracts(scene, rest, graph.evaluations(id(Stage::Skin)));
  for (const TractSettings& t : tractSettings) tracts.push_back(t.tract);
}

void Pipeline::Impl::computeDistribute() {
  follicles.clear();
  relaxResults.clear();
  uint64_t nextId = 0;
  const auto factor = densityFactorField(scene, rest);
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    TractSettings& t = tractSettings[i];
    coat::ScatterOptions so;
    // A tract's own seed re-scatters only that tract; the others keep their follicles.
    so.seed = t.seed ? mix64(*t.seed * 0x9E37u + 0x5EED0000u) : mix64(scene.seed * 0x9E37u + i);
    so.density.uniform = t.density;
    so.density.multiplier = factor;
    so.count = t.count;
    so.tractIndex = static_cast<uint32_t>(i);
    so.firstId = nextId;
    // count 0 with no density: a tract of hand-placed (pinned) follicles only, e.g. flight feathers.
    coat::Follicles f =
        (so.count == 0 && t.density <= 0) ? coat::Follicles{} : coat::scatterFollicles(rest, t.tract, so);
    nextId += f.size() + t.pinned.size() + 1;
    for (size_t k = 0; k < t.pinned.size(); ++k)
      coat::addPinnedFollicleNear(f, rest, t.tract, t.pinned[k], static_cast<uint32_t>(i), nextId - 1 - k);
    coat::RelaxOptions ro = t.relax;
    if (factor) {
      // Relaxation keeps the painted density (only its shape matters there).
      ro.density.uniform = 1.0;
      ro.density.multiplier = factor;
    }
    ro.progress = [&, i](const std::string&, double fr) {
      return report(progress, "distribute", (double(i) + fr) / double(tractSettings.size()));
    };
    relaxResults.push_back(f.size() > t.pinned.size() ? coat::relaxFollicles(rest, t.tract, f, ro)
                                                      : coat::RelaxResult{});
    follicles.append(f);
  }
  redistributeOverlaps(nextId);
  removeFollicles();
  report(progress, "distribute", 1);
}

// Each tract's "removed_follicles" leave the coat after relaxation and the overlap redistribution, so
// the follicles that stay keep their places bit for bit: deleting a feather leaves a gap. A follicle
// goes when its id is listed by the tract it belongs to.
void Pipeline::Impl::removeFollicles() {
  bool any = false;
  for (const TractSettings& t : tractSettings) any = any || !t.removed.empty();
  if (!any) return;
  coat::Follicles kept;
  kept.reserve(follicles.size());
  for (size_t k = 0; k < follicles.size(); ++k) {
    const std::vector<uint64_t>& gone = tractSettings[follicles.tract[k]].removed;
    if (std::binary_search(gone.begin(), gone.end(), follicles.id[k])) continue;
    kept.face.push_back(follicles.face[k]);
    kept.bary.push_back(follicles.bary[k]);
    kept.position.push_back(follicles.position[k]);
    kept.normal.push_back(follicles.normal[k]);
    kept.tract.push_back(follicles.tract[k]);
    kept.pinned.push_back(follicles.pinned[k]);
    kept.id.push_back(follicles.id[k]);
  }
  follicles = std::move(kept);
}

// Thesis 9.2.1: "if the tracts are the same feather type a more uniform distribution is typically desired.
// This can be accomplished by running the follicle distribution algorithm a second time, on only polygons
// of multiple tracts." Per overlap_group (in order of first appearance): the faces in two or more of its
// tracts lose the follicles scattered there (pinned ones stay) and get one distribution at the group's
// mean density, relaxed on those faces; each new follicle joins the group's tract whose remaining
// follicle is nearest (the tract it continues). Deterministic in the scene seed and the group's index.
void Pipeline::Impl::redistributeOverlaps(uint64_t& nextId) {
  std::vector<std::string> groups;
  for (const TractSettings& t : tractSettings)
    if (!t.overlapGroup.empty() && std::find(groups.begin(), groups.end(), t.overlapGroup) == groups.end())
      groups.push_back(t.overlapGroup);
  for (size_t g = 0; g < groups.size(); ++g) {
    std::vector<uint32_t> members;
    for (size_t i = 0; i < tractSettings.size(); ++i)
      if (tractSettings[i].overlapGroup == groups[g]) members.push_back(static_cast<uint32_t>(i));
    if (members.size() < 2) continue;
    std::vector<uint8_t> cover(rest.faceCount(), 0), isMember(tractSettings.size(), 0);
    double density = 0;
    for (uint32_t i : members) {
      isMember[i] = 1;
      const TractSettings& t = tractSettings[i];
      for (uint32_t f : t.tract.faces) cover[f] = static_cast<uint8_t>(std::min(cover[f] + 1, 2));
      density += t.density > 0 ? t.density : double(t.count) / std::max(t.area, 1e-300);
    }
    density /= double(members.size());
    coat::Tract shared;
    shared.name = groups[g] + " overlap";
    for (uint32_t f = 0; f < cover.size(); ++f)
      if (cover[f] >= 2) shared.faces.push_back(f);
    if (shared.faces.empty() || !(density > 0)) continue;
    // The group's follicles off the shared faces (and pinned ones) stay.
    coat::Follicles kept;
    kept.reserve(follicles.size());
    for (size_t k = 0; k < follicles.size(); ++k) {
      if (isMember[follicles.tract[k]] && cover[follicles.face[k]] >= 2 && !follicles.pinned[k]) continue;
      kept.push(rest, follicles.face[k], follicles.bary[k], follicles.tract[k], follicles.id[k], follicles.pinned[k]);
    }
    coat::ScatterOptions so;
    so.seed = mix64(scene.seed * 0x9E37u + 0x0E7A0000u + g);
    so.density.uniform = density;
    so.density.multiplier = densityFactorField(scene, rest);
    so.tractIndex = members[0];
    so.firstId = nextId;
    coat::Follicles fresh = coat::scatterFollicles(rest, shared, so);
    nextId += fresh.size() + 1;
    coat::RelaxOptions ro;
    if (so.density.multiplier) {
      ro.density.uniform = 1.0;
      ro.density.multiplier = so.density.multiplier;
    }
    if (fresh.size() > 1) coat::relaxFollicles(rest, shared, fresh, ro);
    // Each joins the member tract of the nearest remaining follicle (ties: the earlier tract).
    std::vector<glm::dvec3> sites;
    std::vector<uint32_t> siteTract;
    for (size_t k = 0; k < kept.size(); ++k)
      if (isMember[kept.tract[k]]) {
        sites.push_back(kept.position[k]);
        siteTract.push_back(kept.tract[k]);
      }
    for (size_t k = 0; k < fresh.size(); ++k) {
      uint32_t best = members[0];
      double bestD = std::numeric_limits<double>::infinity();
      for (size_t s = 0; s < sites.size(); ++s) {
        const double d = glm::dot(sites[s] - fresh.position[k], sites[s] - fresh.position[k]);
        if (d < bestD || (d == bestD && siteTract[s] < best)) {
          bestD = d;
          best = siteTract[s];
        }
      }
      fresh.tract[k] = best;
    }
    kept.append(fresh);
    follicles = std::move(kept);
  }
}

coat::TractParameterization Pipeline::Impl::boxParameterization(uint32_t tract) const {
  glm::dvec3 lo, hi;
  int ax[3];
  boxAxes(rest, lo, hi, ax);
  const glm::dvec3 ext = glm::max(hi - lo, glm::dvec3(1e-12));
  coat::TractParameterization p;
  p.method = coat::ParamMethod::Projection;
  p.note = "bounding-box projection (at most one key feather)";
  p.scale = ext[ax[0]];
  for (size_t f = 0; f < follicles.size(); ++f) {
    if (follicles.tract[f] != tract) continue;
    const glm::dvec3 q = (follicles.position[f] - lo) / ext;
    p.follicles.push_back(static_cast<uint32_t>(f));
    p.follicleUv.push_back({q[ax[0]], q[ax[1]]});
  }
  return p;
}

void Pipeline::Impl::computeInterpolate() {
  report(progress, "interpolate", 0);
  params.clear();
  std::vector<coat::TractKeys> keys;
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    TractSettings& t = tractSettings[i];
    try {
      params.push_back(
          coat::parameterizeTract(rest, t.tract, static_cast<uint32_t>(i), follicles, t.feathers.parameterization));
    } catch (const Error&) {
      // With at most one key feather nothing is interpolated, so a closed or folded tract needs no
      // real parameterization: (u,v) from the two longest axes of the mesh's bounding box.
      if (t.feathers.keys.size() > 1) throw;
      params.push_back(boxParameterization(static_cast<uint32_t>(i)));
    }
  }
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    TractSettings& t = tractSettings[i];
    coat::TractKeys k;
    k.param = &params[i];
    k.keys = coat::resolveKeyFeathers(follicles, params[i], t.feathers.keys, library, t.tract.name, t.feathers.feather,
                                      scene.file);
    k.scaleJitter = t.feathers.scaleJitter;
    keys.push_back(std::move(k));
  }
  coatRest = coat::CoatFeathers{};
  coat::InterpolateOptions io;
  io.seed = scene.seed;
  coat::interpolateCoatFeathers(follicles, keys, library, io, coatRest);
  restMaterials = coatMaterials(materialNames, library, coatRest);
  // Tract-level feather scale (explicit, or automatic from the follicle spacing).
  for (size_t i = 0; i < tractSettings.size(); ++i) {
    const TractSettings& t = tractSettings[i];
    double s = t.featherScale;
    if (t.autoScale && i < relaxResults.size() && relaxResults[i].spacing > 0) {
      double len = 0;
      size_t n = 0;
      for (size_t f = 0; f < coatRest.size(); ++f)
        if (coatRest.tract[f] == i) {
          len += coatRest.params[f].totalLength();
          ++n;
        }
      if (n && len > 0) s = t.featherSpacings * relaxResults[i].spacing / (len / double(n));
    }
    if (s != 1.0)
      for (size_t f = 0; f < coatRest.size(); ++f)
        if (coatRest.tract[f] == i) coat::scaleFeather(coatRest.params[f], s);
  }
  // Growth schedules: the tract's, else the feather file's, else the scene's (else the default).
  for (size_t f = 0; f < coatRest.size(); ++f) {
    const uint32_t t = coatRest.tract[f];
    if (t < tractSettings.size() && tractSettings[t].growth)
      coatRest.params[f].growth = tractSettings[t].growth;
    else if (!coatRest.params[f].growth)
      coatRest.params[f].growth = sceneGrowth;
  }
  // Memory of the coat's geometry before packing and meshing it, at the current level of detail; rendering
  // by screen size, at the least a render meshes (every feather at kMinScreenLodFraction of it): the mesh
  // stage checks again with the levels it is given.
  const bool bySize = scene.render.lodByScreenSize;
  requireCoatMemory(coatRest.params, nullptr, lod * (bySize ? kMinScreenLodFraction : 1.0), nullptr,
                    bySize ? "the coat's geometry at its least level by screen size" : "the coat's geometry",
                    scene.file);
  report(progress, "interpolate", 1);
}

void requireCoatMemory(const std::vector<feather::FeatherParams>& params, const std::vector<uint8_t>* present,
                       double lod, const std::vector<double>* featherLods, const std::string& what,
                       const std::string& file) {
  double triangles = 0;
  size_t largest = 0;
  double largestBarbs = 0;
  const bool perFeather = featherLods && featherLods->size() == params.size();
  for (size_t f = 0; f < params.size(); ++f) {
    if (present && f < present->size() && !(*present)[f]) continue;
    double barbs = 0;
    for (const feather::FeatherParams* p = &params[f]; p; p = p->afterfeather.get())
      barbs += 2.0 * p->rachisLength / std::max(std::min(p->spacingBase, p->spacingTip), 1e-300);
    if (barbs > largestBarbs) {
      largestBarbs = barbs;
      largest = f;
    }
    triangles += barbs * kTrianglesPerBarb * lod * (perFeather ? (*featherLods)[f] : 1.0);
  }
  if (params.empty()) return;
  const std::string name = params[largest].name;
  requireMemory(triangles * kBytesPerTriangle,
                what + " (about " + std::to_string(static_cast<uint64_t>(std::min(triangles, 1e18))) +
                    " triangles; up to " + std::to_string(static_cast<uint64_t>(std::min(largestBarbs, 1e18))) +
                    " barbs per feather)",
                file, name.empty() ? "feathers" : "feathers." + name);
}

// Directions and ordering are read here, not with the tracts, so editing them re-orients and
// repacks without re-relaxing follicles.
void Pipeline::Impl::computeDirections() {
  directionOptions = coat::DirectionOptions{};
  orderOptions = coat::OrderOptions{};
  if (scene.fromBareMesh) {
    // Any mesh with one command: feathers flow along the longest bounding-box axis and are layered
    // along it (roof tiles from the far end).
    glm::dvec3 lo, hi;
    int ax[3];
    boxAxes(rest, lo, hi, ax);
    glm::dvec3 a = 0.5 * (lo + hi), b = a;
    a[ax[0]] = lo[ax[0]];
    b[ax[0]] = hi[ax[0]];
    directionOptions.field.axis = {a, b};
    orderOptions.method = coat::OrderMethod::Axis;
    orderOptions.axis = {a, b};
  }
  if (const coat::DirectionOptions* d = settings.directions(scene)) directionOptions = *d;
  if (const coat::OrderOptions* o = settings.ordering(scene)) {
    orderOptions = *o;
  } else if (!scene.directions.empty() && directionOptions.field.axis.size() >= 2) {
    // A scene that gives a body axis and no ordering is layered along that axis (roof tiles from the tail).
    orderOptions.method = coat::OrderMethod::Axis;
    orderOptions.axis = directionOptions.field.axis;
  }
  directions = coat::computeSurfaceDirections(rest, tracts, follicles, directionOptions);
  coat::evaluateFrames(rest, follicles, directions, coatRest);
  try {
    coat::orderLayers(rest, tracts, params, follicles, directions, orderOptions, coatRest);
  } catch (const Error& e) {
    throw e.withFile(scene.file);  // "ordering.tracts[2]" is a key of the scene
  }
}

}  // namespace pteryla::pipeline
