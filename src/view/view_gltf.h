// `vlab export`: a recorded run (scene.json + poses.bin, lab_poses.h) as a
// glTF 2.0 binary (.glb) that Blender and three.js import: one node per body
// with its geoms as child nodes (boxes, spheres, ellipsoids, cylinders,
// capsules and planes triangulated here, meshes from the MJCF), the world's
// geoms static, one animation with a translation and a rotation channel per
// body (LINEAR, one key per recorded frame), and from the MJCF its textures,
// cameras and lights. What maps how:
//
// - Materials: baseColorFactor = the geom's rgba (its material's), metallic
//   0, roughness 0.8; alpha < 1 blends; planes are double-sided.
// - Textures (images: PNG in the GLB's binary chunk, MuJoCo's RGB pixels):
//   a 2-D texture on a plane or a primitive gets the texture coordinates
//   MuJoCo 2.2.2's renderer generates (texrepeat over the geom's size, or per
//   metre with texuniform; the sampler repeats), so a floor's checker has its
//   squares where MuJoCo draws them, without KHR_texture_transform. A cube
//   texture on a box: each face of the box shows its face image (+x, -x, +y,
//   -y, +z, -z: fileright, fileleft, fileup, filedown, filefront, fileback)
//   the way OpenGL's cube map lays it there (mjcf/cubes/README.md's table),
//   clamped at the edges. Not textured (rgba only): meshes, and cube
//   textures on anything but a box (MuJoCo looks those up per pixel).
// - Cameras: every MJCF camera as a perspective camera (yfov = fovy, znear
//   and zfar from <visual><map> times the model's extent; no aspect ratio:
//   the viewport's) on its body's node with the camera's pose in the body
//   (MuJoCo's camera frame looks along -z with +y up, as glTF's does).
//   Tracking modes are not followed: each camera stays where it is in its
//   body (at qpos0 for one welded to the world or to a recorded body).
// - Lights (KHR_lights_punctual, active lights only): directional ->
//   directional; a spot (MuJoCo's other lights) with a cutoff under 90 deg ->
//   spot with outerConeAngle = cutoff, innerConeAngle 0; cutoff 90 deg or
//   more -> point. color = diffuse / max(diffuse), intensity = max(diffuse)
//   (MuJoCo's unitless OpenGL scale; attenuation, exponent, ambient and
//   specular are not carried). The light shines along the node's -z, turned
//   onto the MJCF's dir. MuJoCo's headlight (it follows the viewer's camera)
//   is not exported.
// - A camera or light on a body that moves but is neither recorded nor welded
//   to a recorded body is left out (GltfSummary::left_out).
//
// The bytes depend only on the recording and the MJCF: the same run exports
// to the same file.
#pragma once

#include <string>

namespace vlab::view {

struct GltfSummary {
  int bodies = 0;
  int geoms = 0;
  long frames = 0;
  double duration_s = 0;  ///< last frame's time minus the first's
  long bytes = 0;         ///< of the .glb
  int textures = 0;       ///< glTF textures (a cube texture on a box: one per face)
  int cameras = 0;
  int lights = 0;
  int left_out = 0;  ///< cameras and lights on bodies the recording does not carry
};

/// Writes `run_dir`'s recording to `glb_path` (through a temporary file:
/// nothing half-written). `model`: the MJCF for meshes, textures, cameras
/// and lights ("": the one scene.json names; a scene without meshes or
/// textures needs none, and without it has no cameras or lights). Throws InputError naming the file
/// for a missing or malformed recording, an existing `glb_path` (never
/// overwritten), a mesh or texture without its model, or a model whose bodies
/// are not the recording's.
GltfSummary ExportGltf(const std::string& run_dir, const std::string& glb_path, const std::string& model);

}  // namespace vlab::view
