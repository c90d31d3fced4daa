// A speed counter (kind counter) on a spinning MJCF joint, like the PowerBall's
// own rpm counter or a tachometer on a shaft (device_counter.cc).
#pragma once

#include <cmath>
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

/// rpm per rad/s: the counter's speed unit.
inline constexpr double kRpmPerRadPerSecond = 60.0 / (2.0 * M_PI);

/// The counter's gate schedule: true when a reading falls at the period end `t` (the first
/// at or after the gate's end `*next_s`), then `*next_s` moved on to the next gate's end (a
/// gate shorter than a period catches up). The device reads by it, and vlab identify's replay
/// predicts its readings by it.
bool CounterReadingDue(double t, double gate_s, double* next_s);

/// Reads a counter entry's keys (joint, rate, resolution, powerball).
std::shared_ptr<const DeviceParams> ReadCounterParams(MapReader& r);
/// Makes the counter; throws InputError naming the device and the joint it cannot bind.
std::unique_ptr<Device> MakeCounter(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
