#include "render/image_codec.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace vlab::render {

namespace codec_detail {

std::size_t CheckedStride(const ImageView& image, const char* what) {
  if (image.width < 1 || image.height < 1 || !image.pixels) {
    throw ImageCodecError(std::string(what) + ": an empty image (" + std::to_string(image.width) + "x" +
                          std::to_string(image.height) + ")");
  }
  if (image.channels != 1 && image.channels != 3 && image.channels != 4) {
    throw ImageCodecError(std::string(what) + ": " + std::to_string(image.channels) + " channels (1, 3 or 4 expected)");
  }
  if (image.depth != 8 && image.depth != 16) {
    throw ImageCodecError(std::string(what) + ": " + std::to_string(image.depth) + " bits per sample (8 or 16)");
  }
  const std::size_t packed = static_cast<std::size_t>(image.width) * image.channels * (image.depth / 8);
  if (image.stride != 0 && image.stride < packed) {
    throw ImageCodecError(std::string(what) + ": a row stride of " + std::to_string(image.stride) +
                          " bytes is shorter than a row (" + std::to_string(packed) + ")");
  }
  return image.stride ? image.stride : packed;
}

void Allocate(int width, int height, int channels, int depth, const char* what, Image* out) {
  const unsigned long long pixels = static_cast<unsigned long long>(width) * static_cast<unsigned long long>(height);
  if (width < 1 || height < 1 || pixels > (1ull << 30)) {
    throw ImageCodecError(std::string(what) + ": unsupported image size " + std::to_string(width) + "x" +
                          std::to_string(height));
  }
  out->width = width;
  out->height = height;
  out->channels = channels;
  out->depth = depth;
  out->bytes.resize(static_cast<std::size_t>(pixels) * channels * (depth / 8));
}

}  // namespace codec_detail

bool LooksLikePng(const std::uint8_t* bytes, std::size_t size) {
  static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return size >= 8 && std::memcmp(bytes, kSignature, 8) == 0;
}

bool LooksLikeJpeg(const std::uint8_t* bytes, std::size_t size) {
  return size >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8 && bytes[2] == 0xff;
}

void DecodeImage(const std::uint8_t* bytes, std::size_t size, DecodeMode mode, Image* out) {
  if (LooksLikePng(bytes, size)) return codec_detail::DecodePng(bytes, size, mode, out);
  if (LooksLikeJpeg(bytes, size)) return codec_detail::DecodeJpeg(bytes, size, mode, out);
  throw ImageCodecError(size == 0 ? "no image data (0 bytes)"
                                  : "neither PNG nor JPEG data (" + std::to_string(size) + " bytes)");
}

Image DecodeImage(const std::vector<std::uint8_t>& bytes, DecodeMode mode) {
  Image image;
  DecodeImage(bytes.data(), bytes.size(), mode, &image);
  return image;
}

Image ReadImageFile(const std::string& path, DecodeMode mode) {
  // the whole file, then the in-memory decoder
  std::FILE* f = std::fopen(path.c_str(), "rbe");
  if (!f) throw ImageCodecError("image '" + path + "': cannot open: " + std::strerror(errno));
  std::vector<std::uint8_t> bytes;
  std::uint8_t chunk[65536];
  std::size_t n = 0;
  while ((n = std::fread(chunk, 1, sizeof(chunk), f)) > 0) bytes.insert(bytes.end(), chunk, chunk + n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw ImageCodecError("image '" + path + "': read error");
  try {
    return DecodeImage(bytes, mode);
  } catch (const ImageCodecError& e) {
    throw ImageCodecError("image '" + path + "': " + e.what());
  }
}

}  // namespace vlab::render
