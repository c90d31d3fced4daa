// The camera side that the vision programs share (vision_program.h,
// vision_yoyo_program.h): where the camera device is, the connection to it,
// the newest whole frame and what is counted of every frame.
//
// Ports
//   input   whole camera frames (bridge::CameraClient: RGB, exposure time, the
//           camera's pose in the world when known)
//   rate    the camera's: each Receive waits for the newest whole frame; frames
//           that arrive meanwhile are skipped (counted)
// Not thread-safe.
#pragma once

#include <chrono>
#include <optional>
#include <string>

#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>

#include "bridge/bridge_camera_client.h"
#include "vision/vision_detector.h"

namespace vlab::vision {

/// Where a vision program's camera device is.
struct CameraSourceConfig {
  std::string camera_address = "127.0.0.1";
  int camera_port = 50013;
  double connect_timeout_s = 10;  ///< wait this long for the camera's describe reply
};

/// What a vision program counts of the frames it receives and processes.
struct FrameCounters {
  long frames = 0;           ///< frames processed (states published)
  long frames_skipped = 0;   ///< whole frames passed over to take a newer one
  long wrong_size = 0;       ///< frames whose size differs from the camera's describe (not processed)
  double process_s_max = 0;  ///< longest processing of one frame (its program's work + publish), s
  double process_s_sum = 0;
};

/// A connected camera device, its camera model and the frame received last.
class CameraFeed {
 public:
  /// Connects to the camera of `config` and reads its camera model. Throws
  /// bridge::NetworkError, bridge::TimeoutError (no camera),
  /// bridge::ProtocolError, InputError (the camera's intrinsics).
  explicit CameraFeed(const CameraSourceConfig& config);

  /// Seconds since the feed connected (monotonic clock).
  double Now() const;
  /// Waits up to wait_s (s) for the newest whole frame of the camera model's
  /// size; counts skipped and wrong-size frames into *counters. False when none came.
  bool Receive(double wait_s, FrameCounters* counters);
  /// Counts one processed frame into *counters: its processing took from t0_s (a Now()) to now.
  void CountProcessed(double t0_s, FrameCounters* counters) const;

  /// The frame received last, as an RGB image over its bytes (valid until the next Receive).
  cv::Mat rgb() { return cv::Mat(frame_.height, frame_.width, CV_8UC3, frame_.rgb.data()); }
  /// The frame received last.
  const bridge::CameraClient::Frame& frame() const { return frame_; }
  /// The camera's pose in the world that came with the last frame (nullopt: unknown).
  std::optional<Eigen::Isometry3d> pose() const;

  /// The camera device's client (its describe reply, calibration, label).
  const bridge::CameraClient& camera() const { return camera_; }
  /// The camera model of its describe reply's intrinsics and distortion.
  const CameraModel& model() const { return model_; }

 private:
  bridge::CameraClient camera_;
  CameraModel model_;
  std::chrono::steady_clock::time_point start_;
  bridge::CameraClient::Frame frame_;  // reused
};

/// What a vision device's describe reply says of the camera it reads (its
/// "camera" entry): name, endpoint (of `source`), server, size, rate,
/// intrinsics, distortion, pose.
nlohmann::json CameraDescribe(const CameraFeed& feed, const CameraSourceConfig& source);

}  // namespace vlab::vision
