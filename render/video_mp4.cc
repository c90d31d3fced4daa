// The MP4 writer behind render/video.h (library vlab_render_video): OpenCV's
// VideoWriter with its FFmpeg back end, fourcc "mp4v". Linking this unit
// installs it as VideoFile's factory before main() runs.
#include <filesystem>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "render/video.h"

namespace vlab::render {

namespace {

namespace fs = std::filesystem;

class Mp4VideoFile : public VideoFile {
 public:
  Mp4VideoFile(const std::string& path, const std::string& staging, int width, int height)
      : VideoFile(path, width, height), staging_(staging) {}

  ~Mp4VideoFile() override {
    if (finished_) return;
    writer_.release();
    std::error_code ec;
    fs::remove(staging_, ec);
  }

  bool Open(double fps) {
    const int fourcc = cv::VideoWriter::fourcc('m', 'p', '4', 'v');
    return writer_.open(staging_, cv::CAP_FFMPEG, fourcc, fps, cv::Size(width_, height_), true);
  }

  void Add(const RgbImage& rgb) override {
    CheckSize(rgb);
    const cv::Mat view(rgb.height, rgb.width, CV_8UC3, const_cast<std::uint8_t*>(rgb.pixels.data()));
    cv::cvtColor(view, bgr_, cv::COLOR_RGB2BGR);  // VideoWriter takes BGR
    writer_.write(bgr_);
    ++frames_;
  }

  void Finish() override {
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

 private:
  std::string staging_;
  bool finished_ = false;
  cv::VideoWriter writer_;
  cv::Mat bgr_;  // reused conversion buffer
};

std::unique_ptr<VideoFile> CreateMp4(const std::string& path, const std::string& staging, double fps, int width,
                                     int height) {
  auto v = std::make_unique<Mp4VideoFile>(path, staging, width, height);
  if (!v->Open(fps)) {
    v.reset();  // removes the staging file
    throw std::runtime_error("video '" + path +
                             "': OpenCV cannot open an MP4 (mp4v) writer (FFmpeg back end missing?)");
  }
  return v;
}

// installs the writer when the program starts
[[maybe_unused]] const bool g_installed = (VideoFile::SetFactory(CreateMp4), true);

}  // namespace

}  // namespace vlab::render
