#include "yoyosim/yoyosim_describe.h"

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_yoyo.h"

namespace vlab::yoyosim {

namespace {

using nlohmann::json;

json Vector(const Vec3& v) { return json::array({v[0], v[1], v[2]}); }

}  // namespace

std::string PointDescribeJson(const bridge::DeviceDescription& d, const YoyoSim& sim, const PointFacts& facts) {
  json j;
  j["layout"] = bridge::LayoutJson(bridge::DeviceKind::kPoint);
  j["units"] = {{"x", "m"}, {"y", "m"}, {"z", "m"}, {"vx", "m/s"}, {"vy", "m/s"}, {"vz", "m/s"}, {"frame", "world"}};
  j["status_bits"] = {{"holding", bridge::kStatusHolding},
                      {"refused", bridge::kStatusRefused},
                      {"watchdog", bridge::kStatusWatchdog},
                      {"not_owner", bridge::kStatusNotOwner}};
  j["limits"] = {{"workspace_min", Vector(sim.workspace_min())},
                 {"workspace_max", Vector(sim.workspace_max())},
                 {"speed_max", facts.speed_max}};
  j["start"] = Vector(sim.start());
  j["command_meaning"] =
      "hand position set-point for the end of the next period: the servo reference moves to it linearly over the "
      "period";
  j["watchdog_periods"] = facts.watchdog_periods;
  j["owner_timeout_s"] = facts.owner_timeout_s;
  return bridge::DescribeJson(d, "point", j.dump());
}

std::string YoyoDescribeJson(const bridge::DeviceDescription& d, const YoyoSim& sim) {
  const YoyoParams& y = sim.yoyo();
  json j;
  j["layout"] = bridge::LayoutJson(bridge::DeviceKind::kYoyo);
  j["units"] = {{"x", "m"},        {"y", "m"},        {"z", "m"}, {"vz", "m/s"}, {"string_force", "N"},
                {"spin", "rad/s"}, {"frame", "world"}};
  j["status_bits"] = {{"not_seen", bridge::kYoyoNotSeen}};
  j["yoyo"] = {{"mass", y.mass},
               {"spin_inertia", y.spin_inertia},
               {"axle_radius", y.axle_radius},
               {"string_length", y.string_length}};
  return bridge::DescribeJson(d, "yoyo", j.dump());
}

}  // namespace vlab::yoyosim
