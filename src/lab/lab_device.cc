#include "lab/lab_device.h"

namespace vlab::lab {

// defined with each device
std::unique_ptr<SimDevice> MakeSensorDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);
std::unique_ptr<SimDevice> MakeBaseDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);

bool IsSimDeviceKind(const std::string& kind) { return kind == "base" || kind == "feet" || kind == "imu"; }

std::unique_ptr<SimDevice> MakeSimDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed) {
  if (config.kind == "base") return MakeBaseDevice(m, config, seed);
  return MakeSensorDevice(m, config, seed);
}

}  // namespace vlab::lab
