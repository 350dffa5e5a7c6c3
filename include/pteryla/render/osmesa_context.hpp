#pragma once
// Headless RenderContext on Mesa's off-screen interface (llvmpipe). Lives in its own library,
// pteryla_render_osmesa, which links libOSMesa; never link it into a binary that also links libGL
// (the viewer uses a GLFW context instead). Mesa 22.3 (Debian 12) still ships OSMesa; newer Mesa
// dropped it, where an EGL surfaceless context would implement the same interface.
#include <memory>
#include <string>

#include "pteryla/render/context.hpp"

namespace pteryla::render {

class OsMesaContext final : public RenderContext {
 public:
  // Creates an RGBA8 context with a 24-bit depth buffer, asking for OpenGL 3.3 core and falling
  // back to a compatibility context. Throws pteryla::Error when no usable context can be made.
  OsMesaContext(int width, int height);
  ~OsMesaContext() override;
  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;

  void makeCurrent() override;
  GlProc getProcAddress(const char* name) const override;
  glm::ivec2 framebufferSize() const override;

  // Reallocates the colour buffer (framebuffer 0) and makes the context current.
  void resize(int width, int height);
  // True when the context is a core profile (false: compatibility fallback).
  bool isCoreProfile() const;
  // "OpenGL <version> / <renderer>", e.g. "4.5 (Core Profile) Mesa 22.3.6 / llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string description();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pteryla::render
