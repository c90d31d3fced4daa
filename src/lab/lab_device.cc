#include "lab/lab_device.h"

namespace vlab::lab {

// defined with each device
std::unique_ptr<SimDevice> MakeSensorDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);
std::unique_ptr<SimDevice> MakeBaseDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);
std::unique_ptr<SimDevice> MakeGazeDevice(const mjModel* m, const DeviceConfig& config);
std::unique_ptr<SimDevice> MakeGripperDevice(const mjModel* m, const DeviceConfig& config);
std::unique_ptr<SimDevice> MakePoseDevice(const mjModel* m, const DeviceConfig& config);

bool IsSimDeviceKind(const std::string& kind) {
  return kind == "base" || kind == "gripper" || kind == "feet" || kind == "imu" || kind == "gaze" || kind == "pose";
}

std::unique_ptr<SimDevice> MakeSimDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed) {
  if (config.kind == "base") return MakeBaseDevice(m, config, seed);
  if (config.kind == "gaze") return MakeGazeDevice(m, config);
  if (config.kind == "gripper") return MakeGripperDevice(m, config);
  if (config.kind == "pose") return MakePoseDevice(m, config);
  return MakeSensorDevice(m, config, seed);
}

}  // namespace vlab::lab
