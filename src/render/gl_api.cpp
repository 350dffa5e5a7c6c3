#include "gl_api.hpp"

#include <string>

#include "pteryla/core/error.hpp"

namespace pteryla::render {

void GlApi::load(const RenderContext& context) {
#define PTERYLA_GL_LOAD(type, name)                                                            \
  name = reinterpret_cast<type>(context.getProcAddress("gl" #name));                           \
  if (!name)                                                                                   \
    throw Error(std::string("OpenGL entry point gl" #name " is unavailable: the context does " \
                            "not provide OpenGL 3.3"));
  PTERYLA_GL_FUNCTIONS(PTERYLA_GL_LOAD)
#undef PTERYLA_GL_LOAD
}

}  // namespace pteryla::render
