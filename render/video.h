// MP4 video of rendered frames. This header and video.cc (vlab_render) hold
// the interface and the checks of a video's name; the writer itself
// (render/video_mp4.cc: OpenCV's FFmpeg back end, MPEG-4 Part 2, fourcc
// "mp4v", readable by cv::VideoCapture, ffprobe and common players) is the
// library vlab_render_video, which only the programs that write videos link
// (it needs OpenCV's videoio and its hundred-odd shared libraries). Linking it
// installs its writer before main() runs; a program without it refuses a video
// with a clear error.
//
// The file is written under a temporary name in the same folder
// (.NAME.partial-PID.mp4) and renamed into place by Finish(); a VideoFile
// destroyed before Finish() removes what it wrote. Not thread-safe.
#pragma once

#include <memory>
#include <string>

#include "render/renderer.h"

namespace vlab::render {

class VideoFile {
 public:
  /// What makes the writer: called by Create with a checked path, the staging
  /// file to write, fps > 0 and a size of at least 1x1. Throws
  /// std::runtime_error when no writer can be opened.
  using Factory = std::unique_ptr<VideoFile> (*)(const std::string& path, const std::string& staging, double fps,
                                                 int width, int height);
  /// Installs the writer Create uses (vlab_render_video does, at start-up);
  /// call before any Create, from one thread.
  static void SetFactory(Factory factory);

  /// Opens `path` (must end in .mp4; its folder must exist) for frames of
  /// width x height at `fps` frames per second. Throws InputError for a bad
  /// name or folder, std::invalid_argument for a bad rate or size,
  /// std::runtime_error when this program has no video writer (it does not
  /// link vlab_render_video) or the writer cannot be opened.
  static std::unique_ptr<VideoFile> Create(const std::string& path, double fps, int width, int height);
  virtual ~VideoFile() = default;
  VideoFile(const VideoFile&) = delete;
  VideoFile& operator=(const VideoFile&) = delete;

  /// Appends one frame; throws std::invalid_argument when its size differs.
  virtual void Add(const RgbImage& rgb) = 0;
  /// Closes the stream and renames the file into place. Throws
  /// std::runtime_error when that fails (the partial file is removed).
  virtual void Finish() = 0;

  /// Frames added so far.
  int frames() const { return frames_; }
  /// The file's final name, as given to Create.
  const std::string& path() const { return path_; }

 protected:
  VideoFile(const std::string& path, int width, int height) : path_(path), width_(width), height_(height) {}
  /// Throws std::invalid_argument (naming the file) unless rgb is width x height.
  void CheckSize(const RgbImage& rgb) const;

  std::string path_;
  int width_ = 0;
  int height_ = 0;
  int frames_ = 0;
};

}  // namespace vlab::render
