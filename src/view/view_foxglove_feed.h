// What `vlab view --foxglove` streams (view_foxglove.h): the channels it
// advertises for a view's sources and the ROS 2 messages it publishes on them
// (scene_messages.h, encoding "cdr", schemas "ros2msg"):
//   /tf             tf2_msgs/msg/TFMessage: world -> each body of the scene
//                   stream (the scene device's poses, or the arm's by MuJoCo
//                   kinematics), one message per pose frame; frames named as
//                   scene::BodyFrames names them
//   /scene          foxglove_msgs/msg/SceneUpdate: the visual geometry, an
//                   entity per body locked to its /tf frame; one message,
//                   which every subscriber gets (a channel's newest message)
//   /DEVICE         vlab_msgs/msg/<Device>: the device's log columns the view
//                   gets (the scene device's `signals`, or an arm device's q,
//                   qd, tau named as log.csv names them), one per frame
//   /camera/NAME    sensor_msgs/msg/CompressedImage: each camera frame relayed,
//                   JPEG as the camera sent it, a raw frame as PNG
// Every message's log time is its simulated stamp (ns), so that a live stream
// and a recorded file of the same run carry the same times.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

#include "scene/scene_messages.h"
#include "view/view_foxglove.h"
#include "view/view_server.h"

namespace vlab::view {

class FoxgloveFeed {
 public:
  /// `geometry`: the scene's visual geometry (SceneGeometry, the scene
  /// device's describe reply), its bodies in stream order; `model`: the MJCF
  /// it came from, for mesh vertices (null: /scene leaves meshes out);
  /// `signals`: log column names; `camera`: a camera device's name ("": no
  /// camera channel). Throws nlohmann::json's exceptions for a geometry
  /// without SceneGeometry's fields.
  FoxgloveFeed(const nlohmann::json& geometry, const mjModel* model, const std::vector<std::string>& signals,
               const std::string& camera);
  const std::vector<FoxgloveChannel>& channels() const { return channels_; }

  /// Publishes the /scene message (once: it holds for the run), stamped t (s).
  void PublishScene(double t, ViewServer* server);

  /// Publishes one frame at simulated time t (s): /tf from `poses` (7 per
  /// body: x, y, z m, qw, qx, qy, qz) and each device's signals from
  /// `signals` (one value per signal column). Main loop only.
  void PublishFrame(double t, const double* poses, const double* signals, ViewServer* server);

  /// Publishes one camera picture at simulated time t (s): `format` "jpeg" or
  /// "png". Any one thread (the camera feed).
  void PublishCamera(double t, const std::string& format, const std::string& picture, ViewServer* server);

 private:
  std::vector<FoxgloveChannel> channels_;
  nlohmann::json geometry_;
  const mjModel* model_;
  std::vector<scene::SignalChannel> signal_channels_;
  std::vector<scene::FrameTransform> transforms_;
  std::string camera_;
  int camera_channel_ = -1;
  std::string frame_scratch_, camera_scratch_;
};

/// A simulated time t >= 0 (s) as a log time in ns (the stamp's, StampOf).
std::uint64_t LogTimeNs(double t);

}  // namespace vlab::view
