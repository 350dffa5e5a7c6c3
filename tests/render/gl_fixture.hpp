#pragma once
// Shared by the GL render tests: one OSMesa context per test binary (the renderer makes it current),
// and a synthetic coat on its skin uploaded to a renderer with a camera framing it.
#include <glm/vec3.hpp>

#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/renderer.hpp"
#include "pteryla/render/synthetic.hpp"

namespace pteryla::render::gltest {

inline OsMesaContext& context() {
  static OsMesaContext ctx(64, 64);
  return ctx;
}

// Uploads `coat` (skin and feathers) to `r` and returns a camera at `eye` framing the feathers.
inline Camera showCoat(Renderer& r, const SyntheticCoat& coat, glm::vec3 eye = {0.5f, 1.0f, 3.0f}) {
  r.setSkin(coat.skin);
  r.setCoat(coat.coat, coat.ranges);
  Camera cam;
  cam.eye = eye;
  glm::vec3 lo, hi;
  coat.coat.bounds(lo, hi);
  cam.frameBounds(lo, hi, 1.0f, 0.8f);
  return cam;
}

}  // namespace pteryla::render::gltest
