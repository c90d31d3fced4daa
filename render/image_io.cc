#include "render/image_io.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace vlab::render {

namespace fs = std::filesystem;

namespace {

void EncodeAndWrite(const std::string& path, const ImageView& image) {
  std::vector<std::uint8_t> bytes;
  try {
    EncodePng(image, -1, &bytes);
  } catch (const ImageCodecError& e) {
    throw std::runtime_error("image '" + path + "': " + e.what());
  }
  WriteFileAtomic(path, bytes);
}

ImageView Gray16(const std::vector<std::uint16_t>& samples, int width, int height) {
  return {width, height, 1, 16, samples.data(), 0};
}

}  // namespace

std::uint16_t DepthToMillimetres(float metres) {
  if (!(metres > 0) || std::isinf(metres)) return 0;  // nothing drawn (or invalid)
  const double mm = std::round(static_cast<double>(metres) * 1000.0);
  return mm >= 65535.0 ? 65535 : static_cast<std::uint16_t>(mm);
}

ImageView View(const RgbImage& rgb) { return {rgb.width, rgb.height, 3, 8, rgb.pixels.data(), 0}; }

void ToMillimetres(const DepthImage& depth, std::vector<std::uint16_t>* mm) {
  mm->resize(static_cast<std::size_t>(depth.width) * depth.height);
  for (int y = 0; y < depth.height; ++y) {
    std::uint16_t* row = mm->data() + static_cast<std::size_t>(depth.width) * y;
    const float* src = depth.metres.data() + static_cast<std::size_t>(depth.width) * y;
    for (int x = 0; x < depth.width; ++x) row[x] = DepthToMillimetres(src[x]);
  }
}

void ToGeomIdPlusOne(const SegmentationImage& seg, std::vector<std::uint16_t>* ids) {
  ids->resize(static_cast<std::size_t>(seg.width) * seg.height);
  for (int y = 0; y < seg.height; ++y) {
    std::uint16_t* row = ids->data() + static_cast<std::size_t>(seg.width) * y;
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

void WritePng(const std::string& path, const RgbImage& rgb) { EncodeAndWrite(path, View(rgb)); }

void WriteDepthPng(const std::string& path, const DepthImage& depth) {
  std::vector<std::uint16_t> mm;
  ToMillimetres(depth, &mm);
  EncodeAndWrite(path, Gray16(mm, depth.width, depth.height));
}

void WriteSegmentationPng(const std::string& path, const SegmentationImage& seg) {
  std::vector<std::uint16_t> ids;
  ToGeomIdPlusOne(seg, &ids);
  EncodeAndWrite(path, Gray16(ids, seg.width, seg.height));
}

void EncodeJpeg(const RgbImage& rgb, int quality, std::vector<std::uint8_t>* jpeg) {
  EncodeJpeg(View(rgb), quality, jpeg);
}

}  // namespace vlab::render
