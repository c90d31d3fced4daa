#include "bridge/bridge_camera_source.h"

#include <sys/stat.h>

#include <cmath>
#include <cstring>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

namespace vlab::bridge {

struct VideoSource::Impl {
  cv::VideoCapture capture;
  cv::Mat bgr;                // as read
  cv::Mat scaled;             // resized to the delivered size
  bool first_pending = true;  // Open read the first frame; Read returns it first
};

VideoSource::VideoSource() : impl_(new Impl) {}
VideoSource::~VideoSource() = default;

namespace {

bool IsDevicePath(const std::string& s) { return s.rfind("/dev/video", 0) == 0; }

// a video file: FFmpeg when this OpenCV has it (no GStreamer chatter), else any backend
int FileBackend() { return cv::videoio_registry::hasBackend(cv::CAP_FFMPEG) ? cv::CAP_FFMPEG : cv::CAP_ANY; }

}  // namespace

std::unique_ptr<VideoSource> VideoSource::Open(const std::string& source, const VideoSourceOptions& options) {
  // OpenCV reports failed opens on stderr itself; the caller's one line says it all
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  const std::string label = "video source '" + source + "'";
  struct stat st {};
  if (source.empty() || ::stat(source.c_str(), &st) != 0) {
    throw VideoSourceError(label + ": no such file or device");
  }
  std::unique_ptr<VideoSource> v(new VideoSource());
  v->source_ = source;
  v->device_ = IsDevicePath(source) && S_ISCHR(st.st_mode);
  if (!v->device_ && !S_ISREG(st.st_mode)) throw VideoSourceError(label + ": neither a video file nor a V4L2 device");
  cv::VideoCapture& cap = v->impl_->capture;
  bool opened = false;
  try {
    opened = v->device_ ? cap.open(source, cv::CAP_V4L2) : cap.open(source, FileBackend());
  } catch (const cv::Exception& e) {
    throw VideoSourceError(label + ": cannot be opened: " + e.what());
  }
  if (!opened || !cap.isOpened()) {
    throw VideoSourceError(label + (v->device_ ? ": cannot open the V4L2 device (busy, or not a capture device?)"
                                               : ": not a video file OpenCV can read"));
  }
  if (v->device_) {
    if (options.width > 0) cap.set(cv::CAP_PROP_FRAME_WIDTH, options.width);
    if (options.height > 0) cap.set(cv::CAP_PROP_FRAME_HEIGHT, options.height);
    if (options.fps > 0) cap.set(cv::CAP_PROP_FPS, options.fps);
  }
  bool read = false;
  try {
    read = cap.read(v->impl_->bgr);
  } catch (const cv::Exception&) {
    read = false;
  }
  if (!read || v->impl_->bgr.empty() || v->impl_->bgr.type() != CV_8UC3) {
    throw VideoSourceError(label + ": opened, but no colour frame could be read from it");
  }
  v->backend_ = cap.getBackendName();
  const double fps = cap.get(cv::CAP_PROP_FPS);
  v->fps_ = std::isfinite(fps) && fps > 0 && fps <= 1000 ? fps : 0;
  const double frames = cap.get(cv::CAP_PROP_FRAME_COUNT);
  v->frame_count_ = !v->device_ && std::isfinite(frames) && frames > 0 ? static_cast<long>(frames) : 0;
  v->width_ = options.width > 0 ? options.width : v->impl_->bgr.cols;
  v->height_ = options.height > 0 ? options.height : v->impl_->bgr.rows;
  return v;
}

bool VideoSource::Read(std::uint8_t* rgb) {
  Impl& m = *impl_;
  if (!m.first_pending) {
    try {
      if (!m.capture.read(m.bgr) || m.bgr.empty() || m.bgr.type() != CV_8UC3) return false;
    } catch (const cv::Exception&) {
      return false;
    }
  }
  m.first_pending = false;
  cv::Mat out(height_, width_, CV_8UC3, rgb);
  if (m.bgr.cols == width_ && m.bgr.rows == height_) {
    cv::cvtColor(m.bgr, out, cv::COLOR_BGR2RGB);
  } else {
    cv::resize(m.bgr, m.scaled, cv::Size(width_, height_), 0, 0, cv::INTER_AREA);
    cv::cvtColor(m.scaled, out, cv::COLOR_BGR2RGB);
  }
  return true;
}

bool VideoSource::Rewind() {
  if (device_) return false;
  try {
    return impl_->capture.set(cv::CAP_PROP_POS_FRAMES, 0);
  } catch (const cv::Exception&) {
    return false;
  }
}

}  // namespace vlab::bridge
