#pragma once
// RenderContext over a GLFW window (render/context.hpp): the renderer loads its GL entry points through
// glfwGetProcAddress, so the viewer links libGL (via GLFW) and never OSMesa.
#include "pteryla/render/context.hpp"

struct GLFWwindow;

namespace pteryla::viewer {

class GlfwContext : public render::RenderContext {
 public:
  explicit GlfwContext(GLFWwindow* window) : window_(window) {}
  void makeCurrent() override;
  render::GlProc getProcAddress(const char* name) const override;
  glm::ivec2 framebufferSize() const override;
  GLFWwindow* window() const { return window_; }

 private:
  GLFWwindow* window_;
};

}  // namespace pteryla::viewer
