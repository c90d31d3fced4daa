// Feet and IMU devices (kinds feet and imu): MJCF sensors read as they are,
// with optional seeded noise (device_sensors.cc).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "lab/devices/device.h"

namespace vlab::lab {

/// A device that reads MJCF sensors as they are (kinds feet and imu).
struct SensorParams : DeviceParams {
  std::vector<std::string> sensors;  ///< MJCF sensors, in payload order
  double noise = 0.0;                ///< Gaussian noise std added to every value (sensor units; 0: none)
  // feet only: log columns of the whole support (not on the wire)
  std::vector<std::string> pads;   ///< one MJCF site per sensor: where it presses (empty: no CoP columns)
  std::string weight_of;           ///< body whose subtree weight the sum is compared with ("": none)
  double contact_threshold = 0.0;  ///< N: a pad reading more than this is in contact
};

/// Reads a feet entry's keys (sensors, noise, pads, weight_of, contact_threshold).
std::shared_ptr<const DeviceParams> ReadFeetParams(MapReader& r);
/// Reads an imu entry's keys (sensors, noise).
std::shared_ptr<const DeviceParams> ReadImuParams(MapReader& r);
/// Makes the device; throws InputError naming the device and the MJCF element it cannot bind.
std::unique_ptr<Device> MakeSensors(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
