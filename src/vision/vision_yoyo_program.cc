#include "vision/vision_yoyo_program.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>

#include "vision/vision_camera_feed.h"

namespace vlab::vision {

namespace {

using nlohmann::json;

// what the yoyo device's describe reply says about its camera and tracker
json DescribeExtra(const CameraFeed& feed, const YoyoVisionConfig& config) {
  const BlobConfig& b = config.blob;
  return {{"camera", CameraDescribe(feed, config)},
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
  return std::unique_ptr<YoyoVisionProgram>(new YoyoVisionProgram(config));
}

YoyoVisionProgram::YoyoVisionProgram(const YoyoVisionConfig& config)
    : feed_(config), tracker_(config.blob, config.line) {
  YoyoServerConfig server = config.server;
  server.frame_hz = feed_.camera().fps();
  server.describe_extra.update(DescribeExtra(feed_, config), true);
  server_ = YoyoServer::Create(server);
}

bool YoyoVisionProgram::Step(double wait_s) {
  server_->Poll(feed_.Now());
  if (!feed_.Receive(wait_s, &counters_)) return false;
  const double t0 = feed_.Now();
  const bridge::CameraClient::Frame& frame = feed_.frame();
  const double* state = tracker_.Track(feed_.rgb(), feed_.model(), feed_.pose(), frame.time_s);
  server_->Poll(feed_.Now());  // subscribers that came meanwhile get this frame
  server_->Publish(static_cast<double>(frame.id), frame.time_s, state);

  if (tracker_.seen()) {
    ++counters_.seen;
  } else if (!tracker_.blob().found) {
    ++counters_.no_blob;
  } else {
    ++counters_.no_pose;
  }
  feed_.CountProcessed(t0, &counters_);
  return true;
}

}  // namespace vlab::vision
