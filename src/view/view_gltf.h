// `vlab export`: a recorded run (scene.json + poses.bin, lab_poses.h) as a
// glTF 2.0 binary (.glb) that Blender and three.js import: one node per body
// with its geoms as child nodes (boxes, spheres, ellipsoids, cylinders,
// capsules and planes triangulated here, meshes from the MJCF), a material per
// geom from its rgba (textures are not exported), the world's geoms static,
// and one animation with a translation and a rotation channel per body
// (LINEAR, one key per recorded frame).
#pragma once

#include <string>

namespace vlab::view {

struct GltfSummary {
  int bodies = 0;
  int geoms = 0;
  long frames = 0;
  double duration_s = 0;  ///< last frame's time minus the first's
  long bytes = 0;         ///< of the .glb
};

/// Writes `run_dir`'s recording to `glb_path` (through a temporary file:
/// nothing half-written). `model`: the MJCF for meshes ("": the one
/// scene.json names; a scene without meshes needs none). Throws InputError
/// naming the file for a missing or malformed recording, an existing
/// `glb_path` (never overwritten) or a mesh without its model.
GltfSummary ExportGltf(const std::string& run_dir, const std::string& glb_path, const std::string& model);

}  // namespace vlab::view
