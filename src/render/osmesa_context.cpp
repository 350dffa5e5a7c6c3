// Headless OpenGL through Mesa's OSMesa (llvmpipe): the RenderContext used by the CLI and the tests.
#include "pteryla/render/osmesa_context.hpp"

#include <GL/osmesa.h>

#include <string>
#include <vector>

#include "pteryla/core/error.hpp"

namespace pteryla::render {

struct OsMesaContext::Impl {
  OSMesaContext ctx = nullptr;
  std::vector<unsigned char> buffer;
  int width = 0, height = 0;
  bool core = false;
};

namespace {
void checkSize(int w, int h) {
  if (w <= 0 || h <= 0 || w > 16384 || h > 16384)
    throw Error("OSMesa framebuffer size must be in [1, 16384], got " + std::to_string(w) + "x" + std::to_string(h));
}
}  // namespace

OsMesaContext::OsMesaContext(int width, int height) : impl_(std::make_unique<Impl>()) {
  checkSize(width, height);
  const int core[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 8,
                      OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                      OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
  impl_->ctx = OSMesaCreateContextAttribs(core, nullptr);
  impl_->core = impl_->ctx != nullptr;
  if (!impl_->ctx) {
    const int compat[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 8,
                          OSMESA_PROFILE, OSMESA_COMPAT_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                          OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    impl_->ctx = OSMesaCreateContextAttribs(compat, nullptr);
  }
  if (!impl_->ctx) throw Error("OSMesa could not create an OpenGL 3.3 context (is libosmesa6 installed?)");
  resize(width, height);
}

OsMesaContext::~OsMesaContext() {
  if (impl_ && impl_->ctx) OSMesaDestroyContext(impl_->ctx);
}

void OsMesaContext::makeCurrent() {
  if (!OSMesaMakeCurrent(impl_->ctx, impl_->buffer.data(), GL_UNSIGNED_BYTE, impl_->width, impl_->height))
    throw Error("OSMesaMakeCurrent failed");
  // Row 0 of the buffer is the bottom row, as glReadPixels reports it.
  OSMesaPixelStore(OSMESA_Y_UP, 1);
}

GlProc OsMesaContext::getProcAddress(const char* name) const {
  return reinterpret_cast<GlProc>(OSMesaGetProcAddress(name));
}

glm::ivec2 OsMesaContext::framebufferSize() const { return {impl_->width, impl_->height}; }

void OsMesaContext::resize(int width, int height) {
  checkSize(width, height);
  impl_->width = width;
  impl_->height = height;
  impl_->buffer.assign(static_cast<size_t>(width) * height * 4, 0);
  makeCurrent();
}

bool OsMesaContext::isCoreProfile() const { return impl_->core; }

std::string OsMesaContext::description() {
  makeCurrent();
  using GetStringFn = const unsigned char* (*)(unsigned int);
  auto getString = reinterpret_cast<GetStringFn>(getProcAddress("glGetString"));
  if (!getString) return "unknown";
  auto str = [&](unsigned int e) {
    const unsigned char* s = getString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_VERSION) + " / " + str(GL_RENDERER);
}

}  // namespace pteryla::render
