// Bias torques of a small MuJoCo model by one recursive Newton-Euler pass over
// its arrays: h(q, qd) = gravity + Coriolis/centrifugal, what mj_rne with
// flg_acc = 0 gives after mj_kinematics, mj_comPos and mj_comVel, in one pass
// and without the data those fill (for the arm servo's handful of bodies the
// four MuJoCo passes cost about four times as much, mostly mj_kinematics).
//
// Frames: world; twists and spatial accelerations at the world origin
// (Featherstone), wrenches about it. Joints: hinge and slide, several per body
// (applied in order, as MuJoCo does); bodies in MuJoCo's order (parents first).
// The model's constant arrays (body_pos/quat, body_ipos/iquat, mass, inertia,
// joint axes and anchors) are read once, by the constructor and by Refresh:
// whoever changes them (a new payload, a moved root) calls Refresh.
//
// A chain whose every body has at most one joint, a hinge at the body's origin
// (the PA10, the HOAP-3, the head), takes a faster pass in the bodies' own
// frames (Luh, Walker and Paul's recursion): a hinge about a frame axis turns
// two columns, and each body's inertia about its centre of mass is a constant
// 3x3 in its frame. It gives the same torques to rounding.
#pragma once

#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

namespace vlab::lab {

/// One-pass RNE for a model of hinge and slide joints (see the file comment).
class ChainRne {
 public:
  /// Sizes the scratch for `model` and reads its constants (Refresh). Throws
  /// InputError when it has a joint that is not a hinge or slide.
  explicit ChainRne(const mjModel& model);

  /// Reads `model`'s body and joint constants again (the model given at
  /// construction, after its arrays changed). No allocation.
  void Refresh(const mjModel& model);

  /// Bias force h(q, qd) of `model` (the one given at construction, as of the
  /// last Refresh) at `qpos`, `qvel` into `qfrc` (nv values, N·m or N). No
  /// allocation.
  void Bias(const mjModel& model, const double* qpos, const double* qvel, double* qfrc);

  /// Whether Bias takes the pass in the bodies' frames (see the file comment).
  bool local() const { return local_; }
  /// The general pass (world-origin twists), whatever the chain: Bias's
  /// answer for a chain that cannot take the local pass; tests compare the two.
  void BiasWorld(const mjModel& model, const double* qpos, const double* qvel, double* qfrc);

 private:
  void BiasLocal(const mjModel& model, const double* qpos, const double* qvel, double* qfrc);

  struct Body {
    // constants (Refresh)
    int parent = 0;
    Eigen::Matrix3d inertia_com;        // about the centre of mass, body axes (the local pass)
    int axis_index = -1;                // the local pass: its hinge is about body axis 0, 1 or 2; -1 other or none
    int joint = -1;                     // the local pass: its hinge (-1: welded to its parent)
    Eigen::Matrix3d offset_rotation;    // body_quat: the frame in its parent's, before the joints
    Eigen::Vector3d offset;             // body_pos
    Eigen::Matrix3d inertial_rotation;  // body_iquat
    Eigen::Vector3d inertial_pos;       // body_ipos
    Eigen::Vector3d principal;          // body_inertia
    double mass = 0.0;
    bool offset_is_identity = false;
    // per call
    Eigen::Matrix3d rotation;  // body frame in world
    Eigen::Vector3d position;
    Eigen::Vector3d omega, velocity;  // twist at the world origin
    Eigen::Vector3d alpha, accel;     // spatial acceleration at the world origin (gravity as -g)
    Eigen::Vector3d force, moment;    // wrench of its subtree, moment about the world origin
  };
  struct Joint {
    // constants (Refresh)
    Eigen::Vector3d local_axis, local_pos;
    bool hinge = true;
    int qpos_adr = 0, dof_adr = 0;
    double qpos0 = 0.0;
    // per call
    Eigen::Vector3d axis, anchor;  // world
  };
  std::vector<Body> bodies_;
  std::vector<Joint> joints_;
  bool local_ = false;                          // every body: at most one joint, a hinge at its origin
  std::vector<int> first_joint_, joint_count_;  // per body
  Eigen::Vector3d gravity_accel_;               // the world's acceleration: -g, or 0 without gravity
};

}  // namespace vlab::lab
