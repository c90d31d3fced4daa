#include "render/video.h"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "core/core_errors.h"
#include "render/image_io.h"

namespace vlab::render {

namespace fs = std::filesystem;

std::unique_ptr<VideoFile> VideoFile::Create(const std::string& path, double fps, int width, int height) {
  const fs::path target(path);
  const std::string name = target.filename().string();
  if (name.size() < 5 || target.extension() != ".mp4") {
    throw vlab::InputError("video '" + path + "': the file name must end in .mp4");
  }
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(folder)) throw vlab::InputError("video '" + path + "': no folder '" + folder.string() + "'");
  if (!(fps > 0) || width < 1 || height < 1) {
    throw std::invalid_argument("video '" + path + "': needs fps > 0 and a frame size");
  }
  std::unique_ptr<VideoFile> v(new VideoFile());
  v->path_ = path;
  // the container is chosen from the extension: keep .mp4 at the end of the temporary name
  v->staging_ = (folder / ("." + target.stem().string() + ".partial-" + std::to_string(::getpid()) + ".mp4")).string();
  v->width_ = width;
  v->height_ = height;
  const int fourcc = cv::VideoWriter::fourcc('m', 'p', '4', 'v');
  if (!v->writer_.open(v->staging_, cv::CAP_FFMPEG, fourcc, fps, cv::Size(width, height), true)) {
    std::error_code ec;
    fs::remove(v->staging_, ec);
    throw std::runtime_error("video '" + path +
                             "': OpenCV cannot open an MP4 (mp4v) writer (FFmpeg back end missing?)");
  }
  return v;
}

VideoFile::~VideoFile() {
  if (finished_) return;
  writer_.release();
  std::error_code ec;
  fs::remove(staging_, ec);
}

void VideoFile::Add(const RgbImage& rgb) {
  if (rgb.width != width_ || rgb.height != height_) {
    throw std::invalid_argument("video '" + path_ + "': frame " + std::to_string(rgb.width) + "x" +
                                std::to_string(rgb.height) + " in a " + std::to_string(width_) + "x" +
                                std::to_string(height_) + " video");
  }
  ToBgr(rgb, &bgr_);
  writer_.write(bgr_);
  ++frames_;
}

void VideoFile::Finish() {
  if (finished_) return;
  writer_.release();
  std::error_code ec;
  if (fs::file_size(staging_, ec) == 0 || ec) {
    fs::remove(staging_, ec);
    throw std::runtime_error("video '" + path_ + "': nothing was written");
  }
  fs::rename(staging_, path_, ec);
  if (ec) {
    fs::remove(staging_, ec);
    throw std::runtime_error("video '" + path_ + "': cannot rename into place: " + ec.message());
  }
  finished_ = true;
}

}  // namespace vlab::render
