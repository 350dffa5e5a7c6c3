#include "pteryla/render/scene_view.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/data_dir.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/feather/params.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/render/material_blend.hpp"
#include "pteryla/render/pattern.hpp"
#include "pteryla/render/scratchboard.hpp"

namespace pteryla::render {
namespace {

glm::vec3 v3(const glm::dvec3& v) { return glm::vec3(v); }

std::string textureDir() { return dataDirectory() + "/textures"; }

}  // namespace

Camera sceneCamera(const pipeline::Scene& scene, const TriMesh& skin, const TriMesh& coat, int width, int height) {
  glm::vec3 lo(-1), hi(1);
  if (scene.camera.autoFrame) {
    glm::vec3 lo2, hi2;
    bool any = skin.bounds(lo, hi);
    if (coat.bounds(lo2, hi2)) {
      if (any) {
        lo = glm::min(lo, lo2);
        hi = glm::max(hi, hi2);
      } else {
        lo = lo2;
        hi = hi2;
        any = true;
      }
    }
    if (!any) {
      lo = glm::vec3(-1);
      hi = glm::vec3(1);
    }
  }
  return sceneCameraForBounds(scene, lo, hi, width, height);
}

Camera sceneCameraForBounds(const pipeline::Scene& scene, const glm::vec3& lo, const glm::vec3& hi, int width,
                            int height) {
  Camera c;
  c.fovYDegrees = static_cast<float>(scene.camera.fovDeg);
  c.up = v3(scene.camera.up);
  const float aspect = float(width) / float(std::max(height, 1));
  if (!scene.camera.autoFrame) {
    c.eye = v3(scene.camera.eye);
    c.target = v3(scene.camera.target);
    const float dist = glm::length(c.eye - c.target);
    c.zNear = std::max(1e-3f, dist * 0.01f);
    c.zFar = dist * 10.0f;
    return c;
  }
  glm::vec3 dir = glm::normalize(v3(scene.camera.viewDir));
  const glm::vec3 centre = 0.5f * (lo + hi);
  c.target = centre;
  c.eye = centre - dir;
  c.frameBounds(lo, hi, aspect, 0.8f);  // the box's bounding sphere is loose: frame a little tighter
  return c;
}

bool coatReachBounds(pipeline::Pipeline& p, glm::vec3& lo, glm::vec3& hi) {
  const TriMesh skin = p.skinTriMesh();
  bool any = skin.bounds(lo, hi);
  const coat::CoatFeathers& f = p.feathers();
  const std::vector<double>& elevation = p.elevations();
  const size_t n = std::min(f.size(), elevation.size());
  struct Box {
    glm::dvec3 lo{std::numeric_limits<double>::max()}, hi{-std::numeric_limits<double>::max()};
  };
  // Each present feather, placed as the mesher places it, from a coarse copy of its parameters: the same
  // shaft, key barbs, angles and barb lengths with kBarbsPerVane barbs per vane. Barb curves lie inside
  // their control polygons, so those points stand for the barbs between the sampled ones.
  constexpr double kBarbsPerVane = 12;
  const Box coat = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 64), Box{},
      [&](const tbb::blocked_range<size_t>& r, Box b) {
        feather::FeatherCurves curves;
        feather::GenerateOptions go;
        go.shaftSegments = 8;
        auto coarse = [&](const feather::FeatherParams& src) {
          feather::FeatherParams q = src;
          q.spacingBase = q.spacingTip = q.rachisLength / kBarbsPerVane;
          return q;
        };
        for (size_t i = r.begin(); i != r.end(); ++i) {
          if (!f.present[i]) continue;
          feather::FeatherParams q = coarse(f.params[i]);
          if (q.afterfeather) q.afterfeather = std::make_shared<const feather::FeatherParams>(coarse(*q.afterfeather));
          feather::generateBarbs(q, curves, go);
          const coat::FeatherFrame& fr = f.frames[i];
          const auto pl = feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, elevation[i]);
          auto add = [&](const glm::vec3& local) {
            const glm::dvec3 w = pl.origin + double(local.x) * pl.x + double(local.y) * pl.y + double(local.z) * pl.z;
            b.lo = glm::min(b.lo, w);
            b.hi = glm::max(b.hi, w);
          };
          for (const feather::ShaftCurve& sh : curves.shafts)
            for (const glm::vec3& x : sh.points) add(x);
          for (const glm::vec3& x : curves.cvs) add(x);
        }
        return b;
      },
      [](Box a, const Box& b) {
        a.lo = glm::min(a.lo, b.lo);
        a.hi = glm::max(a.hi, b.hi);
        return a;
      });
  if (coat.lo.x <= coat.hi.x) {
    if (any) {
      lo = glm::min(lo, glm::vec3(coat.lo));
      hi = glm::max(hi, glm::vec3(coat.hi));
    } else {
      lo = glm::vec3(coat.lo);
      hi = glm::vec3(coat.hi);
      any = true;
    }
  }
  return any;
}

std::vector<Light> sceneLights(const pipeline::Scene& scene) {
  std::vector<Light> out;
  if (scene.render.lightRig == "studio") {
    // Key, fill and rim around the camera's view: the key from the upper left of the camera (it casts
    // the shadows), a cool fill from the right at about a third, and a rim from behind and above that
    // outlines the silhouette.
    const pipeline::CameraSpec& c = scene.camera;
    glm::vec3 view = c.autoFrame ? v3(c.viewDir) : v3(c.target - c.eye);
    if (!(glm::length(view) > 0.0f)) view = glm::vec3(0, 0, -1);
    view = glm::normalize(view);
    glm::vec3 up = v3(c.up);
    glm::vec3 right = glm::cross(view, up);
    if (!(glm::length(right) > 1e-6f))
      right = glm::cross(view, std::abs(view.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    right = glm::normalize(right);
    up = glm::cross(right, view);
    out.push_back({glm::normalize(-0.6f * view + 0.8f * up - 0.5f * right), glm::vec3(1.0f, 0.96f, 0.90f)});
    out.push_back({glm::normalize(-0.7f * view + 0.8f * right - 0.1f * up), glm::vec3(0.30f, 0.32f, 0.36f)});
    out.push_back({glm::normalize(0.8f * view + 0.6f * up), glm::vec3(0.70f, 0.70f, 0.70f)});
    return out;
  }
  for (const auto& l : scene.lights) {
    Light x;
    x.direction = -v3(l.direction);  // scene: direction the light travels; renderer: toward the light
    x.color = v3(l.color) * static_cast<float>(l.intensity);
    out.push_back(x);
  }
  return out;
}

RenderSettings sceneSettings(const pipeline::Scene& scene, int width, int height) {
  RenderSettings s;
  s.width = width;
  s.height = height;
  s.background = glm::vec4(v3(scene.render.background), 1.0f);
  s.ambient = glm::vec3(static_cast<float>(scene.render.ambient));
  s.skinColor = v3(scene.render.skinColor);
  s.shadows = scene.render.shadows;
  s.shadowStrength = static_cast<float>(scene.render.shadowStrength);
  s.msaaSamples = scene.render.msaa;
  s.exposure = static_cast<float>(scene.render.exposure);
  s.filmic = scene.render.tone == "filmic";
  s.ground = scene.render.ground;
  s.groundNormal = glm::vec3(scene.camera.up);
  s.groundColor = v3(scene.render.groundColor);
  return s;
}

namespace {

// One feather definition's look.
FeatherMaterial definitionMaterial(const pipeline::Scene& scene, const pipeline::CoatMaterial& m) {
  static const std::map<std::string, PatternKind> kinds = {{"plain", PatternKind::Plain},
                                                           {"barred", PatternKind::Barred},
                                                           {"scalloped", PatternKind::Scalloped},
                                                           {"spotted", PatternKind::Spotted},
                                                           {"eyespot", PatternKind::Eyespot}};
  FeatherMaterial f;
  f.name = m.name;
  f.baseColor = m.baseColor;
  f.barbules.d = m.brdfD.value_or(scene.render.brdfD);
  f.barbules.h = m.brdfH.value_or(scene.render.brdfH);
  f.colorUv = m.uv == "barb" ? ColorUv::Barb : m.uv == "growth" ? ColorUv::Growth : ColorUv::Global;
  if (!m.texture.empty()) {
    f.colorTexture = m.texture;
    f.baseColor = glm::vec3(1.0f);
  } else if (!m.pattern.empty()) {
    const std::string file = textureDir() + "/" + m.pattern + ".png";
    if (fileExists(file)) {
      f.colorTexture = file;
    } else {
      PatternParams pp;
      auto it = kinds.find(m.pattern);
      pp.kind = it == kinds.end() ? PatternKind::Barred : it->second;
      pp.baseColor = m.baseColor;
      pp.markColor = m.baseColor * 0.35f;
      f.colorImage = generatePattern(pp);
      f.baseColor = glm::vec3(1.0f);
    }
  }
  if (!m.alphaTexture.empty()) {
    f.alphaTexture = m.alphaTexture;
  } else {
    BarbAlphaParams ap;
    if (pipeline::isDownName(m.name)) ap.fluff = 1.0f;
    f.alphaImage = generateBarbAlpha(ap);
  }
  return f;
}

}  // namespace

std::vector<FeatherMaterial> sceneMaterials(const pipeline::Scene& scene, const pipeline::CoatMesh& coat) {
  std::vector<FeatherMaterial> out;
  out.reserve(coat.materials.size());
  for (const auto& m : coat.materials)
    out.push_back(m.blend.empty() ? definitionMaterial(scene, m) : FeatherMaterial{});
  // Blends of key feathers' looks (issue #30 item 2): their parts are definitions' materials, made above.
  std::map<std::string, Image> files;
  const ImageLoader load = [&](const std::string& path) -> const Image& {
    auto it = files.find(path);
    if (it == files.end()) it = files.emplace(path, loadImage(path)).first;
    return it->second;
  };
  std::vector<FeatherMaterial> parts;
  std::vector<double> weights;
  for (size_t k = 0; k < coat.materials.size(); ++k) {
    const pipeline::CoatMaterial& m = coat.materials[k];
    if (m.blend.empty()) continue;
    parts.clear();
    weights.clear();
    for (const pipeline::MaterialWeight& w : m.blend) {
      if (w.material >= coat.materials.size() || !coat.materials[w.material].blend.empty())
        throw Error("material blend part " + std::to_string(w.material) + " is not a feather definition's material", {},
                    "materials[" + std::to_string(k) + "].blend");
      // A part's texture that cannot be read is named as the renderer names it (materials[i].colorTexture).
      const FeatherMaterial& part = out[w.material];
      for (const auto& [path, key] :
           {std::pair{&part.colorTexture, "colorTexture"}, {&part.alphaTexture, "alphaTexture"}}) {
        if (path->empty()) continue;
        try {
          load(*path);
        } catch (const Error& e) {
          throw Error(e.detail(), e.file().empty() ? *path : e.file(),
                      "materials[" + std::to_string(w.material) + "]." + key);
        }
      }
      parts.push_back(part);
      weights.push_back(w.weight);
    }
    try {
      out[k] = blendFeatherMaterials(parts, weights, m.name, load);
    } catch (const Error& e) {
      throw Error("cannot blend material '" + m.name + "': " + e.detail(), e.file(),
                  "materials[" + std::to_string(k) + "]" + (e.element().empty() ? "" : "." + e.element()));
    }
  }
  return out;
}

std::vector<FeatherDrawRange> drawRanges(const pipeline::CoatMesh& coat) {
  std::vector<FeatherDrawRange> out;
  out.reserve(coat.ranges.size());
  for (const auto& r : coat.ranges) {
    FeatherDrawRange d;
    d.firstIndex = r.firstIndex;
    d.indexCount = r.indexCount;
    d.material = r.material;
    d.origin = r.origin;
    d.axisX = r.axisX;
    d.axisY = r.axisY;
    for (int k = 0; k < 4; ++k) d.partCount[k] = r.partCount[k];
    out.push_back(d);
  }
  return out;
}

std::vector<double> screenSizeLods(pipeline::Pipeline& p, const Camera& camera, int width, int height,
                                   double pixelsPerBarb, double minFraction) {
  const coat::CoatFeathers& f = p.feathers();
  const std::vector<double>& elevation = p.elevations();
  std::vector<double> out(f.size(), 1.0);
  const double lo = std::clamp(minFraction, 1e-3, 1.0);
  for (size_t i = 0; i < f.size(); ++i) {
    if (!f.present[i] || i >= elevation.size()) continue;
    const feather::FeatherParams& params = f.params[i];
    const coat::FeatherFrame& fr = f.frames[i];
    const auto pl = feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, elevation[i]);
    const double half = 0.5 * params.rachisLength;
    const glm::vec3 centre(fr.origin + pl.x * half);
    const double px = screenSizeOfSphere(centre, static_cast<float>(half), camera, {width, height});
    const double spacing = 0.5 * (params.spacingBase + params.spacingTip);
    const double barbs = spacing > 0 ? params.rachisLength / spacing : 1.0;
    const double f1 = px / (std::max(pixelsPerBarb, 1e-6) * std::max(barbs, 1.0));
    out[i] = std::clamp(std::isfinite(f1) ? f1 : 1.0, lo, 1.0);
  }
  return out;
}

Image renderFeatherImage(RenderContext& context, const feather::FeatherParams& p, const TriMesh& mesh, int w, int h) {
  pipeline::CoatMesh coat;
  coat.mesh = mesh;
  pipeline::CoatMaterial m;
  m.name = p.name;
  m.pattern = p.material.pattern;
  if (!p.material.texture.empty()) m.texture = resolveRelative(p.sourceFile, p.material.texture);
  if (!p.material.alphaTexture.empty()) m.alphaTexture = resolveRelative(p.sourceFile, p.material.alphaTexture);
  if (p.material.baseColor) m.baseColor = glm::vec3(*p.material.baseColor);
  m.brdfD = p.material.brdfD;
  m.brdfH = p.material.brdfH;
  coat.materials.push_back(m);
  pipeline::Scene scene;
  scene.render.background = {0.92, 0.92, 0.9};
  scene.lights.push_back({{-0.3, -0.4, -1.0}, {1, 1, 1}, 1.0});
  Renderer r(context);
  r.setMaterials(sceneMaterials(scene, coat));
  r.setCoat(coat.mesh, {});
  glm::vec3 lo, hi;
  Camera cam;
  if (mesh.bounds(lo, hi)) {
    const glm::vec3 centre = 0.5f * (lo + hi);
    cam.up = glm::vec3(1, 0, 0);  // shaft (+x) up the image
    cam.target = centre;
    cam.eye = centre + glm::vec3(0, 0, 1);
    cam.frameBounds(lo, hi, float(w) / float(h), 1.05f);
  }
  RenderSettings s = sceneSettings(scene, w, h);
  s.drawSkin = false;
  return r.renderImage(cam, sceneLights(scene), s);
}

struct SceneView::Impl {
  explicit Impl(RenderContext& c) : renderer(c) {}
  Renderer renderer;
  // The arrays the renderer reads (it keeps no copy of the coat's positions and indices): set again
  // whenever the mesh stage ran or the arrays are others (another pipeline, or moved).
  const void* lastPositions = nullptr;
  const void* lastIndices = nullptr;
  size_t lastVertices = 0, lastIndexCount = 0;
  uint64_t lastSkinEval = ~0ull, lastMeshEval = ~0ull;
  bool materialsSet = false;
  std::vector<pipeline::CoatMaterial> lastMaterials;  // the coat's materials when last set
  TriMesh skin;

  void sync(pipeline::Pipeline& p) {
    const auto& coat = p.coatMesh();
    using pipeline::Stage;
    if (p.evaluations(Stage::Pose) != lastSkinEval) {
      skin = p.skinTriMesh();
      renderer.setSkin(skin);
      lastSkinEval = p.evaluations(Stage::Pose);
    }
    const TriMesh& m = coat.mesh;
    if (p.evaluations(Stage::Mesh) != lastMeshEval || m.positions.data() != lastPositions ||
        m.indices.data() != lastIndices || m.positions.size() != lastVertices || m.indices.size() != lastIndexCount) {
      // Materials follow the rest coat (blends of key feathers' looks), so re-set them when it changes.
      if (!materialsSet || coat.materials != lastMaterials) {
        renderer.setMaterials(sceneMaterials(p.scene(), coat));
        lastMaterials = coat.materials;
        materialsSet = true;
      }
      renderer.setCoat(m, drawRanges(coat), Renderer::CoatStorage::Reference);
      lastMeshEval = p.evaluations(Stage::Mesh);
      lastPositions = m.positions.data();
      lastIndices = m.indices.data();
      lastVertices = m.positions.size();
      lastIndexCount = m.indices.size();
    }
  }
};

SceneView::SceneView(RenderContext& context) : impl_(std::make_unique<Impl>(context)) {}
SceneView::~SceneView() = default;
Renderer& SceneView::renderer() { return impl_->renderer; }
void SceneView::markDirty() {
  impl_->lastSkinEval = impl_->lastMeshEval = ~0ull;
  impl_->materialsSet = false;
}

Image SceneView::render(pipeline::Pipeline& p, int width, int height, const std::string& styleIn) {
  const std::string style = styleIn.empty() ? p.scene().render.style : styleIn;
  if (style == "scratchboard") {
    // The CPU style draws the coat's mesh at the pipeline's levels (it sets none of its own).
    const auto& coat = p.coatMesh();
    const TriMesh skin = p.skinTriMesh();
    ScratchboardSettings s;
    s.width = width;
    s.height = height;
    return renderScratchboard(coat.mesh, skin, sceneCamera(p.scene(), skin, coat.mesh, width, height),
                              sceneLights(p.scene()), s);
  }
  // Screen-size LOD: an auto-framed camera frames the skin and the coat's reach (coatReachBounds: the
  // packed feathers, not their mesh), then each feather is meshed once, at its own level. The framing
  // depends on the pack alone, so a frame is the same whatever was meshed before it (`render --time T`
  // equals that frame of `frames`). At a fixed level the camera frames the coat's mesh, as it always did.
  const bool bySize = p.scene().render.lodByScreenSize;
  Camera cam;
  if (!bySize) {
    p.setFeatherLods({});
    cam = sceneCamera(p.scene(), p.skinTriMesh(), p.coatMesh().mesh, width, height);
  } else {
    glm::vec3 lo(-1), hi(1);
    if (p.scene().camera.autoFrame && !coatReachBounds(p, lo, hi)) lo = glm::vec3(-1), hi = glm::vec3(1);
    cam = sceneCameraForBounds(p.scene(), lo, hi, width, height);
    p.setFeatherLods(screenSizeLods(p, cam, width, height));
  }
  impl_->sync(p);
  return impl_->renderer.renderImage(cam, sceneLights(p.scene()), sceneSettings(p.scene(), width, height));
}

void SceneView::draw(pipeline::Pipeline& p, const Camera& camera, int width, int height) {
  impl_->sync(p);
  impl_->renderer.render(camera, sceneLights(p.scene()), sceneSettings(p.scene(), width, height));
}

}  // namespace pteryla::render
