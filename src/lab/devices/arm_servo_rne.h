// Bias torques of a small MuJoCo model by one recursive Newton-Euler pass over
// its arrays: h(q, qd) = gravity + Coriolis/centrifugal, what mj_rne with
// flg_acc = 0 gives after mj_kinematics, mj_comPos and mj_comVel, in one pass
// and without the data those fill (for the arm servo's handful of bodies the
// four MuJoCo passes cost about four times as much, mostly mj_kinematics).
//
// Frames: world; twists and spatial accelerations at the world origin
// (Featherstone), wrenches about it. Joints: hinge and slide, several per body
// (applied in order, as MuJoCo does); bodies in MuJoCo's order (parents first).
// Reads body_pos/quat, body_ipos/iquat, mass and inertia at every call, so a
// changed payload or a moved root is taken as is.
#pragma once

#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

namespace vlab::lab {

/// One-pass RNE for a model of hinge and slide joints (see the file comment).
class ChainRne {
 public:
  /// Sizes the scratch for `model`. Throws InputError when it has a joint that
  /// is not a hinge or slide.
  explicit ChainRne(const mjModel& model);

  /// Bias force h(q, qd) of `model` (the one given at construction) at `qpos`,
  /// `qvel` into `qfrc` (nv values, N·m or N). No allocation.
  void Bias(const mjModel& model, const double* qpos, const double* qvel, double* qfrc);

 private:
  struct Body {
    Eigen::Matrix3d rotation;  // body frame in world
    Eigen::Vector3d position;
    Eigen::Vector3d omega, velocity;  // twist at the world origin
    Eigen::Vector3d alpha, accel;     // spatial acceleration at the world origin (gravity as -g)
    Eigen::Vector3d force, moment;    // wrench of its subtree, moment about the world origin
  };
  struct Joint {
    Eigen::Vector3d axis, anchor;  // world
  };
  std::vector<Body> bodies_;
  std::vector<Joint> joints_;
};

}  // namespace vlab::lab
