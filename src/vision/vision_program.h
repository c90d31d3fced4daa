// The vision program (`vlab vision`): the role ARToolKit played in the
// original lab. It subscribes to a camera device (the lab's simulated webcam
// or `vlab camera` on a real one: the same bytes), finds the described markers
// in every frame and serves their poses as a markers device.
//
// Ports
//   input   whole camera frames (bridge::CameraClient: RGB, exposure time,
//           the camera's pose in the world when known); marker descriptions
//           and describe requests on the markers socket
//   output  one markers state per camera frame (seq = frame id, time =
//           exposure time), to every subscriber of the markers device
//   rate    the camera's: each Step waits for the newest whole frame; frames
//           that arrive while one is processed are skipped (counted)
// Latency: detection and pose take 5-10 ms per 640 x 480 frame on one core.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_markers.h"
#include "vision/vision_detector.h"
#include "vision/vision_locate.h"
#include "vision/vision_server.h"

namespace vlab::vision {

struct VisionConfig {
  std::string camera_address = "127.0.0.1";
  int camera_port = 50013;
  double connect_timeout_s = 10;  ///< wait this long for the camera's describe reply
  MarkersServerConfig server;     ///< the markers device (name, bind address, port)
  DetectorConfig detector;
  std::vector<bridge::MarkerDescriptionMsg> markers;  ///< the table at start (--marker)
};

struct VisionCounters {
  long frames = 0;           ///< frames processed (states published)
  long frames_skipped = 0;   ///< whole frames passed over to take a newer one
  long wrong_size = 0;       ///< frames whose size differs from the camera's describe (not processed)
  long reported = 0;         ///< markers reported, over all frames
  long valid = 0;            ///< of those, valid
  long unknown = 0;          ///< detections of markers not in the table
  double process_s_max = 0;  ///< longest detection + pose + publish, s
  double process_s_sum = 0;
};

class VisionProgram {
 public:
  /// Connects to the camera and binds the markers device. Throws
  /// InputError (bad --marker table), bridge::NetworkError,
  /// bridge::TimeoutError (no camera), bridge::ProtocolError.
  static std::unique_ptr<VisionProgram> Create(const VisionConfig& config);

  /// Serves the markers socket, waits up to wait_s (s) for a camera frame
  /// and, when one came, locates the markers and publishes the state.
  /// Returns true when a frame was processed.
  bool Step(double wait_s);

  const bridge::CameraClient& camera() const { return camera_; }
  const MarkersServer& server() const { return *server_; }
  const CameraModel& camera_model() const { return model_; }
  const VisionCounters& counters() const { return counters_; }
  /// The state published last.
  const bridge::MarkersStateMsg& last_state() const { return state_; }

 private:
  VisionProgram(bridge::CameraClient camera, const VisionConfig& config);
  double Now() const;

  bridge::CameraClient camera_;
  CameraModel model_;
  MarkerDetector detector_;
  std::unique_ptr<MarkersServer> server_;
  VisionCounters counters_;
  std::chrono::steady_clock::time_point start_;
  // per frame, reused
  bridge::CameraClient::Frame frame_;
  cv::Mat grey_;
  bridge::MarkersStateMsg state_;
};

/// The camera model of a camera device: its describe reply's intrinsics and
/// distortion. Throws InputError naming the camera when they are unusable.
CameraModel CameraModelOf(const bridge::CameraClient& camera);

/// Waits up to wait_s for the newest whole frame of `camera` into *frame.
/// False when none came (a timeout) or when its size is not `model`'s (then
/// *wrong_size is counted); *skipped counts the frames passed over for it.
bool ReceiveFrame(bridge::CameraClient& camera, double wait_s, const CameraModel& model,
                  bridge::CameraClient::Frame* frame, long* skipped, long* wrong_size);

/// What a vision device's describe reply says of the camera it reads (its
/// "camera" entry): name, endpoint, server, size, rate, intrinsics, distortion, pose.
nlohmann::json CameraDescribe(const bridge::CameraClient& camera, const CameraModel& model, const std::string& address,
                              int port);

/// The camera's pose in the world that travels with a frame (nullopt: unknown).
std::optional<Eigen::Isometry3d> CameraPoseOf(const bridge::CameraClient::Frame& frame);

/// "DICT:ID:SIDE" or "DICT:FIRST-LAST:SIDE" (e.g. "4X4_50:0-35:0.03") ->
/// descriptions. Throws InputError naming the text.
std::vector<bridge::MarkerDescriptionMsg> ParseMarkerOption(const std::string& text);

}  // namespace vlab::vision
