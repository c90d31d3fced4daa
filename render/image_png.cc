// PNG half of image_codec.h on libpng. libpng reports errors by longjmp: every
// setjmp below sits in a function whose frame holds only plain data, and the
// C++ objects (buffers, the guard that frees libpng's structs) live in the
// caller, which a longjmp never crosses.
#include <png.h>
#include <zlib.h>

#include <cstdio>
#include <cstring>

#include "render/image_codec.h"

namespace vlab::render {

namespace {

// libpng's error text, kept for the exception
struct PngError {
  char message[160];
};

void OnError(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(error->message, sizeof(error->message), "%s", message ? message : "libpng error");
  png_longjmp(png, 1);
}

void OnWarning(png_structp, png_const_charp) {}  // warnings are not errors (as in OpenCV)

bool LittleEndian() {
  const std::uint16_t one = 1;
  return *reinterpret_cast<const std::uint8_t*>(&one) == 1;
}

// ---- encoding

void WriteToVector(png_structp png, png_bytep data, png_size_t size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    out->insert(out->end(), data, data + size);
  } catch (...) {
    ok = false;
  }
  if (!ok) png_error(png, "out of memory");
}

void FlushNothing(png_structp) {}

bool WriteRows(png_structp png, png_infop info, const ImageView* image, int compression, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  if (compression >= 0) {
    png_set_compression_level(png, compression);
  } else {
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_compression_level(png, Z_BEST_SPEED);
  }
  png_set_compression_strategy(png, compression >= 0 ? Z_DEFAULT_STRATEGY : Z_RLE);
  const int type = image->channels == 1   ? PNG_COLOR_TYPE_GRAY
                   : image->channels == 3 ? PNG_COLOR_TYPE_RGB
                                          : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(png, info, image->width, image->height, image->depth, type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (image->depth == 16 && LittleEndian()) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

struct WriteGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~WriteGuard() { png_destroy_write_struct(&png, info ? &info : nullptr); }
};

// ---- decoding

struct Source {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t pos;
};

void ReadFromMemory(png_structp png, png_bytep out, png_size_t size) {
  auto* source = static_cast<Source*>(png_get_io_ptr(png));
  if (size > source->size - source->pos) png_error(png, "the data ends early (truncated)");
  std::memcpy(out, source->data + source->pos, size);
  source->pos += size;
}

struct Header {
  png_uint_32 width;
  png_uint_32 height;
  int bit_depth;
  int color_type;
  int num_trans;
};

bool ReadHeader(png_structp png, png_infop info, Header* h) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  png_get_IHDR(png, info, &h->width, &h->height, &h->bit_depth, &h->color_type, nullptr, nullptr, nullptr);
  h->num_trans = 0;
  if (h->color_type == PNG_COLOR_TYPE_RGB || h->color_type == PNG_COLOR_TYPE_PALETTE) {
    png_bytep trans = nullptr;
    png_color_16p values = nullptr;
    png_get_tRNS(png, info, &trans, &h->num_trans, &values);
  }
  return true;
}

// libpng's transforms in the order OpenCV's PngDecoder::readData sets them
// (RGB where OpenCV asks for BGR)
bool ReadRows(png_structp png, png_infop info, png_infop end, const Header* h, int channels, int depth,
              png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  const bool color = channels > 1;
  if (depth == 8 && h->bit_depth == 16) {
    png_set_strip_16(png);
  } else if (LittleEndian()) {
    png_set_swap(png);
  }
  if (channels < 4) {
    png_set_strip_alpha(png);
  } else {
    png_set_tRNS_to_alpha(png);
  }
  if (h->color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if ((h->color_type & PNG_COLOR_MASK_COLOR) == 0 && h->bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if ((h->color_type & PNG_COLOR_MASK_COLOR) == 0 && color) {
    png_set_gray_to_rgb(png);
  } else if (!color) {
    png_set_rgb_to_gray(png, 1, 0.299, 0.587);
  }
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) != static_cast<png_size_t>(h->width) * channels * (depth / 8)) {
    png_error(png, "unsupported pixel layout");
  }
  png_read_image(png, rows);
  png_read_end(png, end);
  return true;
}

struct ReadGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  png_infop end = nullptr;
  ~ReadGuard() { png_destroy_read_struct(&png, info ? &info : nullptr, end ? &end : nullptr); }
};

}  // namespace

void EncodePng(const ImageView& image, int compression, std::vector<std::uint8_t>* png) {
  const std::size_t stride = codec_detail::CheckedStride(image, "PNG encoding");
  if (compression > 9) compression = 9;
  std::vector<png_bytep> rows(image.height);
  for (int y = 0; y < image.height; ++y) {
    rows[y] = const_cast<png_bytep>(static_cast<const std::uint8_t*>(image.pixels) + stride * y);
  }
  PngError error{};
  WriteGuard g;
  g.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, OnError, OnWarning);
  if (g.png) g.info = png_create_info_struct(g.png);
  if (!g.png || !g.info) throw ImageCodecError("PNG encoding: libpng could not start (out of memory)");
  png->clear();
  png_set_write_fn(g.png, png, WriteToVector, FlushNothing);
  if (!WriteRows(g.png, g.info, &image, compression, rows.data())) {
    png->clear();
    throw ImageCodecError(std::string("PNG encoding failed: ") + error.message);
  }
}

namespace codec_detail {

void DecodePng(const std::uint8_t* bytes, std::size_t size, DecodeMode mode, Image* out) {
  PngError error{};
  Source source{bytes, size, 0};
  ReadGuard g;
  g.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, OnError, OnWarning);
  if (g.png) g.info = png_create_info_struct(g.png);
  if (g.info) g.end = png_create_info_struct(g.png);
  if (!g.png || !g.info || !g.end) throw ImageCodecError("PNG: libpng could not start (out of memory)");
  png_set_read_fn(g.png, &source, ReadFromMemory);
  Header h{};
  if (!ReadHeader(g.png, g.info, &h)) throw ImageCodecError(std::string("PNG: bad header: ") + error.message);

  // the output layout: OpenCV's type for the mode
  int channels = 1;
  if (h.color_type == PNG_COLOR_TYPE_RGB || h.color_type == PNG_COLOR_TYPE_PALETTE) {
    channels = h.num_trans > 0 ? 4 : 3;
  } else if (h.color_type == PNG_COLOR_TYPE_GRAY_ALPHA || h.color_type == PNG_COLOR_TYPE_RGB_ALPHA) {
    channels = 4;
  }
  int depth = h.bit_depth == 16 ? 16 : 8;
  if (mode != DecodeMode::kUnchanged) {
    channels = mode == DecodeMode::kColor ? 3 : 1;
    depth = 8;
  }
  if (h.width > 0x7fffffffu || h.height > 0x7fffffffu) throw ImageCodecError("PNG: unsupported image size");
  Allocate(static_cast<int>(h.width), static_cast<int>(h.height), channels, depth, "PNG", out);
  std::vector<png_bytep> rows(h.height);
  const std::size_t stride = static_cast<std::size_t>(h.width) * channels * (depth / 8);
  for (png_uint_32 y = 0; y < h.height; ++y) rows[y] = out->bytes.data() + stride * y;
  if (!ReadRows(g.png, g.info, g.end, &h, channels, depth, rows.data())) {
    throw ImageCodecError(std::string("PNG: bad image data: ") + error.message);
  }
}

}  // namespace codec_detail

}  // namespace vlab::render
