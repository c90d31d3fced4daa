#include "vision/vision_program.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "core/core_errors.h"

namespace vlab::vision {

namespace {

using nlohmann::json;

// what the markers device's describe reply says about its camera and detector
json DescribeExtra(const bridge::CameraClient& camera, const CameraModel& m, const DetectorConfig& d,
                   const std::string& address, int port) {
  return {{"rates", {{"control_hz", camera.fps()}, {"frame_hz", camera.fps()}}},
          {"camera", CameraDescribe(camera, m, address, port)},
          {"detector",
           {{"method",
             "OpenCV aruco detectMarkers, CORNER_REFINE_APRILTAG, corners - 0.5 px, outline refined "
             "from the grey levels; solvePnP IPPE_SQUARE, both poses refined (Levenberg-Marquardt)"},
            {"refine_edges", d.refine_edges},
            {"max_reprojection_error_px", d.max_reprojection_error_px},
            {"min_ambiguity_ratio", d.min_ambiguity_ratio},
            {"min_alternative_error_px", d.min_alternative_error_px},
            {"max_ambiguous_rotation_deg", d.max_ambiguous_rotation_deg},
            {"max_view_angle_deg", d.max_view_angle_deg}}}};
}

long WholeNumber(const std::string& text, const std::string& what) {
  std::size_t used = 0;
  long value = -1;
  try {
    value = std::stol(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || value < 0) {
    throw vlab::InputError("--marker '" + what + "': '" + text + "' is not a marker id");
  }
  return value;
}

}  // namespace

json CameraDescribe(const bridge::CameraClient& camera, const CameraModel& m, const std::string& address, int port) {
  const json& cd = camera.describe();
  return {
      {"name", camera.name()},
      {"address", address},
      {"port", port},
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

bool ReceiveFrame(bridge::CameraClient& camera, double wait_s, const CameraModel& model,
                  bridge::CameraClient::Frame* frame, long* skipped, long* wrong_size) {
  const long skipped_before = camera.frames_skipped();
  try {
    camera.ReceiveLatest(wait_s, frame);
  } catch (const bridge::TimeoutError&) {
    return false;
  }
  *skipped += camera.frames_skipped() - skipped_before;
  if (frame->width != model.width || frame->height != model.height ||
      frame->rgb.size() != static_cast<std::size_t>(frame->width) * frame->height * 3) {
    ++*wrong_size;
    return false;
  }
  return true;
}

std::optional<Eigen::Isometry3d> CameraPoseOf(const bridge::CameraClient::Frame& frame) {
  if (!frame.pose.valid) return std::nullopt;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = frame.pose.q_WC.normalized().toRotationMatrix();
  X.translation() = frame.pose.p_WC;
  return X;
}

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

std::vector<bridge::MarkerDescriptionMsg> ParseMarkerOption(const std::string& text) {
  const std::size_t a = text.find(':'), b = text.rfind(':');
  if (a == std::string::npos || a == b) {
    throw vlab::InputError("--marker '" + text +
                           "': expected DICT:ID:SIDE or DICT:FIRST-LAST:SIDE, e.g. 4X4_50:0-35:0.03");
  }
  const bridge::MarkerDictionary* d = bridge::FindMarkerDictionary(text.substr(0, a));
  if (d == nullptr) throw vlab::InputError("--marker '" + text + "': unknown dictionary '" + text.substr(0, a) + "'");
  const std::string ids = text.substr(a + 1, b - a - 1);
  const std::size_t dash = ids.find('-');
  const long first = WholeNumber(ids.substr(0, dash), text);
  const long last = dash == std::string::npos ? first : WholeNumber(ids.substr(dash + 1), text);
  if (last < first || last >= d->markers) {
    throw vlab::InputError("--marker '" + text + "': ids must lie in 0.." + std::to_string(d->markers - 1) + " of " +
                           d->name + ", first <= last");
  }
  double side = 0;
  std::size_t used = 0;
  try {
    side = std::stod(text.substr(b + 1), &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() - b - 1 || !(side > 0 && side <= bridge::kMaxMarkerSide_m)) {
    throw vlab::InputError("--marker '" + text + "': the side must be a length in m, 0 < side <= 10");
  }
  std::vector<bridge::MarkerDescriptionMsg> out;
  for (long id = first; id <= last; ++id) out.push_back({d->code, static_cast<int>(id), side});
  return out;
}

std::unique_ptr<VisionProgram> VisionProgram::Create(const VisionConfig& config) {
  bridge::CameraClientOptions options;
  options.timeout_s = config.connect_timeout_s;
  bridge::CameraClient camera = bridge::CameraClient::Connect(config.camera_address, config.camera_port, options);
  return std::unique_ptr<VisionProgram>(new VisionProgram(std::move(camera), config));
}

VisionProgram::VisionProgram(bridge::CameraClient camera, const VisionConfig& config)
    : camera_(std::move(camera)), detector_(config.detector), start_(std::chrono::steady_clock::now()) {
  model_ = CameraModelOf(camera_);
  MarkersServerConfig server = config.server;
  server.describe_extra.update(
      DescribeExtra(camera_, model_, config.detector, config.camera_address, config.camera_port), true);
  server_ = MarkersServer::Create(server);
  if (!server_->Describe(config.markers)) {
    throw vlab::InputError("--marker: " + std::to_string(config.markers.size()) + " markers exceed the table's " +
                           std::to_string(server.max_markers));
  }
  state_.markers.reserve(bridge::kMaxMarkersPerState);
}

double VisionProgram::Now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool VisionProgram::Step(double wait_s) {
  server_->Poll(Now());
  if (!ReceiveFrame(camera_, wait_s, model_, &frame_, &counters_.frames_skipped, &counters_.wrong_size)) return false;
  const double t0 = Now();
  const cv::Mat rgb(frame_.height, frame_.width, CV_8UC3, frame_.rgb.data());
  cv::cvtColor(rgb, grey_, cv::COLOR_RGB2GRAY);
  const std::optional<Eigen::Isometry3d> X_world_camera = CameraPoseOf(frame_);
  server_->Poll(Now());  // descriptions that came meanwhile apply to this frame
  const LocateStats stats = LocateMarkers(grey_, model_, X_world_camera, server_->table(), detector_, &state_);
  server_->Publish(static_cast<double>(frame_.id), frame_.time_s, state_, Now());

  ++counters_.frames;
  counters_.reported += stats.reported;
  counters_.valid += stats.valid;
  counters_.unknown += state_.unknown;
  const double took = Now() - t0;
  counters_.process_s_sum += took;
  counters_.process_s_max = std::max(counters_.process_s_max, took);
  return true;
}

}  // namespace vlab::vision
