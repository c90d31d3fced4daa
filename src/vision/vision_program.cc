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
json DescribeExtra(const CameraFeed& feed, const VisionConfig& config) {
  const DetectorConfig& d = config.detector;
  return {{"rates", {{"control_hz", feed.camera().fps()}, {"frame_hz", feed.camera().fps()}}},
          {"camera", CameraDescribe(feed, config)},
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
  return std::unique_ptr<VisionProgram>(new VisionProgram(config));
}

VisionProgram::VisionProgram(const VisionConfig& config) : feed_(config), detector_(config.detector) {
  MarkersServerConfig server = config.server;
  server.describe_extra.update(DescribeExtra(feed_, config), true);
  server_ = MarkersServer::Create(server);
  if (!server_->Describe(config.markers)) {
    throw vlab::InputError("--marker: " + std::to_string(config.markers.size()) + " markers exceed the table's " +
                           std::to_string(server.max_markers));
  }
  state_.markers.reserve(bridge::kMaxMarkersPerState);
}

bool VisionProgram::Step(double wait_s) {
  server_->Poll(feed_.Now());
  if (!feed_.Receive(wait_s, &counters_)) return false;
  const double t0 = feed_.Now();
  cv::cvtColor(feed_.rgb(), grey_, cv::COLOR_RGB2GRAY);
  server_->Poll(feed_.Now());  // descriptions that came meanwhile apply to this frame
  const LocateStats stats = LocateMarkers(grey_, feed_.model(), feed_.pose(), server_->table(), detector_, &state_);
  const bridge::CameraClient::Frame& frame = feed_.frame();
  server_->Publish(static_cast<double>(frame.id), frame.time_s, state_, feed_.Now());

  counters_.reported += stats.reported;
  counters_.valid += stats.valid;
  counters_.unknown += state_.unknown;
  feed_.CountProcessed(t0, &counters_);
  return true;
}

}  // namespace vlab::vision
