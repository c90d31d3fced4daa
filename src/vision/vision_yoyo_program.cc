#include "vision/vision_yoyo_program.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>

#include "vision/vision_program.h"

namespace vlab::vision {

namespace {

using nlohmann::json;

// what the yoyo device's describe reply says about its camera and tracker
json DescribeExtra(const bridge::CameraClient& camera, const CameraModel& m, const YoyoVisionConfig& config) {
  const BlobConfig& b = config.blob;
  return {{"camera", CameraDescribe(camera, m, config.camera_address, config.camera_port)},
          {"tracker",
           {{"method",
             "colour blob: HSV threshold, largest outer contour filled (holes ignored), its centroid's ray "
             "intersected with the vertical plane through the line that faces the camera; vz from consecutive "
             "seen frames' z and exposure times"},
            {"color", b.color},
            {"hsv", {{"hue_lo", b.hue_lo}, {"hue_hi", b.hue_hi}, {"s_min", b.s_min}, {"v_min", b.v_min}}},
            {"min_area_px", b.min_area_px},
            {"max_area_fraction", b.max_area_fraction},
            {"line", {{"x", config.line.x}, {"y", config.line.y}}}}}};
}

}  // namespace

std::unique_ptr<YoyoVisionProgram> YoyoVisionProgram::Create(const YoyoVisionConfig& config) {
  bridge::CameraClientOptions options;
  options.timeout_s = config.connect_timeout_s;
  bridge::CameraClient camera = bridge::CameraClient::Connect(config.camera_address, config.camera_port, options);
  return std::unique_ptr<YoyoVisionProgram>(new YoyoVisionProgram(std::move(camera), config));
}

YoyoVisionProgram::YoyoVisionProgram(bridge::CameraClient camera, const YoyoVisionConfig& config)
    : camera_(std::move(camera)), tracker_(config.blob, config.line), start_(std::chrono::steady_clock::now()) {
  model_ = CameraModelOf(camera_);
  YoyoServerConfig server = config.server;
  server.frame_hz = camera_.fps();
  server.describe_extra.update(DescribeExtra(camera_, model_, config), true);
  server_ = YoyoServer::Create(server);
}

double YoyoVisionProgram::Now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool YoyoVisionProgram::Step(double wait_s) {
  server_->Poll(Now());
  if (!ReceiveFrame(camera_, wait_s, model_, &frame_, &counters_.frames_skipped, &counters_.wrong_size)) return false;
  const double t0 = Now();
  const cv::Mat rgb(frame_.height, frame_.width, CV_8UC3, frame_.rgb.data());
  const std::optional<Eigen::Isometry3d> X_world_camera = CameraPoseOf(frame_);
  const double* state = tracker_.Track(rgb, model_, X_world_camera, frame_.time_s);
  server_->Poll(Now());  // subscribers that came meanwhile get this frame
  server_->Publish(static_cast<double>(frame_.id), frame_.time_s, state);

  ++counters_.frames;
  if (tracker_.seen()) {
    ++counters_.seen;
  } else if (!tracker_.blob().found) {
    ++counters_.no_blob;
  } else {
    ++counters_.no_pose;
  }
  const double took = Now() - t0;
  counters_.process_s_sum += took;
  counters_.process_s_max = std::max(counters_.process_s_max, took);
  return true;
}

}  // namespace vlab::vision
