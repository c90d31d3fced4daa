// Frames of a real camera for `vlab camera`: OpenCV's VideoCapture on a V4L2
// device (/dev/videoN) or on a video file (any container and codec OpenCV's
// FFmpeg backend reads), delivered as RGB8 images of one fixed size.
//
// Threading: one thread. Open throws; Read never throws.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

namespace vlab::bridge {

/// The source cannot be opened or gives no frame; the message names it.
class VideoSourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct VideoSourceOptions {
  int width = 0;  ///< device: size to ask for (0: its default); frames of another size are scaled to it
  int height = 0;
  double fps = 0;  ///< device: rate to ask for (0: its default)
};

class VideoSource {
 public:
  /// Opens `source` ("/dev/videoN" for a V4L2 device, else a video file) and
  /// reads its first frame. Throws VideoSourceError naming the source when it
  /// does not exist, cannot be opened, or gives no frame.
  static std::unique_ptr<VideoSource> Open(const std::string& source, const VideoSourceOptions& options = {});
  ~VideoSource();

  bool is_device() const { return device_; }
  /// Size of the images Read delivers (options' size, else the source's), pixels.
  int width() const { return width_; }
  int height() const { return height_; }
  /// The source's own frame rate (device: as reported; file: its container's), Hz; 0 if unknown.
  double fps() const { return fps_; }
  /// Frames in a file (0 for a device or when unknown).
  long frame_count() const { return frame_count_; }
  /// OpenCV's name of the backend in use ("V4L2", "FFMPEG", ...).
  const std::string& backend() const { return backend_; }
  const std::string& source() const { return source_; }

  /// The next frame as RGB8 (rows top-down, width() x height()) into `rgb`
  /// (3 * width * height bytes). False at the end of a file or when a device
  /// stops delivering.
  bool Read(std::uint8_t* rgb);
  /// Back to the first frame of a file; false for a device or when the file cannot seek.
  bool Rewind();

 private:
  struct Impl;
  VideoSource();
  std::unique_ptr<Impl> impl_;
  std::string source_;
  std::string backend_;
  bool device_ = false;
  int width_ = 0, height_ = 0;
  double fps_ = 0;
  long frame_count_ = 0;
};

}  // namespace vlab::bridge
