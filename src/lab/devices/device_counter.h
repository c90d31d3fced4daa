// A speed counter (kind counter) on a spinning MJCF joint, like the PowerBall's
// own rpm counter or a tachometer on a shaft (device_counter.cc).
#pragma once

#include <memory>
#include <string>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A gate-time speed counter on one hinge joint.
struct CounterParams : DeviceParams {
  std::string joint;        ///< the MJCF hinge joint whose turns are counted
  double rate_hz = 0.0;     ///< readings per second: the gate is 1 / rate (0: every control period)
  double resolution = 0.0;  ///< rpm: the speed reading's step (0: not quantised)
  bool powerball = false;   ///< also log a PowerBall's ground truth (powerball_truth.h; lab only)
};

/// Reads a counter entry's keys (joint, rate, resolution, powerball).
std::shared_ptr<const DeviceParams> ReadCounterParams(MapReader& r);
/// Makes the counter; throws InputError naming the device and the joint it cannot bind.
std::unique_ptr<Device> MakeCounter(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
