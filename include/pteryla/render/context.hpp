#pragma once
// RenderContext: the one seam between pteryla_render and whatever owns an OpenGL context (an OSMesa
// buffer for the CLI and tests, a GLFW window for the viewer, later an EGL surfaceless context).
// pteryla_render never links libGL: the Renderer loads every GL entry point it uses through
// getProcAddress() of the context it is given, so one binary never mixes libGL and libOSMesa.
//
// Contract for implementations:
//  - the context offers OpenGL 3.3 core (a compatibility context of version >= 3.3 also works);
//  - makeCurrent() binds it to the calling thread; all Renderer calls happen with it current;
//  - getProcAddress() returns the entry point for a GL function name, or nullptr;
//  - framebufferSize() is the size in pixels of framebuffer 0 (the window or the OSMesa buffer),
//    which Renderer::render() draws into and Renderer::readPixels() reads back.
// A GLFW implementation is three one-liners: glfwMakeContextCurrent(window),
// glfwGetProcAddress(name), glfwGetFramebufferSize(window, &w, &h).
#include <glm/vec2.hpp>

namespace pteryla::render {

using GlProc = void (*)();

class RenderContext {
 public:
  virtual ~RenderContext() = default;
  virtual void makeCurrent() = 0;
  virtual GlProc getProcAddress(const char* name) const = 0;
  virtual glm::ivec2 framebufferSize() const = 0;
};

}  // namespace pteryla::render
