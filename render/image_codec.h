// PNG and JPEG in memory (libpng, libjpeg): the one place vlab turns pixels
// into image bytes and back. The settings are those OpenCV's imgcodecs used
// before (so images and streams keep their bytes and pixels):
//
// - PNG, compression -1: zlib level 1, the SUB filter, the RLE strategy
//   (imencode's default); 0-9: that zlib level, libpng's default filters and
//   strategy (imencode with IMWRITE_PNG_COMPRESSION).
// - JPEG: baseline, 4:2:0 chroma subsampling, Huffman tables not optimised,
//   JFIF header, libjpeg's quality scaling (imencode with IMWRITE_JPEG_QUALITY).
// - Decoding: libpng's and libjpeg's transforms in OpenCV's order (16 to 8 bits
//   by dropping the low byte, alpha stripped for colour and grey, grey from
//   colour as 0.299 R + 0.587 G + 0.114 B for PNG, libjpeg's own for JPEG).
//   Unlike OpenCV, colour is RGB (not BGR), EXIF orientation is not applied,
//   and a truncated file is an error instead of a partly grey image.
//
// Threading: every function is reentrant (no shared state).
// Errors: ImageCodecError with a message saying what is wrong; never a crash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vlab::render {

/// Image bytes could not be encoded or decoded (bad, truncated or unsupported
/// data, a bad image description); the message says why.
class ImageCodecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Pixels in memory, not owned: rows top-down, channels interleaved (1 grey,
/// 3 RGB, 4 RGBA), `depth` 8 or 16 bits per sample (16: native-endian
/// std::uint16_t).
struct ImageView {
  int width = 0;   ///< pixels
  int height = 0;  ///< pixels
  int channels = 3;
  int depth = 8;
  const void* pixels = nullptr;
  std::size_t stride = 0;  ///< bytes from one row to the next; 0: rows packed
};

/// A decoded image owning its pixels: packed rows, layout as in ImageView.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  int depth = 8;
  std::vector<std::uint8_t> bytes;  ///< height rows of width * channels * depth / 8 bytes

  /// A view of the pixels (valid while this image lives and is not resized).
  ImageView view() const { return {width, height, channels, depth, bytes.data(), 0}; }
  /// The samples of a 16-bit image (depth == 16), row after row.
  const std::uint16_t* samples16() const { return reinterpret_cast<const std::uint16_t*>(bytes.data()); }
};

/// What a decoder delivers, whatever the file holds.
enum class DecodeMode {
  kColor,      ///< 8-bit RGB (imread's IMREAD_COLOR, but RGB)
  kGray,       ///< 8-bit grey (IMREAD_GRAYSCALE)
  kUnchanged,  ///< as stored: 1, 3 or 4 channels (PNG alpha or tRNS: 4), 8 or 16 bits (IMREAD_UNCHANGED)
};

/// PNG of an image of 1, 3 or 4 channels of 8 or 16 bits into *png (replaced).
/// `compression`: -1 for the fast default, else a zlib level 0-9 (see above).
/// Throws ImageCodecError for a bad view or a libpng failure.
void EncodePng(const ImageView& image, int compression, std::vector<std::uint8_t>* png);

/// Baseline JPEG of an 8-bit grey or RGB image into *jpeg (replaced);
/// `quality` 1-100 (clamped). Throws ImageCodecError for a bad view or a
/// libjpeg failure.
void EncodeJpeg(const ImageView& image, int quality, std::vector<std::uint8_t>* jpeg);

/// True when `bytes` start like a PNG or a JPEG file.
bool LooksLikePng(const std::uint8_t* bytes, std::size_t size);
bool LooksLikeJpeg(const std::uint8_t* bytes, std::size_t size);

/// Decodes PNG or JPEG bytes (told apart by their signature) into *out,
/// reusing its buffer. Throws ImageCodecError for anything else, for
/// truncated or corrupt data and for CMYK JPEG.
void DecodeImage(const std::uint8_t* bytes, std::size_t size, DecodeMode mode, Image* out);
/// The same, returning the image.
Image DecodeImage(const std::vector<std::uint8_t>& bytes, DecodeMode mode);

/// Reads and decodes a PNG or JPEG file; ImageCodecError names the file when
/// it cannot be read or decoded.
Image ReadImageFile(const std::string& path, DecodeMode mode);

namespace codec_detail {
// the format-specific halves (image_png.cc, image_jpeg.cc)
void DecodePng(const std::uint8_t* bytes, std::size_t size, DecodeMode mode, Image* out);
void DecodeJpeg(const std::uint8_t* bytes, std::size_t size, DecodeMode mode, Image* out);
// bytes per row of a view, checking its fields; throws ImageCodecError naming `what`
std::size_t CheckedStride(const ImageView& image, const char* what);
// sizes *out for width x height x channels x depth, refusing images above 2^30 pixels
void Allocate(int width, int height, int channels, int depth, const char* what, Image* out);
}  // namespace codec_detail

}  // namespace vlab::render
