#include "vision/vision_camera_feed.h"

#include <algorithm>

#include <nlohmann/json.hpp>

namespace vlab::vision {

namespace {

using nlohmann::json;

// the camera model of a camera device: its describe reply's intrinsics and
// distortion; InputError naming the camera when they are unusable
CameraModel CameraModelOf(const bridge::CameraClient& camera) {
  const bridge::CameraCalibration& c = camera.calibration();
  CameraModel m;
  m.width = c.width;
  m.height = c.height;
  m.fx = c.fx;
  m.fy = c.fy;
  m.cx = c.cx;
  m.cy = c.cy;
  if (std::any_of(c.distortion.begin(), c.distortion.end(), [](double v) { return v != 0.0; })) {
    m.distortion.assign(c.distortion.begin(), c.distortion.end());
  }
  CheckCameraModel(m, camera.Label());
  return m;
}

bridge::CameraClient Connect(const CameraSourceConfig& config) {
  bridge::CameraClientOptions options;
  options.timeout_s = config.connect_timeout_s;
  return bridge::CameraClient::Connect(config.camera_address, config.camera_port, options);
}

}  // namespace

CameraFeed::CameraFeed(const CameraSourceConfig& config)
    : camera_(Connect(config)), model_(CameraModelOf(camera_)), start_(std::chrono::steady_clock::now()) {}

double CameraFeed::Now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool CameraFeed::Receive(double wait_s, FrameCounters* counters) {
  const long skipped_before = camera_.frames_skipped();
  try {
    camera_.ReceiveLatest(wait_s, &frame_);
  } catch (const bridge::TimeoutError&) {
    return false;
  }
  counters->frames_skipped += camera_.frames_skipped() - skipped_before;
  if (frame_.width != model_.width || frame_.height != model_.height ||
      frame_.rgb.size() != static_cast<std::size_t>(frame_.width) * frame_.height * 3) {
    ++counters->wrong_size;
    return false;
  }
  return true;
}

void CameraFeed::CountProcessed(double t0_s, FrameCounters* counters) const {
  const double took = Now() - t0_s;
  ++counters->frames;
  counters->process_s_sum += took;
  counters->process_s_max = std::max(counters->process_s_max, took);
}

std::optional<Eigen::Isometry3d> CameraFeed::pose() const {
  if (!frame_.pose.valid) return std::nullopt;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = frame_.pose.q_WC.normalized().toRotationMatrix();
  X.translation() = frame_.pose.p_WC;
  return X;
}

json CameraDescribe(const CameraFeed& feed, const CameraSourceConfig& source) {
  const bridge::CameraClient& camera = feed.camera();
  const CameraModel& m = feed.model();
  const json& cd = camera.describe();
  return {
      {"name", camera.name()},
      {"address", source.camera_address},
      {"port", source.camera_port},
      {"server", cd.value("server", json())},
      {"width", m.width},
      {"height", m.height},
      {"fps", camera.fps()},
      // the camera's schedule, as its describe reply gives it (null when it does not): a
      // client that holds a lockstep clock for a frame's markers needs it (docs/tasks.md)
      {"exposure_s", cd.value("exposure_s", json())},
      {"latency_s", cd.value("latency_s", json())},
      {"intrinsics", {{"fx", m.fx}, {"fy", m.fy}, {"cx", m.cx}, {"cy", m.cy}, {"source", camera.calibration().source}}},
      {"distortion", camera.calibration().distortion},
      {"pose", cd.value("pose", json())}};
}

}  // namespace vlab::vision
