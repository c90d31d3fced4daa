// A scene stream (kind scene): the pose of every visual body, for viewers
// (`vlab view`), the pose recording of a run and the glTF export
// (device_scene.cc).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

#include "lab/devices/device.h"
#include "scene/scene_geometry.h"

namespace vlab::lab {

/// A scene stream's keys.
struct SceneParams : DeviceParams {
  double rate_hz = 30.0;             ///< pose frames per second (at most the control rate)
  std::vector<std::string> signals;  ///< log columns sent after the poses (live plots), at most kMaxSceneSignals
};

inline constexpr int kMaxSceneSignals = 16;

/// The stream's bodies, geometry and poses (scene/scene_geometry.h, shared with the view).
using scene::SceneBodies;
using scene::SceneGeometry;
using scene::ScenePoses;

/// Reads a scene entry's keys (rate, signals).
std::shared_ptr<const DeviceParams> ReadSceneParams(MapReader& r);
/// Makes the scene stream; throws InputError naming the device when the rate
/// is faster than the control rate or the scene has too many bodies for a datagram.
std::unique_ptr<Device> MakeScene(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
