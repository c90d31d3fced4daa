// What `vlab view` takes from the MJCF it draws: mesh vertices and faces,
// texture pixels, cameras, lights, and the poses of an arm's bodies from its joint
// angles (MuJoCo kinematics); and the binary pose frame the page reads.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json_fwd.hpp>

namespace vlab::view {

/// Bytes of one pose frame, as the page reads it (little-endian):
///   float64 time (s), float64 seq, then float32 x, y, z, qw, qx, qy, qz of
///   every streamed body, world frame.
inline constexpr int kFrameHeaderBytes = 16;
std::string EncodeFrame(double time, double seq, const double* poses, int values);

class ViewModel {
 public:
  /// Loads the MJCF at `path`; throws InputError naming it.
  static std::unique_ptr<ViewModel> Load(const std::string& path);
  ~ViewModel();
  const mjModel* model() const { return m_; }

  /// /mesh/ID: uint32 vertex count, uint32 face count, float32 x, y, z per
  /// vertex (mesh frame, m), uint32 three vertex indices per face. False for
  /// an id that is not a mesh.
  bool MeshBytes(int id, std::string* out) const;
  /// /tex/ID: the texture's pixels as PNG (a cube texture: its six faces
  /// stacked, +x, -x, +y, -y, +z, -z). False for an id that is not a texture.
  bool TexturePng(int id, std::string* out) const;
  /// The MJCF cameras fixed in the world: name, pos, quat (MuJoCo camera
  /// frame: looking along -z, +y up), fovy (deg).
  nlohmann::json Cameras() const;
  /// The MJCF's active lights fixed in the world: name, pos, dir (world
  /// frame), directional, castshadow, diffuse (rgb), cutoff (deg).
  nlohmann::json Lights() const;

  /// The arm's joints by name (joint names from its describe reply); throws
  /// InputError naming the first joint the model lacks or one that is not a
  /// hinge or slide joint.
  void BindJoints(const std::vector<std::string>& names);
  /// Sets the bound joints to q, runs mj_kinematics and writes the poses of
  /// `bodies` (SceneBodies order) into out.
  void ArmPoses(const std::vector<double>& q, const std::vector<int>& bodies, double* out);

 private:
  ViewModel() = default;
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::vector<int> qpos_adr_;
};

}  // namespace vlab::view
