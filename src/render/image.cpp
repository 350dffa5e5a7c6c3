// RGBA8 image I/O through OpenImageIO, and the image-difference utilities used by the level-of-detail
// comparison (thesis 7.1.3, Fig. 7.4: full vs reduced geometry) and coverage checks.
#include "pteryla/render/image.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/core/quiet.hpp"

namespace pteryla::render {

Image::Image(int w, int h, uint8_t r, uint8_t g, uint8_t b, uint8_t a) : width(w), height(h) {
  if (w < 0 || h < 0) throw Error("image size must be non-negative");
  rgba.resize(static_cast<size_t>(w) * h * 4);
  for (size_t i = 0; i < rgba.size(); i += 4) {
    rgba[i] = r;
    rgba[i + 1] = g;
    rgba[i + 2] = b;
    rgba[i + 3] = a;
  }
}

void saveImage(const std::string& path, const Image& image) {
  if (image.empty() || image.rgba.size() != static_cast<size_t>(image.width) * image.height * 4)
    throw Error("cannot save an empty or inconsistent image", path);
  const std::string ext = extensionOf(path);
  // The writer is chosen by the target's name; the bytes go to memory when the format supports it
  // (PNG, JPEG, TIFF, EXR do), so no library ever writes the file itself: libjpeg's default error
  // handler would exit() on a write error, and a full disk would leave a truncated file. The encoded
  // image is then written through AtomicFile (temporary file renamed on success).
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error("no image writer for this file type (" + OIIO::geterror() + ")", path);
  const bool jpeg = ext == ".jpg" || ext == ".jpeg";
  const bool exr = ext == ".exr";
  const int channels = jpeg ? 3 : 4;
  OIIO::ImageSpec spec(image.width, image.height, channels, exr ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
  if (jpeg) spec.attribute("CompressionQuality", 95);
  // Image holds straight (unassociated) alpha: keep colours under transparent pixels intact.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  const bool inMemory = out->supports("ioproxy") && out->set_ioproxy(&memory);
  AtomicFile file(path);
  if (!inMemory) file.releaseStream();
  if (!out->open(inMemory ? path : file.tempPath(), spec))
    throw Error("cannot open image for writing: " + out->geterror(), path);
  bool ok;
  if (jpeg) {
    std::vector<uint8_t> rgb(static_cast<size_t>(image.width) * image.height * 3);
    for (size_t i = 0, j = 0; i < image.rgba.size(); i += 4, j += 3) {
      rgb[j] = image.rgba[i];
      rgb[j + 1] = image.rgba[i + 1];
      rgb[j + 2] = image.rgba[i + 2];
    }
    ok = out->write_image(OIIO::TypeDesc::UINT8, rgb.data());
  } else {
    ok = out->write_image(OIIO::TypeDesc::UINT8, image.rgba.data());
  }
  if (!ok) {
    const std::string msg = out->geterror();
    out->close();
    throw Error("cannot write image: " + msg + " (any previous file is unchanged)", path);
  }
  if (!out->close())
    throw Error("cannot finish writing image: " + out->geterror() + " (any previous file is unchanged)", path);
  out.reset();
  if (inMemory) {
    if (encoded.empty()) throw Error("the image encoder produced no data", path);
    file.write(encoded.data(), encoded.size());
  }
  file.commit();
}

Image loadImage(const std::string& path) {
  if (!fileExists(path)) throw Error("image file not found", path);
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // straight alpha, as Image stores it
  const QuietThirdParty silence;  // libpng warnings ("iCCP: known incorrect sRGB profile") under --quiet
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) throw Error("cannot read image: " + OIIO::geterror(), path);
  const OIIO::ImageSpec& spec = in->spec();
  const int w = spec.width, h = spec.height, nc = spec.nchannels;
  if (w <= 0 || h <= 0 || nc <= 0) throw Error("image has no pixels", path);
  // The header's size is checked before a single pixel is decoded: a PNG may declare 65535x65535.
  // Decoded channels + the RGBA copy + the renderer's flipped upload copy and mipmaps. (Textures wider
  // than the GL limit are scaled down when uploaded.)
  requireMemory(double(w) * double(h) * (double(nc) + 4.0 + 4.0 + 6.0),
                "image " + std::to_string(w) + "x" + std::to_string(h), path, "");
  std::vector<uint8_t> raw(static_cast<size_t>(w) * h * nc);
  if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::UINT8, raw.data())) {
    const std::string msg = in->geterror();
    in->close();
    throw Error("cannot decode image: " + msg, path);
  }
  in->close();
  Image img(w, h);
  for (size_t p = 0; p < static_cast<size_t>(w) * h; ++p) {
    const uint8_t* s = raw.data() + p * nc;
    uint8_t* d = img.rgba.data() + p * 4;
    if (nc >= 3) {
      d[0] = s[0];
      d[1] = s[1];
      d[2] = s[2];
      d[3] = nc >= 4 ? s[3] : 255;
    } else {
      d[0] = d[1] = d[2] = s[0];
      d[3] = nc == 2 ? s[1] : 255;
    }
  }
  return img;
}

Image fitImage(const Image& image, int maxSide) {
  PTERYLA_CHECK(maxSide > 0, "fitImage needs a positive size");
  if (image.width <= maxSide && image.height <= maxSide) return image;
  const int w = std::min(image.width, maxSide), h = std::min(image.height, maxSide);
  Image out(w, h);
  // Box filter: each output pixel averages the source pixels it covers (in full or in part).
  const double sx = double(image.width) / w, sy = double(image.height) / h;
  for (int y = 0; y < h; ++y) {
    const int y0 = static_cast<int>(y * sy);
    const int y1 = std::max(y0 + 1, std::min(image.height, static_cast<int>(std::ceil((y + 1) * sy))));
    for (int x = 0; x < w; ++x) {
      const int x0 = static_cast<int>(x * sx);
      const int x1 = std::max(x0 + 1, std::min(image.width, static_cast<int>(std::ceil((x + 1) * sx))));
      uint32_t sum[4] = {0, 0, 0, 0};
      for (int yy = y0; yy < y1; ++yy)
        for (int xx = x0; xx < x1; ++xx)
          for (int c = 0; c < 4; ++c) sum[c] += image.pixel(xx, yy)[c];
      const uint32_t n = static_cast<uint32_t>((y1 - y0) * (x1 - x0));
      for (int c = 0; c < 4; ++c) out.pixel(x, y)[c] = static_cast<uint8_t>((sum[c] + n / 2) / n);
    }
  }
  return out;
}

double meanAbsoluteError(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw Error("images differ in size: " + std::to_string(a.width) + "x" + std::to_string(a.height) + " vs " +
                std::to_string(b.width) + "x" + std::to_string(b.height));
  if (a.empty()) return 0.0;
  uint64_t sum = 0;
  for (size_t i = 0; i < a.rgba.size(); i += 4)
    for (int c = 0; c < 3; ++c) sum += static_cast<uint64_t>(std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])));
  return static_cast<double>(sum) / (255.0 * 3.0 * static_cast<double>(a.width) * a.height);
}

double coveredFraction(const Image& image, const uint8_t background[3], int tolerance) {
  if (image.empty()) return 0.0;
  size_t covered = 0;
  for (size_t i = 0; i < image.rgba.size(); i += 4) {
    for (int c = 0; c < 3; ++c) {
      if (std::abs(int(image.rgba[i + c]) - int(background[c])) > tolerance) {
        ++covered;
        break;
      }
    }
  }
  return static_cast<double>(covered) / (static_cast<double>(image.width) * image.height);
}

}  // namespace pteryla::render
