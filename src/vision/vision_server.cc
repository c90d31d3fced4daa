#include "vision/vision_server.h"

#include <algorithm>

#include <nlohmann/json.hpp>
#include <opencv2/core/version.hpp>

namespace vlab::vision {

namespace {

using nlohmann::json;

json MarkerFields() {
  return {"dictionary", "id", "valid", "reprojection_error", "T_camera[16]", "world_valid", "T_world[16]"};
}

}  // namespace

std::unique_ptr<MarkersServer> MarkersServer::Create(const MarkersServerConfig& config) {
  std::unique_ptr<MarkersServer> server(new MarkersServer(config));
  server->server_ = BindDeviceSocket(config);
  server->server_->ServeSessions(Sessions(config, &server->now_s_), "");
  server->RebuildDescribe();
  return server;
}

bridge::SessionConfig MarkersServer::Sessions(const MarkersServerConfig& config, const double* now_s) {
  bridge::SessionConfig s;
  s.kind = bridge::DeviceKind::kMarkers;
  s.max_subscribers = std::max(1, config.max_subscribers);
  s.subscriber_timeout_s = config.subscriber_timeout_s;
  s.clock = [now_s] { return *now_s; };
  return s;
}

MarkersServer::MarkersServer(const MarkersServerConfig& config) : config_(config), table_(config.max_markers) {
  packet_.reserve(bridge::kMaxPacketValues * sizeof(double));
}

int MarkersServer::Poll(double now_s) {
  now_s_ = now_s;
  return server_->Drain(0, [this](const unsigned char* data, std::size_t size, const bridge::Endpoint& from) {
    Handle(data, size, from);
  });
}

void MarkersServer::Handle(const unsigned char* data, std::size_t size, const bridge::Endpoint& from) {
  ++counters_.received;
  auto refuse = [this](long* reason) {
    ++*reason;
    ++counters_.refused;
  };
  using Request = bridge::DeviceServer::Request;
  const Request request = server_->HandleRequest(data, size, from);
  counters_.sessions = server_->sessions().counters();
  if (request == Request::kMalformed) return refuse(&counters_.refused_malformed);
  if (request == Request::kDescribed) ++counters_.describes;
  if (request != Request::kCommand) return;
  // a marker-description command, from a subscriber
  if (!server_->sessions().Touch(from)) return refuse(&counters_.refused_not_subscribed);
  if (bridge::ParseMarkersCommand(server_->header(), server_->payload(), &descriptions_) !=
      bridge::DecodeError::kNone) {
    return refuse(&counters_.refused_malformed);
  }
  if (!Describe(descriptions_)) return refuse(&counters_.refused_limits);
  ++counters_.accepted;
}

bool MarkersServer::Describe(const std::vector<bridge::MarkerDescriptionMsg>& descriptions) {
  if (!table_.Apply(descriptions)) return false;
  RebuildDescribe();
  return true;
}

void MarkersServer::Publish(double seq, double time, const bridge::MarkersStateMsg& state, double now_s) {
  now_s_ = now_s;
  bridge::EncodeMarkersState(seq, time, state, &packet_);
  server_->PublishToSubscribers(packet_);
  counters_.sessions = server_->sessions().counters();
  ++counters_.states;
}

void MarkersServer::RebuildDescribe() {
  json markers = json::array();
  for (const bridge::MarkerDescriptionMsg& d : table_.Entries()) {
    markers.push_back({{"dictionary", bridge::FindMarkerDictionary(d.dictionary)->name},
                       {"code", d.dictionary},
                       {"id", d.id},
                       {"side", d.side_m}});
  }
  json dictionaries = json::object();
  for (const bridge::MarkerDictionary& d : bridge::MarkerDictionaries()) {
    dictionaries[d.name] = {{"code", d.code}, {"bits", d.bits}, {"markers", d.markers}};
  }
  json j = {{"name", config_.name},
            {"kind", "markers"},
            {"protocol", bridge::kProtocolVersion},
            {"server", std::string("vlab vision (OpenCV ") + CV_VERSION + " aruco)"},
            {"clock", "realtime"},
            {"endpoint", {{"address", config_.bind_address}, {"port", server_->port()}}},
            {"rates", {{"control_hz", 0.0}}},
            {"header", {"magic", "version", "kind", "type", "seq", "time", "length"}},
            {"layout",
             {{"state", {"count", "described", "unknown", "marker[count]"}},
              {"marker", MarkerFields()},
              {"command", {"description[k]"}},
              {"description", {"dictionary", "id", "side"}}}},
            {"units",
             {{"time", "s, exposure time of the image (the camera's clock)"},
              {"seq", "the camera's frame id"},
              {"reprojection_error", "px, RMS over the 4 corners"},
              {"T_camera", "row-major 4x4, m; marker frame in the OpenCV camera frame (x right, y down, z forward)"},
              {"T_world", "row-major 4x4, m; marker frame in the world frame (zero unless world_valid)"},
              {"side", "m, outer edge of the black border; 0 removes the marker"}}},
            {"marker_frame", "origin at the marker centre, x right of the printed marker, y up, z out of the print"},
            {"max_markers_per_state", bridge::kMaxMarkersPerState},
            {"max_descriptions_per_command", bridge::kMaxDescriptionsPerCommand},
            {"max_markers", config_.max_markers},
            {"markers", markers},
            {"dictionaries", dictionaries}};
  j.update(config_.describe_extra, true);
  server_->set_describe_json(j.dump());
}

}  // namespace vlab::vision
