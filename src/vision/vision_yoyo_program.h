// The vision program's yo-yo mode (`vlab vision --yoyo-port PORT`): subscribes
// to a camera device, finds the yo-yo's colour blob in every frame, places it
// on the yo-yo's vertical line (vision_blob.h) and serves the result as a
// yoyo device (vision_yoyo_server.h) in place of the lab's ground truth.
//
// Ports
//   input   whole camera frames (bridge::CameraClient: RGB, exposure time,
//           the camera's pose in the world, needed: a frame without it gives
//           a not-seen state); describe requests on the yoyo socket
//   output  one yoyo state per camera frame (seq = frame id, time = exposure
//           time), to every subscriber: [status, x, y, z, vz, 0, 0];
//           status kYoyoNotSeen when no blob was found (values = last ones)
//   rate    the camera's (25 Hz for the lab's webcam): each Step waits for the
//           newest whole frame; frames that arrive meanwhile are skipped
// Latency: HSV threshold, contours and geometry take ~1 ms per 640 x 480 frame.
#pragma once

#include <memory>
#include <string>

#include "bridge/bridge_camera_client.h"
#include "vision/vision_blob.h"
#include "vision/vision_camera_feed.h"
#include "vision/vision_detector.h"
#include "vision/vision_yoyo_server.h"

namespace vlab::vision {

/// The camera (CameraSourceConfig), the yoyo device, the blob and the yo-yo's line.
struct YoyoVisionConfig : CameraSourceConfig {
  YoyoServerConfig server;  ///< the yoyo device (name, bind address, port)
  BlobConfig blob;
  YoyoLine line;
};

/// The frames (FrameCounters: processing is threshold + blob + geometry + publish) and what each showed.
struct YoyoVisionCounters : FrameCounters {
  long seen = 0;     ///< frames with a position
  long no_blob = 0;  ///< frames without a blob of the colour and size
  long no_pose = 0;  ///< frames with a blob but without the camera's pose (or a ray off the plane)
};

class YoyoVisionProgram {
 public:
  /// Connects to the camera and binds the yoyo device. Throws
  /// bridge::NetworkError, bridge::TimeoutError (no camera),
  /// bridge::ProtocolError, InputError (the camera's intrinsics).
  static std::unique_ptr<YoyoVisionProgram> Create(const YoyoVisionConfig& config);

  /// Serves the yoyo socket, waits up to wait_s (s) for a camera frame and,
  /// when one came, tracks the yo-yo and publishes the state. Returns true
  /// when a frame was processed.
  bool Step(double wait_s);

  const bridge::CameraClient& camera() const { return feed_.camera(); }
  const YoyoServer& server() const { return *server_; }
  const CameraModel& camera_model() const { return feed_.model(); }
  const YoyoTracker& tracker() const { return tracker_; }
  const YoyoVisionCounters& counters() const { return counters_; }

 private:
  explicit YoyoVisionProgram(const YoyoVisionConfig& config);

  CameraFeed feed_;
  YoyoTracker tracker_;
  std::unique_ptr<YoyoServer> server_;
  YoyoVisionCounters counters_;
};

}  // namespace vlab::vision
