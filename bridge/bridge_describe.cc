#include "bridge/bridge_describe.h"

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "bridge/bridge_protocol.h"

namespace vlab::bridge {

namespace {

using nlohmann::json;

json Common(const DeviceDescription& d, const std::string& kind) {
  return {{"name", d.name},
          {"kind", kind},
          {"protocol", kProtocolVersion},
          {"server", d.server},
          {"clock", d.clock},
          {"endpoint", {{"address", d.address}, {"port", d.port}}},
          {"rates", {{"control_hz", d.control_hz}}},
          {"header", {"magic", "version", "kind", "type", "seq", "time", "length"}}};
}

}  // namespace

std::string DescribeJson(const ArmDescription& d) {
  const std::size_t n = d.joints.size();
  json j = Common(d, "arm");
  j["layout"] = LayoutJson(DeviceKind::kArm, static_cast<int>(n));
  j["units"] = {{"q", "rad"}, {"qd", "rad/s"}, {"tau", "N m"}, {"value", "rad (mode 1), rad/s (mode 2), N m (mode 3)"}};
  j["modes"] = {{"hold", 0}, {"position", 1}, {"velocity", 2}, {"torque", 3}};
  j["status_bits"] = {{"holding", kStatusHolding},  {"refused", kStatusRefused},   {"saturated", kStatusSaturated},
                      {"at_limit", kStatusAtLimit}, {"watchdog", kStatusWatchdog}, {"not_owner", kStatusNotOwner}};
  j["joints"] = d.joints;
  j["limits"] = {{"position_min", d.position_min},
                 {"position_max", d.position_max},
                 {"velocity_max", d.velocity_max},
                 {"torque_max", d.torque_max}};
  j["watchdog_periods"] = d.watchdog_periods;
  j["owner_timeout_s"] = d.owner_timeout_s;
  if (!d.resolution.empty()) j["resolution"] = d.resolution;
  j["feedforward"] = d.feedforward;
  return DescribeWithPayload(j.dump(), d.payload);
}

std::string DescribeJson(const WrenchDescription& d) {
  json j = Common(d, "wrench");
  j["layout"] = LayoutJson(DeviceKind::kWrench);
  j["units"] = {{"force", "N"}, {"torque", "N m"}, {"frame", "sensor"}};
  j["sensor_model"] = d.sensor_model;
  j["full_scale"] = d.full_scale;
  j["filter"] = d.filter;
  j["filter_cutoff_hz"] = d.filter_cutoff_hz;
  j["rates"]["sample_hz"] = d.sample_hz;
  return j.dump();
}

std::string DescribeJson(const SimDescription& d) {
  json j = Common(d, "sim");
  j["layout"] = LayoutJson(DeviceKind::kSim);
  j["units"] = {{"sim_time", "s"}, {"max_lateness", "s"}};
  j["ops"] = {{"reset", 1}, {"pause", 2}, {"resume", 3}, {"step", 4}, {"set_realtime_factor", 5}};
  j["modes"] = {{"running", 0}, {"paused", 1}};
  j["clocks"] = {{"fast", 0}, {"lockstep", 1}, {"realtime", 2}};
  j["devices"] = d.devices;
  j["owner_timeout_s"] = d.owner_timeout_s;
  j["on_owner_lost"] = d.on_owner_lost;
  j["ops_from"] = d.ops_from;
  return j.dump();
}

std::string DescribeJson(const DeviceDescription& d, const std::string& kind, const std::string& facts) {
  json j = Common(d, kind);
  j.update(json::parse(facts));
  return j.dump();
}

}  // namespace vlab::bridge
