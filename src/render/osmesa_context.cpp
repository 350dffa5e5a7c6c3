// Headless OpenGL through Mesa's OSMesa (llvmpipe): the RenderContext used by the CLI, the tests and the
// host API's Session::render.
//
// Two builds of this file (src/render/CMakeLists.txt):
//  - pteryla_render_osmesa (the CLI, tests, benchmarks) links libOSMesa and calls it directly: the
//    library is loaded at start-up with the program.
//  - pteryla_render_osmesa_dl (PTERYLA_OSMESA_DLOPEN; the host library libpteryla.so) loads libOSMesa
//    with dlopen on the first context and never unloads it, so the host library links no GL at all and
//    stays loadable next to a DCC's libGL (rendering from Blender's Python works), and a machine without
//    libosmesa6 gets an error naming the library instead of a host that cannot load pteryla.
// The executables keep the link: a libOSMesa loaded by dlopen puts Mesa's and LLVM's thread-locals in
// dynamic TLS, and LeakSanitizer's stop-the-world tracer (GCC 12) sometimes crashes reading those slots
// at exit ("Tracer caught signal 11"), which turned sanitized CLI tests into flakes.
// GL functions always come from OSMesaGetProcAddress.
#include "pteryla/render/osmesa_context.hpp"

#include <GL/osmesa.h>
#if defined(PTERYLA_OSMESA_DLOPEN)
#include <dlfcn.h>
#endif

#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

#include "pteryla/core/error.hpp"

namespace pteryla::render {

namespace {

struct OsMesaApi {
  decltype(&OSMesaCreateContextAttribs) createContextAttribs = nullptr;
  decltype(&OSMesaDestroyContext) destroyContext = nullptr;
  decltype(&OSMesaMakeCurrent) makeCurrent = nullptr;
  decltype(&OSMesaPixelStore) pixelStore = nullptr;
  decltype(&OSMesaGetProcAddress) getProcAddress = nullptr;
};

const OsMesaApi& osMesa() {
#if !defined(PTERYLA_OSMESA_DLOPEN)
  static const OsMesaApi linked{&OSMesaCreateContextAttribs, &OSMesaDestroyContext, &OSMesaMakeCurrent,
                                &OSMesaPixelStore, &OSMesaGetProcAddress};
  return linked;
#else
  static OsMesaApi api;
  static std::string failure;
  static std::once_flag once;
  std::call_once(once, [] {
    void* lib = nullptr;
    for (const char* name : {"libOSMesa.so.8", "libOSMesa.so"})
      if ((lib = dlopen(name, RTLD_NOW | RTLD_LOCAL))) break;
    if (!lib) {
      const char* why = dlerror();
      failure = std::string(
                    "cannot load Mesa's off-screen GL library libOSMesa.so.8 (install libosmesa6: "
                    "tools/bootstrap.sh): ") +
                (why ? why : "not found");
      return;
    }
    auto sym = [&](auto& fn, const char* name) {
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(lib, name));
      if (!fn && failure.empty()) failure = std::string("libOSMesa has no ") + name + " (Mesa too old?)";
    };
    sym(api.createContextAttribs, "OSMesaCreateContextAttribs");
    sym(api.destroyContext, "OSMesaDestroyContext");
    sym(api.makeCurrent, "OSMesaMakeCurrent");
    sym(api.pixelStore, "OSMesaPixelStore");
    sym(api.getProcAddress, "OSMesaGetProcAddress");
  });
  if (!failure.empty()) throw Error(failure);
  return api;
#endif
}

}  // namespace

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
  const OsMesaApi& gl = osMesa();
  const int core[] = {OSMESA_FORMAT,
                      OSMESA_RGBA,
                      OSMESA_DEPTH_BITS,
                      24,
                      OSMESA_STENCIL_BITS,
                      8,
                      OSMESA_PROFILE,
                      OSMESA_CORE_PROFILE,
                      OSMESA_CONTEXT_MAJOR_VERSION,
                      3,
                      OSMESA_CONTEXT_MINOR_VERSION,
                      3,
                      0};
  impl_->ctx = gl.createContextAttribs(core, nullptr);
  impl_->core = impl_->ctx != nullptr;
  if (!impl_->ctx) {
    const int compat[] = {OSMESA_FORMAT,
                          OSMESA_RGBA,
                          OSMESA_DEPTH_BITS,
                          24,
                          OSMESA_STENCIL_BITS,
                          8,
                          OSMESA_PROFILE,
                          OSMESA_COMPAT_PROFILE,
                          OSMESA_CONTEXT_MAJOR_VERSION,
                          3,
                          OSMESA_CONTEXT_MINOR_VERSION,
                          3,
                          0};
    impl_->ctx = gl.createContextAttribs(compat, nullptr);
  }
  if (!impl_->ctx) throw Error("OSMesa could not create an OpenGL 3.3 context (is libosmesa6 installed?)");
  resize(width, height);
}

OsMesaContext::~OsMesaContext() {
  if (impl_ && impl_->ctx) osMesa().destroyContext(impl_->ctx);
}

void OsMesaContext::makeCurrent() {
  const OsMesaApi& gl = osMesa();
  if (!gl.makeCurrent(impl_->ctx, impl_->buffer.data(), GL_UNSIGNED_BYTE, impl_->width, impl_->height))
    throw Error("OSMesaMakeCurrent failed");
  // Row 0 of the buffer is the bottom row, as glReadPixels reports it.
  gl.pixelStore(OSMESA_Y_UP, 1);
}

GlProc OsMesaContext::getProcAddress(const char* name) const {
  return reinterpret_cast<GlProc>(osMesa().getProcAddress(name));
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
