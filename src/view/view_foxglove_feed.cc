// The Foxglove stream's channels and messages (view_foxglove_feed.h).
#include "view/view_foxglove_feed.h"

namespace vlab::view {

namespace {

// channel ids: /tf 0, /scene 1, then one per device of the signals, then the camera
constexpr int kTfChannel = 0, kSceneChannel = 1, kFirstSignalChannel = 2;

}  // namespace

FoxgloveFeed::FoxgloveFeed(const nlohmann::json& geometry, const mjModel* model,
                           const std::vector<std::string>& signals, const std::string& camera)
    : geometry_(geometry), model_(model), camera_(camera) {
  const scene::MessageSchema tf = scene::TfMessageSchema(), scene_update = scene::SceneUpdateSchema();
  channels_.push_back({"/tf", tf.name, tf.text});
  channels_.push_back({"/scene", scene_update.name, scene_update.text});
  for (const std::string& frame : scene::BodyFrames(geometry)) {
    transforms_.push_back({"world", frame, {0, 0, 0}, {1, 0, 0, 0}});
  }
  if (!signals.empty()) signal_channels_ = scene::SignalChannels(signals);
  for (const scene::SignalChannel& c : signal_channels_) channels_.push_back({c.topic, c.schema.name, c.schema.text});
  if (!camera.empty()) {
    const scene::MessageSchema image = scene::CompressedImageSchema();
    camera_channel_ = static_cast<int>(channels_.size());
    channels_.push_back({"/camera/" + camera, image.name, image.text});
  }
}

void FoxgloveFeed::PublishScene(double t, ViewServer* server) {
  std::string message;
  scene::EncodeSceneUpdate(t, geometry_, model_, &message);
  server->Publish(FoxgloveRecord(LogTimeNs(t), message), kSceneChannel);
}

void FoxgloveFeed::PublishFrame(double t, const double* poses, const double* signals, ViewServer* server) {
  const std::uint64_t ns = LogTimeNs(t);
  for (std::size_t i = 0; i < transforms_.size(); ++i) {
    const double* p = poses + 7 * i;
    for (int k = 0; k < 3; ++k) transforms_[i].translation[k] = p[k];
    for (int k = 0; k < 4; ++k) transforms_[i].rotation_wxyz[k] = p[3 + k];
  }
  scene::EncodeTfMessage(t, transforms_.data(), transforms_.size(), &frame_scratch_);
  server->Publish(FoxgloveRecord(ns, frame_scratch_), kTfChannel);
  for (std::size_t c = 0; c < signal_channels_.size(); ++c) {
    scene::EncodeSignals(t, signal_channels_[c], signals, &frame_scratch_);
    server->Publish(FoxgloveRecord(ns, frame_scratch_), static_cast<int>(kFirstSignalChannel + c));
  }
}

void FoxgloveFeed::PublishCamera(double t, const std::string& format, const std::string& picture, ViewServer* server) {
  if (camera_channel_ < 0) return;
  scene::EncodeCompressedImage(t, camera_, format, reinterpret_cast<const std::uint8_t*>(picture.data()),
                               picture.size(), &camera_scratch_);
  server->Publish(FoxgloveRecord(LogTimeNs(t), camera_scratch_), camera_channel_);
}

std::uint64_t LogTimeNs(double t) {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  scene::StampOf(t, &sec, &nanosec);
  return static_cast<std::uint64_t>(sec) * 1000000000ull + nanosec;
}

}  // namespace vlab::view
