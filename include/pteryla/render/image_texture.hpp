#pragma once
// An Image as a 2D RGBA8 texture in a RenderContext, for a UI to show (the viewer's view and its
// scratchboard preview go to Dear ImGui as texture ids). GL stays inside pteryla_render: the texture is
// made, filled and deleted through the context's loader, in that context.
#include <cstdint>
#include <memory>

#include "pteryla/render/context.hpp"
#include "pteryla/render/image.hpp"

namespace pteryla::render {

class ImageTexture {
 public:
  explicit ImageTexture(RenderContext& context);
  ~ImageTexture();  // deletes the texture in its own context
  ImageTexture(const ImageTexture&) = delete;
  ImageTexture& operator=(const ImageTexture&) = delete;

  // Copies `image` into the texture (bilinear filtering), reallocating it when the size changed. An
  // empty image leaves the texture as it was. Throws pteryla::Error when the GL cannot take it.
  void upload(const Image& image);
  // The GL texture name (0 until the first upload) and the size of what was uploaded.
  uint32_t id() const;
  int width() const;
  int height() const;
  // The texture's pixels read back (tests).
  Image download() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pteryla::render
