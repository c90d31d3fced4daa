// Image files of rendered frames, written atomically (a temporary name in the
// same folder, then a rename): a reader never sees half a file.
//
// - RGB: 8-bit 3-channel PNG.
// - Depth: 16-bit single-channel PNG, millimetres along the optical axis
//   (rounded); 0 where nothing was drawn, 65535 at or beyond 65.535 m.
// - Segmentation: 16-bit single-channel PNG, geom id + 1; 0 where no geom was
//   drawn (ids above 65534 saturate at 65535).
//
// Encoding: image_codec.h (libpng; its fast default, as OpenCV's imencode).
// Errors: std::runtime_error naming the file when encoding or writing fails.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/image_codec.h"
#include "render/renderer.h"

namespace vlab::render {

/// Depth value of one pixel as written to the 16-bit PNG, mm.
std::uint16_t DepthToMillimetres(float metres);

/// A codec view of an RGB image's pixels (not copied; valid while rgb lives).
ImageView View(const RgbImage& rgb);
/// 16-bit depth image in millimetres (see DepthToMillimetres), row after row,
/// reusing *mm's buffer.
void ToMillimetres(const DepthImage& depth, std::vector<std::uint16_t>* mm);
/// 16-bit segmentation image, geom id + 1, row after row, reusing *ids's buffer.
void ToGeomIdPlusOne(const SegmentationImage& seg, std::vector<std::uint16_t>* ids);

/// Writes `bytes` to `path` through a temporary file in the same folder.
void WriteFileAtomic(const std::string& path, const std::vector<std::uint8_t>& bytes);

/// Encodes an image to PNG (RGB or 16-bit grey) and writes it atomically.
void WritePng(const std::string& path, const RgbImage& rgb);
void WriteDepthPng(const std::string& path, const DepthImage& depth);
void WriteSegmentationPng(const std::string& path, const SegmentationImage& seg);

/// JPEG bytes of an RGB image, quality 1-100 (image_codec.h's settings), into
/// *jpeg. Throws ImageCodecError for an empty image.
void EncodeJpeg(const RgbImage& rgb, int quality, std::vector<std::uint8_t>* jpeg);

}  // namespace vlab::render
