#include "vision/vision_yoyo_server.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_yoyo.h"

namespace vlab::vision {

namespace {

using nlohmann::json;
// DeviceEndpoint counts time in periods: the vision program's are 10 ms ticks
// of its monotonic clock (frames may come at any rate)
constexpr double kTicksPerSecond = 100;

long Tick(double now_s) { return static_cast<long>(std::floor(now_s * kTicksPerSecond)); }

}  // namespace

json YoyoDescribe(const YoyoServerConfig& config, int port) {
  bridge::DeviceDescription d;
  d.name = config.name;
  d.server = "vlab vision";
  d.clock = "realtime";
  d.address = config.bind_address;
  d.port = port;
  d.control_hz = config.frame_hz;
  json facts;
  facts["layout"] = bridge::LayoutJson(bridge::DeviceKind::kYoyo);
  facts["units"] = {{"x", "m"},
                    {"y", "m"},
                    {"z", "m"},
                    {"vz", "m/s"},
                    {"string_force", "N (not measured: always 0)"},
                    {"spin", "rad/s (not measured: always 0)"},
                    {"time", "s, exposure time of the frame (the camera's clock)"},
                    {"seq", "the camera's frame id"}};
  facts["frame"] = "world";
  facts["status_bits"] = {{"not_seen", bridge::kYoyoNotSeen}};
  facts["measures"] = {"x", "y", "z", "vz"};
  facts["not_measured"] = {{"string_force", 0.0}, {"spin", 0.0}};
  facts["rates"] = {{"control_hz", config.frame_hz}, {"frame_hz", config.frame_hz}};
  json j = json::parse(bridge::DescribeJson(d, "yoyo", facts.dump()));
  j.update(config.describe_extra, true);
  return j;
}

std::unique_ptr<YoyoServer> YoyoServer::Create(const YoyoServerConfig& config) {
  std::unique_ptr<YoyoServer> server(new YoyoServer());
  server->server_ = BindDeviceSocket(config);
  bridge::EndpointConfig e;
  e.name = config.name;
  e.kind = bridge::DeviceKind::kYoyo;
  e.describe_json = YoyoDescribe(config, server->server_->port()).dump();
  e.subscriber_timeout_s = config.subscriber_timeout_s;
  e.max_subscribers = std::max(1, config.max_subscribers);
  e.watchdog_periods = 0;
  e.command_length = 0;  // no commands
  server->server_->Serve(std::move(e));
  return server;
}

int YoyoServer::Poll(double now_s) { return server_->Receive(Tick(now_s)); }

void YoyoServer::Publish(double seq, double time, const double* state) {
  constexpr int n = bridge::ValueCount(bridge::LayoutOf(bridge::DeviceKind::kYoyo).state);
  server_->Publish(seq, time, state, n);
  ++states_;
}

}  // namespace vlab::vision
