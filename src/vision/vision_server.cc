#include "vision/vision_server.h"

#include <algorithm>

#include <opencv2/core/version.hpp>
#include <nlohmann/json.hpp>

namespace vlab::vision {

namespace {

using nlohmann::json;
constexpr std::size_t kBufferBytes = 65536;  // any UDP datagram fits

json MarkerFields() {
  return {"dictionary", "id", "valid", "reprojection_error", "T_camera[16]", "world_valid", "T_world[16]"};
}

}  // namespace

std::unique_ptr<MarkersServer> MarkersServer::Create(const MarkersServerConfig& config) {
  std::unique_ptr<MarkersServer> server(new MarkersServer(config));
  server->socket_ = bridge::UdpSocket::Bind(config.bind_address, config.port);
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

MarkersServer::MarkersServer(const MarkersServerConfig& config)
    : config_(config), table_(config.max_markers), sessions_(Sessions(config, &now_s_)), buffer_(kBufferBytes) {
  payload_.reserve(bridge::kMaxPacketValues);
  packet_.reserve(bridge::kMaxPacketValues * sizeof(double));
}

int MarkersServer::Poll(double now_s) {
  int handled = 0;
  for (;;) {
    bridge::Endpoint from;
    bool truncated = false;
    const long size = socket_->Receive(buffer_.data(), buffer_.size(), &from, 0, &truncated);
    if (size < 0) return handled;
    ++handled;
    now_s_ = now_s;
    Handle(size, from, truncated);
  }
}

void MarkersServer::Handle(long size, const bridge::Endpoint& from, bool truncated) {
  ++counters_.received;
  auto refuse = [this](long* reason) {
    ++*reason;
    ++counters_.refused;
  };
  bridge::Header header;
  bridge::DecodeError e =
      truncated ? bridge::DecodeError::kTooLong
                : bridge::DecodePacket(buffer_.data(), static_cast<std::size_t>(size), &header, &payload_);
  using bridge::MessageType;
  // a describe request is answered whatever kind it names (0: any): tools discover with it
  const bool describe = e == bridge::DecodeError::kNone && header.type == static_cast<int>(MessageType::kDescribe);
  if (e == bridge::DecodeError::kNone &&
      (describe ? header.kind > bridge::kMaxDeviceKind : header.kind != static_cast<int>(bridge::DeviceKind::kMarkers))) {
    e = bridge::DecodeError::kBadKind;
  }
  if (e == bridge::DecodeError::kNone && (header.type == static_cast<int>(MessageType::kState) ||
                                          header.type == static_cast<int>(MessageType::kSession))) {
    e = bridge::DecodeError::kBadType;
  }
  if (e != bridge::DecodeError::kNone) return refuse(&counters_.refused_malformed);
  if (describe || header.type == static_cast<int>(MessageType::kSubscribe)) {
    const auto outcome = sessions_.HandleRequest(header, payload_, from, *socket_);
    counters_.sessions = sessions_.counters();
    if (outcome == bridge::SessionTable::Outcome::kMalformed) return refuse(&counters_.refused_malformed);
    if (outcome == bridge::SessionTable::Outcome::kDescribe) {
      ++counters_.describes;
      socket_->SendTo(reinterpret_cast<const unsigned char*>(describe_json_.data()), describe_json_.size(), from);
    }
    return;
  }
  if (!sessions_.Touch(from)) return refuse(&counters_.refused_not_subscribed);
  if (bridge::ParseMarkersCommand(header, payload_, &descriptions_) != bridge::DecodeError::kNone) {
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
  sessions_.Expire();
  counters_.sessions = sessions_.counters();
  bridge::EncodeMarkersState(seq, time, state, &packet_);
  for (const auto& s : sessions_.sessions()) socket_->SendTo(packet_.data(), packet_.size(), s.endpoint);
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
            {"endpoint", {{"address", config_.bind_address}, {"port", socket_ ? socket_->local_port() : config_.port}}},
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
  describe_json_ = j.dump();
}

}  // namespace vlab::vision
