// MP4 video of rendered frames (OpenCV's FFmpeg back end, MPEG-4 Part 2,
// fourcc "mp4v"), readable by cv::VideoCapture, ffprobe and common players.
//
// The file is written under a temporary name in the same folder
// (.NAME.partial-PID.mp4) and renamed into place by Finish(); a VideoFile
// destroyed before Finish() removes what it wrote. Not thread-safe.
#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "render/renderer.h"

namespace vlab::render {

class VideoFile {
 public:
  /// Opens `path` (must end in .mp4; its folder must exist) for frames of
  /// width x height at `fps` frames per second. Throws InputError for a bad
  /// name or folder, std::runtime_error when OpenCV cannot open an MP4 writer.
  static std::unique_ptr<VideoFile> Create(const std::string& path, double fps, int width, int height);
  ~VideoFile();
  VideoFile(const VideoFile&) = delete;
  VideoFile& operator=(const VideoFile&) = delete;

  /// Appends one frame; throws std::invalid_argument when its size differs.
  void Add(const RgbImage& rgb);
  /// Closes the stream and renames the file into place. Throws
  /// std::runtime_error when that fails (the partial file is removed).
  void Finish();

  int frames() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  VideoFile() = default;
  std::string path_;
  std::string staging_;
  int width_ = 0;
  int height_ = 0;
  int frames_ = 0;
  bool finished_ = false;
  cv::VideoWriter writer_;
  cv::Mat bgr_;  // reused conversion buffer
};

}  // namespace vlab::render
