// The Foxglove stream's channels and messages (view_foxglove_feed.h).
#include "view/view_foxglove_feed.h"

namespace vlab::view {

// channel ids: /tf 0, then one per device of the signals, then the camera
FoxgloveFeed::FoxgloveFeed(const std::vector<std::string>& bodies, const std::vector<std::string>& signals,
                           const std::string& camera)
    : camera_(camera) {
  const scene::MessageSchema tf = scene::TfMessageSchema();
  channels_.push_back({"/tf", tf.name, tf.text});
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    scene::FrameTransform f{"world", bodies[i].empty() ? "body" + std::to_string(i) : bodies[i], {}, {1, 0, 0, 0}};
    transforms_.push_back(f);
  }
  if (!signals.empty()) signal_channels_ = scene::SignalChannels(signals);
  for (const scene::SignalChannel& c : signal_channels_) channels_.push_back({c.topic, c.schema.name, c.schema.text});
  if (!camera.empty()) {
    const scene::MessageSchema image = scene::CompressedImageSchema();
    camera_channel_ = static_cast<int>(channels_.size());
    channels_.push_back({"/camera/" + camera, image.name, image.text});
  }
}

void FoxgloveFeed::PublishFrame(double t, const double* poses, const double* signals, ViewServer* server) {
  const std::uint64_t ns = LogTimeNs(t);
  for (std::size_t i = 0; i < transforms_.size(); ++i) {
    const double* p = poses + 7 * i;
    for (int k = 0; k < 3; ++k) transforms_[i].translation[k] = p[k];
    for (int k = 0; k < 4; ++k) transforms_[i].rotation_wxyz[k] = p[3 + k];
  }
  scene::EncodeTfMessage(t, transforms_.data(), transforms_.size(), &frame_scratch_);
  server->Publish(FoxgloveRecord(ns, frame_scratch_), 0);
  for (std::size_t c = 0; c < signal_channels_.size(); ++c) {
    scene::EncodeSignals(t, signal_channels_[c], signals, &frame_scratch_);
    server->Publish(FoxgloveRecord(ns, frame_scratch_), static_cast<int>(1 + c));
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
