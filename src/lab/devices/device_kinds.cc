#include "lab/devices/device_kinds.h"

#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_base.h"
#include "lab/devices/device_camera.h"
#include "lab/devices/device_counter.h"
#include "lab/devices/device_gaze.h"
#include "lab/devices/device_gripper.h"
#include "lab/devices/device_point.h"
#include "lab/devices/device_pose.h"
#include "lab/devices/device_scene.h"
#include "lab/devices/device_sensors.h"
#include "lab/devices/device_sim.h"
#include "lab/devices/device_tool.h"
#include "lab/devices/device_word.h"
#include "lab/devices/device_wrench.h"
#include "lab/devices/device_yoyo.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

using bridge::DeviceKind;

// every kind a scenario can name: its wire kind, the reader of its keys, its factory
const DeviceKindSpec kDeviceKinds[] = {
    {DeviceKind::kArm, &ReadArmParams, &MakeArm},
    {DeviceKind::kWrench, &ReadWrenchParams, &MakeWrench},
    {DeviceKind::kSim, &ReadSimParams, &MakeSim},
    {DeviceKind::kCamera, &ReadCameraParams, &MakeCamera},
    {DeviceKind::kBase, &ReadBaseParams, &MakeBase},
    {DeviceKind::kGripper, &ReadGripperParams, &MakeGripper},
    {DeviceKind::kFeet, &ReadFeetParams, &MakeSensors},
    {DeviceKind::kImu, &ReadImuParams, &MakeSensors},
    {DeviceKind::kGaze, &ReadGazeParams, &MakeGaze},
    {DeviceKind::kPose, &ReadPoseParams, &MakePose},
    {DeviceKind::kPoint, &ReadPointParams, &MakePoint},
    {DeviceKind::kYoyo, &ReadYoyoParams, &MakeYoyo},
    {DeviceKind::kCounter, &ReadCounterParams, &MakeCounter},
    {DeviceKind::kScene, &ReadSceneParams, &MakeScene},
    {DeviceKind::kWord, &ReadWordParams, &MakeWord},
    {DeviceKind::kTool, &ReadToolParams, &MakeTool},
};

const char* Name(DeviceKind kind) { return bridge::KindName(static_cast<int>(kind)); }

}  // namespace

const DeviceKindSpec* FindDeviceKind(DeviceKind kind) {
  for (const DeviceKindSpec& spec : kDeviceKinds) {
    if (spec.kind == kind) return &spec;
  }
  return nullptr;
}

const DeviceKindSpec* FindDeviceKind(const std::string& name) {
  for (const DeviceKindSpec& spec : kDeviceKinds) {
    if (name == Name(spec.kind)) return &spec;
  }
  return nullptr;
}

std::string KnownDeviceKinds() {
  std::string out;
  for (const DeviceKindSpec& spec : kDeviceKinds) out += std::string(out.empty() ? "" : ", ") + Name(spec.kind);
  return out;
}

DeviceConfig ReadDevice(const std::string& file, const YAML::Node& node, const std::string& path) {
  MapReader r(file, node, path);
  DeviceConfig device;
  device.where = YamlWhere(file, node);
  device.name = r.String("name");
  const std::string kind = r.String("kind");
  const YAML::Node port = r.Raw("port");
  if (port.IsScalar() && port.Scalar() == "auto") {
    device.port = kAutoPort;
  } else {
    device.port = r.Integer("port", 0);
    if (device.port < 0 || device.port > 65535) {
      r.Fail("port", "must be 0 (not served) to 65535, or auto (any free port)");
    }
  }
  const DeviceKindSpec* spec = FindDeviceKind(kind);
  if (!spec) r.Fail("kind", "unknown device kind '" + kind + "' (known: " + KnownDeviceKinds() + ")");
  device.kind = spec->kind;
  device.params = spec->read(r);
  r.Finish();
  return device;
}

std::unique_ptr<Device> MakeDevice(const DeviceContext& context, const DeviceConfig& config) {
  const DeviceKindSpec* spec = FindDeviceKind(config.kind);
  if (!spec) {
    throw InputError(config.where + ": device '" + config.name + "': the lab has no device of kind '" +
                     Name(config.kind) + "'");
  }
  return spec->make(context, config);
}

}  // namespace vlab::lab
