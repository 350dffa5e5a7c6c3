#include "pteryla/render/image_texture.hpp"

#include <string>

#include "gl_api.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::render {

struct ImageTexture::Impl {
  RenderContext& ctx;
  GlApi gl;
  GLuint id = 0;
  int width = 0, height = 0;
  explicit Impl(RenderContext& c) : ctx(c) {
    ctx.makeCurrent();
    gl.load(ctx);
  }
};

ImageTexture::ImageTexture(RenderContext& context) : impl_(std::make_unique<Impl>(context)) {}

ImageTexture::~ImageTexture() {
  if (impl_->id) {
    impl_->ctx.makeCurrent();
    impl_->gl.DeleteTextures(1, &impl_->id);
  }
}

void ImageTexture::upload(const Image& image) {
  if (image.empty()) return;
  if (image.rgba.size() != size_t(image.width) * size_t(image.height) * 4)
    throw Error("expected " + std::to_string(image.width) + "x" + std::to_string(image.height) + "x4 bytes, got " +
                    std::to_string(image.rgba.size()),
                "", "image");
  Impl& t = *impl_;
  t.ctx.makeCurrent();
  GlApi& gl = t.gl;
  while (gl.GetError() != GL_NO_ERROR) {
  }
  if (!t.id) gl.GenTextures(1, &t.id);
  gl.BindTexture(GL_TEXTURE_2D, t.id);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  if (t.width != image.width || t.height != image.height) {
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                  image.rgba.data());
  } else {
    gl.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  }
  gl.BindTexture(GL_TEXTURE_2D, 0);
  const GLenum err = gl.GetError();
  if (err != GL_NO_ERROR)
    throw Error("OpenGL refused a " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    " texture (error " + std::to_string(err) + ")",
                "", "image");
  t.width = image.width;
  t.height = image.height;
}

uint32_t ImageTexture::id() const { return impl_->id; }
int ImageTexture::width() const { return impl_->width; }
int ImageTexture::height() const { return impl_->height; }

Image ImageTexture::download() const {
  const Impl& t = *impl_;
  if (!t.id) return Image();
  t.ctx.makeCurrent();
  Image out(t.width, t.height);
  t.gl.BindTexture(GL_TEXTURE_2D, t.id);
  t.gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  t.gl.GetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, out.rgba.data());
  t.gl.BindTexture(GL_TEXTURE_2D, 0);
  return out;
}

}  // namespace pteryla::render
