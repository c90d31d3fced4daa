// Describe replies of vlab-yoyosim's two devices: the common fields of
// bridge_describe plus each kind's layout (bridge_layouts.h), units and facts.
#pragma once

#include <string>

#include "bridge/bridge_describe.h"
#include "yoyosim/yoyosim.h"

namespace vlab::yoyosim {

/// The hand's facts beside the simulator's: command limits and watchdog.
struct PointFacts {
  double speed_max = 2.0;        ///< m/s: the set-point in force moves at most this fast towards a command
  int watchdog_periods = 3;      ///< silent owner -> hold after this many periods
  double owner_timeout_s = 1.0;  ///< silent owner gives the input up after this, s
};

/// The point device's describe reply: layout, units, status bits, limits
/// {workspace_min, workspace_max (m, world), speed_max (m/s)}, start (m),
/// watchdog_periods, owner_timeout_s.
std::string PointDescribeJson(const bridge::DeviceDescription& d, const YoyoSim& sim, const PointFacts& facts);

/// The yoyo device's describe reply: layout (no commands), units, status bits
/// {not_seen}, and the yo-yo's parameters {mass, spin_inertia, axle_radius,
/// string_length} read from the scene.
std::string YoyoDescribeJson(const bridge::DeviceDescription& d, const YoyoSim& sim);

}  // namespace vlab::yoyosim
