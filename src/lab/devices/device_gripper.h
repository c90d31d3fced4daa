// A parallel gripper (kind gripper): an opening servo and a grip-force drive
// on one tendon, a touch sensor per pad (device_gripper.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A parallel gripper (kind gripper): an opening servo and a grip-force drive
/// on one tendon, and a touch sensor per pad (mjcf/gripper's names by default).
struct GripperParams : DeviceParams {
  std::string servo = "gripper";                 ///< position actuator of the opening tendon (ctrl: opening, m)
  std::string force_actuator = "gripper_force";  ///< force actuator of the same tendon (ctrl: N, negative closes)
  std::vector<std::string> touch = {"gripper_touch_left", "gripper_touch_right"};  ///< pad touch sensors
  double max_speed = 0.083;  ///< m/s: opening set-points ramp at this speed (PG 70: 83 mm/s)
  double grasp_force = 2.0;  ///< N on every pad (and the jaws at rest) for "grasped"
  CommandInputConfig input;  ///< watchdog_periods, owner_timeout
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadGripperParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakeGripper(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
