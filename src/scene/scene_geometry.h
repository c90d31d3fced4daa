// The visual side of a MuJoCo scene, as a viewer draws it: which bodies move,
// what their geoms look like, and where the bodies are. Read by the lab's scene
// stream (kind scene) and pose recording, and by `vlab view` and `vlab export`.
#pragma once

#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

namespace vlab::scene {

/// Values of one body's pose: x, y, z (m), qw, qx, qy, qz (unit quaternion), world frame.
inline constexpr int kPoseValues = 7;

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

/// Writes the poses of `bodies` (kPoseValues each, world frame) from mjData's
/// xpos and xquat into out[0 .. kPoseValues * bodies.size()).
void ScenePoses(const mjData& d, const std::vector<int>& bodies, double* out);

}  // namespace vlab::scene
