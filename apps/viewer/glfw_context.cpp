#include "glfw_context.hpp"

#include <GLFW/glfw3.h>

namespace pteryla::viewer {

void GlfwContext::makeCurrent() { glfwMakeContextCurrent(window_); }

render::GlProc GlfwContext::getProcAddress(const char* name) const {
  return reinterpret_cast<render::GlProc>(glfwGetProcAddress(name));
}

glm::ivec2 GlfwContext::framebufferSize() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return {w, h};
}

}  // namespace pteryla::viewer
