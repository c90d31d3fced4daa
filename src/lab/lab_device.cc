#include "lab/lab_device.h"

#include "core/core_errors.h"

namespace vlab::lab {

// defined with each device
std::unique_ptr<SimDevice> MakeSensorDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);
std::unique_ptr<SimDevice> MakeBaseDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);
std::unique_ptr<SimDevice> MakeGazeDevice(const mjModel* m, const DeviceConfig& config);
std::unique_ptr<SimDevice> MakeGripperDevice(const mjModel* m, const DeviceConfig& config);
std::unique_ptr<SimDevice> MakePoseDevice(const mjModel* m, const DeviceConfig& config);
std::unique_ptr<SimDevice> MakeYoyoDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed);

bool IsSimDeviceKind(const std::string& kind) {
  return kind == "base" || kind == "gripper" || kind == "feet" || kind == "imu" || kind == "gaze" || kind == "pose" ||
         kind == "point" || kind == "yoyo";
}

std::unique_ptr<SimDevice> MakeSimDevice(const mjModel* m, const DeviceConfig& config, std::uint64_t seed) {
  if (config.kind == "base") return MakeBaseDevice(m, config, seed);
  if (config.kind == "gaze") return MakeGazeDevice(m, config);
  if (config.kind == "gripper") return MakeGripperDevice(m, config);
  if (config.kind == "pose") return MakePoseDevice(m, config);
  if (config.kind == "yoyo") return MakeYoyoDevice(m, config, seed);
  if (config.kind == "point") {
    throw InputError(config.where + ": device '" + config.name + "': a point device is made with its arm (MakePointDevice)");
  }
  return MakeSensorDevice(m, config, seed);
}

}  // namespace vlab::lab
