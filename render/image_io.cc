#include "render/image_io.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace vlab::render {

namespace fs = std::filesystem;

namespace {

// a read-only view of the caller's RGB pixels (no copy)
cv::Mat View(const RgbImage& rgb) {
  return cv::Mat(rgb.height, rgb.width, CV_8UC3, const_cast<std::uint8_t*>(rgb.pixels.data()));
}

void EncodeAndWrite(const std::string& path, const cv::Mat& image) {
  std::vector<std::uint8_t> bytes;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, bytes);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("image '" + path + "': PNG encoding failed: " + e.what());
  }
  if (!ok) throw std::runtime_error("image '" + path + "': PNG encoding failed");
  WriteFileAtomic(path, bytes);
}

}  // namespace

std::uint16_t DepthToMillimetres(float metres) {
  if (!(metres > 0) || std::isinf(metres)) return 0;  // nothing drawn (or invalid)
  const double mm = std::round(static_cast<double>(metres) * 1000.0);
  return mm >= 65535.0 ? 65535 : static_cast<std::uint16_t>(mm);
}

void ToBgr(const RgbImage& rgb, cv::Mat* bgr) { cv::cvtColor(View(rgb), *bgr, cv::COLOR_RGB2BGR); }

void ToMillimetres(const DepthImage& depth, cv::Mat* mm) {
  mm->create(depth.height, depth.width, CV_16UC1);
  for (int y = 0; y < depth.height; ++y) {
    std::uint16_t* row = mm->ptr<std::uint16_t>(y);
    const float* src = depth.metres.data() + static_cast<std::size_t>(depth.width) * y;
    for (int x = 0; x < depth.width; ++x) row[x] = DepthToMillimetres(src[x]);
  }
}

void ToGeomIdPlusOne(const SegmentationImage& seg, cv::Mat* ids) {
  ids->create(seg.height, seg.width, CV_16UC1);
  for (int y = 0; y < seg.height; ++y) {
    std::uint16_t* row = ids->ptr<std::uint16_t>(y);
    const std::int32_t* src = seg.geom.data() + static_cast<std::size_t>(seg.width) * y;
    for (int x = 0; x < seg.width; ++x) {
      const std::int32_t id = src[x] < 0 ? 0 : src[x] + 1;
      row[x] = static_cast<std::uint16_t>(id > 65535 ? 65535 : id);
    }
  }
}

void WriteFileAtomic(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  const fs::path target(path);
  const fs::path temp =
      target.parent_path() / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(temp.c_str(), "wbe");  // e: close-on-exec
  if (!f) throw std::runtime_error("file '" + path + "': cannot write (folder missing or not writable)");
  errno = 0;
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  int error = written ? 0 : errno;
  const bool closed = std::fclose(f) == 0;
  if (!closed && error == 0) error = errno;
  std::error_code ec;
  if (!written || !closed) {
    fs::remove(temp, ec);
    throw std::runtime_error("file '" + path + "': write failed: " + std::strerror(error ? error : EIO));
  }
  fs::rename(temp, target, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw std::runtime_error("file '" + path + "': cannot rename into place: " + ec.message());
  }
}

void WritePng(const std::string& path, const RgbImage& rgb) {
  cv::Mat bgr;
  ToBgr(rgb, &bgr);
  EncodeAndWrite(path, bgr);
}

void WriteDepthPng(const std::string& path, const DepthImage& depth) {
  cv::Mat mm;
  ToMillimetres(depth, &mm);
  EncodeAndWrite(path, mm);
}

void WriteSegmentationPng(const std::string& path, const SegmentationImage& seg) {
  cv::Mat ids;
  ToGeomIdPlusOne(seg, &ids);
  EncodeAndWrite(path, ids);
}

void EncodeJpeg(const RgbImage& rgb, int quality, std::vector<std::uint8_t>* jpeg) {
  // imencode takes BGR; a thread-local scratch image keeps repeated calls allocation-free
  thread_local cv::Mat bgr;
  ToBgr(rgb, &bgr);
  if (!cv::imencode(".jpg", bgr, *jpeg, {cv::IMWRITE_JPEG_QUALITY, quality})) {
    throw std::runtime_error("JPEG encoding failed");
  }
}

}  // namespace vlab::render
