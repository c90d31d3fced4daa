// Image files of rendered frames, written atomically (a temporary name in the
// same folder, then a rename): a reader never sees half a file.
//
// - RGB: 8-bit 3-channel PNG.
// - Depth: 16-bit single-channel PNG, millimetres along the optical axis
//   (rounded); 0 where nothing was drawn, 65535 at or beyond 65.535 m.
// - Segmentation: 16-bit single-channel PNG, geom id + 1; 0 where no geom was
//   drawn (ids above 65534 saturate at 65535).
//
// Errors: std::runtime_error naming the file when encoding or writing fails.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "render/renderer.h"

namespace vlab::render {

/// Depth value of one pixel as written to the 16-bit PNG, mm.
std::uint16_t DepthToMillimetres(float metres);

/// A BGR view for OpenCV (copies and swaps channels into *bgr, reusing its buffer).
void ToBgr(const RgbImage& rgb, cv::Mat* bgr);
/// 16-bit depth image in millimetres (see DepthToMillimetres), reusing *mm's buffer.
void ToMillimetres(const DepthImage& depth, cv::Mat* mm);
/// 16-bit segmentation image, geom id + 1, reusing *ids's buffer.
void ToGeomIdPlusOne(const SegmentationImage& seg, cv::Mat* ids);

/// Writes `bytes` to `path` through a temporary file in the same folder.
void WriteFileAtomic(const std::string& path, const std::vector<std::uint8_t>& bytes);

/// Encodes an image to PNG (RGB or 16-bit grey) and writes it atomically.
void WritePng(const std::string& path, const RgbImage& rgb);
void WriteDepthPng(const std::string& path, const DepthImage& depth);
void WriteSegmentationPng(const std::string& path, const SegmentationImage& seg);

/// JPEG bytes of an RGB image, quality 1-100 (cv::imencode), into *jpeg.
void EncodeJpeg(const RgbImage& rgb, int quality, std::vector<std::uint8_t>* jpeg);

}  // namespace vlab::render
