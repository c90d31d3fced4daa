// The arm servo's own model: what a real arm controller knows of its arm.
//
// A small, private MuJoCo model of the arm alone, generated once from the
// world model's numbers for the arm's own bodies: the bodies that carry the
// arm's joints, plus bodies the configuration names as rigidly attached parts
// the controller's model includes (servo.bodies), plus a declared payload
// welded to the flange (the body of the arm's last joint). Unjointed bodies
// between two of these are folded into the chain transform (their mass is
// left out unless they are named). Everything else in the world (a gripper, a
// ball, a yo-yo, a push) reaches the joints only as a disturbance.
//
// Ports
//   input   the world's joint positions and velocities at the arm's joints
//   output  bias torques h(q, qd) = gravity + Coriolis/centrifugal of the
//           servo model (N·m or N, device joint order); its joint-space
//           inertia diagonal H_ii (kg·m² or kg)
//   cost    per call: one recursive Newton-Euler pass over the servo model's
//           bodies (arm_servo_rne.h); no allocation
// The model is built once (Create); Place() puts its base where the world's
// arm base is (it stays there: a base that moves later is not followed).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include "bridge/bridge_payload.h"
#include "core/core_mujoco.h"
#include "lab/devices/arm_servo_rne.h"

namespace vlab::lab {

/// A load declared at the flange, as a real controller's set-payload takes it.
/// Frame: the body of the arm's last joint (the flange body), at any joint angle.
struct Payload {
  double mass_kg = 0.0;                             ///< kg, >= 0 (0: no payload)
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();  ///< centre of mass in the flange frame, m
  /// Inertia about the centre of mass in flange axes, kg·m²: ixx, iyy, izz,
  /// ixy, ixz, iyz (products of inertia as in MJCF fullinertia).
  std::array<double, 6> inertia_kgm2 = {0, 0, 0, 0, 0, 0};
};

/// Checks that `payload` is a rigid body: finite values, mass >= 0, inertia
/// positive semi-definite with principal moments obeying the triangle
/// inequality. Returns true when it is; else false with `field` set to
/// "mass", "com" or "inertia" and `reason` to why.
bool CheckPayload(const Payload& payload, std::string* field, std::string* reason);

/// The payload as the wire carries it (bridge_payload.h), and back: the same
/// numbers, field by field.
bridge::ArmPayloadMsg PayloadToWire(const Payload& payload);
Payload PayloadFromWire(const bridge::ArmPayloadMsg& payload);

/// The servo's model of its arm (see the file comment).
class ArmServoModel {
 public:
  /// Builds the model from `world`'s arm joints (joint ids, device order; hinge
  /// or slide) and the extra bodies named in `bodies`. Throws InputError
  /// "servo.bodies: ..." for a missing body or one not carried by the arm's
  /// joints, and "servo model: ..." when the arm's bodies hold a joint that is
  /// not an arm joint or the generated model does not compile. No payload yet.
  static std::unique_ptr<ArmServoModel> Create(const mjModel& world, const std::vector<int>& joints,
                                               const std::vector<std::string>& bodies);

  /// Puts each root of the servo model at the world pose its body's parent
  /// frame has in `world_data` (positions computed: after mj_kinematics).
  void Place(const mjData& world_data);

  /// Replaces the payload. Returns false (and keeps the previous one) when
  /// CheckPayload refuses it, with "FIELD: REASON" in `why` if given.
  bool SetPayload(const Payload& payload, std::string* why = nullptr);
  const Payload& payload() const { return payload_; }

  /// Bias torques h(q, qd) of the servo model at the world's arm state, one per
  /// arm joint in device order, into `tau` (size: the number of arm joints).
  void Bias(const mjData& world_data, double* tau);

  /// The same at the arm state the servo reads (`q`, rad or m, and `qd`, one per
  /// arm joint in device order: its encoders' counts, not the world's state).
  void Bias(const double* q, const double* qd, double* tau);

  /// Joint-space inertia diagonal H_ii (armature included) of the servo model at
  /// the world's arm positions, one per arm joint in device order, into `h`.
  void InertiaDiagonal(const mjData& world_data, double* h);

  /// The generated MJCF text (for messages and tests).
  const std::string& xml() const { return xml_; }
  const mjModel& model() const { return *model_; }

 private:
  ArmServoModel() = default;
  // copies the arm's q (and qd) from the world into the servo data
  void CopyState(const mjData& world_data, bool with_velocity);
  // the pass at the servo data's state; the arm joints' torques into tau
  void BiasOfState(double* tau);

  std::string xml_;
  ModelPtr model_;
  DataPtr data_;
  Payload payload_;
  int payload_body_ = -1;
  std::vector<int> world_qpos_adr_, world_dof_adr_;  // per arm joint
  std::vector<int> qpos_adr_, dof_adr_;              // the same joints in the servo model
  // per root of the servo model: its body, its world body's parent, the offset from that parent
  std::vector<int> root_servo_body_, root_world_parent_;
  std::vector<double> root_offset_pos_, root_offset_quat_;
  std::unique_ptr<ChainRne> rne_pass_;  // the bias in one pass (arm_servo_rne.h)
  std::vector<double> rne_;             // nv of the servo model
};

}  // namespace vlab::lab
