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

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_markers.h"
#include "vision/vision_camera_feed.h"
#include "vision/vision_detector.h"
#include "vision/vision_locate.h"
#include "vision/vision_server.h"

namespace vlab::vision {

/// The camera (CameraSourceConfig), the markers device and the detector.
struct VisionConfig : CameraSourceConfig {
  MarkersServerConfig server;  ///< the markers device (name, bind address, port)
  DetectorConfig detector;
  std::vector<bridge::MarkerDescriptionMsg> markers;  ///< the table at start (--marker)
};

/// The frames (FrameCounters: processing is detection + pose + publish) and the markers.
struct VisionCounters : FrameCounters {
  long reported = 0;  ///< markers reported, over all frames
  long valid = 0;     ///< of those, valid
  long unknown = 0;   ///< detections of markers not in the table
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

  const bridge::CameraClient& camera() const { return feed_.camera(); }
  const MarkersServer& server() const { return *server_; }
  const CameraModel& camera_model() const { return feed_.model(); }
  const VisionCounters& counters() const { return counters_; }
  /// The state published last.
  const bridge::MarkersStateMsg& last_state() const { return state_; }

 private:
  explicit VisionProgram(const VisionConfig& config);

  CameraFeed feed_;
  MarkerDetector detector_;
  std::unique_ptr<MarkersServer> server_;
  VisionCounters counters_;
  cv::Mat grey_;  // per frame, reused
  bridge::MarkersStateMsg state_;
};

/// "DICT:ID:SIDE" or "DICT:FIRST-LAST:SIDE" (e.g. "4X4_50:0-35:0.03") ->
/// descriptions. Throws InputError naming the text.
std::vector<bridge::MarkerDescriptionMsg> ParseMarkerOption(const std::string& text);

}  // namespace vlab::vision
