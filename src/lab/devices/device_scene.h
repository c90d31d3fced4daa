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

namespace vlab::lab {

/// A scene stream's keys.
struct SceneParams : DeviceParams {
  double rate_hz = 30.0;  ///< pose frames per second (at most the control rate)
  std::vector<std::string> signals;  ///< log columns sent after the poses (live plots), at most kMaxSceneSignals
};

inline constexpr int kMaxSceneSignals = 16;

/// The bodies a scene stream carries, in stream order: every body except the
/// world that has a visible geom (group 0-2, alpha > 0), in body-id order.
std::vector<int> SceneBodies(const mjModel* m);

/// The visual geometry of a scene, the describe reply's "bodies" and "geoms"
/// (also written as scene.json beside a pose recording): every visible geom
/// with its body (index into `bodies`, -1 for the world), type, size, pose in
/// its body's frame, rgba (the material's where it has one), mesh id (-1:
/// none) and texture (id, kind "2d"/"cube", width, height, repeat; id -1:
/// none), and the meshes' vertex and face counts. Mesh vertices and texture
/// pixels are not in it: a viewer takes them from the same MJCF.
nlohmann::json SceneGeometry(const mjModel* m, const std::vector<int>& bodies);

/// Writes the poses of `bodies` (x, y, z, qw, qx, qy, qz each, world frame)
/// from mjData's xpos and xquat into out[0 .. 7 * bodies.size()).
void ScenePoses(const mjData& d, const std::vector<int>& bodies, double* out);

/// Reads a scene entry's keys (rate, signals).
std::shared_ptr<const DeviceParams> ReadSceneParams(MapReader& r);
/// Makes the scene stream; throws InputError naming the device when the rate
/// is faster than the control rate or the scene has too many bodies for a datagram.
std::unique_ptr<Device> MakeScene(const DeviceContext& context, const DeviceConfig& config);

}  // namespace vlab::lab
