// A holonomic mobile base (kind base): planar x, y, yaw joints driven by
// velocity actuators, commanded in the base or the world frame (device_base.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A holonomic mobile base (kind base): planar x, y, yaw joints driven by
/// velocity actuators, commanded in the base or the world frame.
struct BaseParams : DeviceParams {
  std::vector<std::string> joints;     ///< world x, world y (slide) and yaw (hinge) joints
  std::vector<std::string> actuators;  ///< velocity actuators of those joints (default: the joint names)
  std::vector<double> max_velocity = {1.0, 1.0, 2.0};      ///< vx, vy (m/s), wz (rad/s)
  std::vector<double> max_acceleration = {1.0, 1.0, 2.0};  ///< m/s^2, m/s^2, rad/s^2
  bool odometry_drift = false;                             ///< seeded odometry errors (scale and yaw-rate bias)
  double drift_scale = 0.01;                               ///< std of the odometry's scale errors (fraction)
  double drift_yaw_rate = 0.002;                           ///< std of the odometry's yaw-rate bias, rad/s
  CommandInputConfig input;                                ///< watchdog_periods, owner_timeout
};

/// Reads the entry's own keys.
std::shared_ptr<const DeviceParams> ReadBaseParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakeBase(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
