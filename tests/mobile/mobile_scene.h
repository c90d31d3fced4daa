// The small helpers the mobile-manipulation tests share (their scenes load with the
// MuJoCo fixture, tests/mujoco_fixture.h): placing weld-mounted bodies, element ids
// that must exist, and a joint-space hold/track servo for the PA10 built from
// src/control (RobotModel + JointPdGravityTorque).
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "control/joint_pd.h"
#include "control/robot_model.h"
#include "control/task_space.h"
#include "mujoco_fixture.h"

namespace vlab::testing {

inline constexpr double kPi = 3.14159265358979323846;

/// Id of a named element; the test fails (and -1 comes back) when it is missing.
inline int RequireId(const mjModel* m, mjtObj type, const std::string& name) {
  const int id = mj_name2id(m, type, name.c_str());
  EXPECT_GE(id, 0) << "no element '" << name << "' of type " << type;
  return id;
}

inline Eigen::Vector3d Vec3(const mjtNum* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }
inline Eigen::Matrix3d Mat3(const mjtNum* xmat) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = xmat[3 * i + j];
  }
  return r;
}

/// Rotation angle (rad) between two rotation matrices.
inline double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

/// Sum of the masses of a body and all its descendants, kg.
inline double SubtreeMass(const mjModel* m, int body) {
  double mass = 0;
  for (int b = 0; b < m->nbody; ++b) {
    for (int a = b; a > 0; a = m->body_parentid[a]) {
      if (a == body) {
        mass += m->body_mass[b];
        break;
      }
    }
  }
  return mass;
}

/// Puts every body that an active weld equality attaches to another body, and that
/// moves on a free joint of its own, at its welded pose (eq_data relpose: position
/// then quaternion of body2 in body1's frame) with the velocity of the point of body1
/// it sits on; then runs mj_forward. This is what must follow any change of the arm's
/// joints in scenes/pa10_gripper.xml.
inline void PlaceWeldedBodies(const mjModel* m, mjData* d) {
  mj_forward(m, d);
  for (int e = 0; e < m->neq; ++e) {
    if (m->eq_type[e] != mjEQ_WELD || !m->eq_active[e]) continue;
    const int b1 = m->eq_obj1id[e], b2 = m->eq_obj2id[e];
    if (m->body_jntnum[b2] != 1 || m->jnt_type[m->body_jntadr[b2]] != mjJNT_FREE) continue;
    const mjtNum* relpose = m->eq_data + mjNEQDATA * e + 3;
    mjtNum pos[3], quat[4];
    mju_rotVecMat(pos, relpose, d->xmat + 9 * b1);
    mju_addTo3(pos, d->xpos + 3 * b1);
    mju_mulQuat(quat, d->xquat + 4 * b1, relpose + 3);
    const int jnt = m->body_jntadr[b2];
    mju_copy3(d->qpos + m->jnt_qposadr[jnt], pos);
    mju_copy4(d->qpos + m->jnt_qposadr[jnt] + 3, quat);
    // velocity of body1 at the welded point: free joint qvel = (linear in world, angular in body frame)
    mjtNum vel[6];
    mj_objectVelocity(m, d, mjOBJ_XBODY, b1, vel, 0);  // (angular, linear) at body1's origin, world frame
    mjtNum r[3], wxr[3];
    mju_sub3(r, pos, d->xpos + 3 * b1);
    mju_cross(wxr, vel, r);
    mjtNum* qvel = d->qvel + m->jnt_dofadr[jnt];
    mju_add3(qvel, vel + 3, wxr);
    mjtNum R2[9];
    mju_quat2Mat(R2, quat);
    mju_mulMatTVec(qvel + 3, R2, vel, 3, 3);
  }
  mj_forward(m, d);
}

/// Inverse kinematics by integrating the task-space controller's joint velocity
/// (kinematically, on the chain model only) from `q_seed` until the tip pose error
/// is below 1e-9 m / 1e-9 rad; the test fails if it does not converge.
inline Eigen::VectorXd SolvePose(control::RobotModel& model, const Eigen::VectorXd& q_seed,
                                 const control::Pose& target) {
  control::TaskSpaceConfig config;
  config.k_null = 0.5;
  config.damping = 1e-7;  // exact task (away from singularities), posture in the null space
  config.q_rest = q_seed;
  auto controller = control::TaskSpaceController::Create(config, model);
  control::TaskSpaceTarget goal;
  goal.pose = target;
  Eigen::VectorXd q = q_seed;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.size());
  double error = 1;
  for (int i = 0; i < 5000 && error > 1e-9; ++i) {
    model.SetState(q, zero);
    const control::TaskSpaceOutput& out = controller->Update(model, q, goal);
    error = std::max(out.position_error_m, out.orientation_error_rad);
    q += out.qd_cmd * 0.02;
  }
  EXPECT_LT(error, 1e-9) << "inverse kinematics did not converge";
  return q;
}

/// Tool pointing straight down as in the PA10's ready pose (tool z = world -z, tool y =
/// world y, tool x = world -x).
inline Eigen::Matrix3d ToolDown() { return Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitY()).toRotationMatrix(); }

/// Joint-space servo of the PA10 chain from `base_body` to `tip_site`:
///   tau = kp (q_d - q) + kd (qd_d - qd) + h(q, qd) + H(q) qdd_d + extra,
/// gains from the inertia at the pose it is created in: kp = H_ii w^2,
/// kd = 2 zeta H_ii w. h is RobotModel's bias: gravity and Coriolis forces with the
/// whole model's velocities, a moving base's included. The motors must carry the
/// joints' names (as in mjcf/pa10/pa10_actuators.xml).
class ArmServo {
 public:
  ArmServo(const mjModel* m, const mjData& d, const std::string& base_body, const std::string& tip_site,
           double bandwidth_hz, double zeta) {
    model_ = control::RobotModel::Create(m, {base_body, tip_site});
    model_->SetState(d);
    const Eigen::MatrixXd H = model_->MassMatrix();
    const int n = model_->dof();
    const double w = 2 * kPi * bandwidth_hz;
    gains_.kp = H.diagonal() * w * w;
    gains_.kd = H.diagonal() * 2 * zeta * w;
    h_.resize(n);
    tau_.resize(n);
    extra_ = Eigen::VectorXd::Zero(n);
    for (const std::string& joint : model_->joint_names()) {
      actuators_.push_back(RequireId(m, mjOBJ_ACTUATOR, joint));
    }
  }

  control::RobotModel& model() { return *model_; }
  int dof() const { return model_->dof(); }
  /// Extra feed-forward torque added to the next commands (chain order), N m.
  Eigen::VectorXd& extra_feedforward() { return extra_; }

  /// Writes the servo torques into d->ctrl of the motors named like the chain's joints.
  void Command(mjData* d, const Eigen::VectorXd& q_d, const Eigen::VectorXd& qd_d, const Eigen::VectorXd& qdd_d) {
    model_->SetState(*d);
    const Eigen::VectorXd q = model_->ChainPositions(*d);
    const Eigen::VectorXd qd = model_->ChainVelocities(*d);
    model_->Bias(&h_);
    if (qdd_d.size() > 0) h_ += model_->MassMatrix() * qdd_d;
    h_ += extra_;
    control::JointPdGravityTorque(gains_, q, qd, q_d, qd_d, h_, &tau_);
    for (int i = 0; i < dof(); ++i) d->ctrl[actuators_[i]] = tau_[i];
  }

 private:
  std::unique_ptr<control::RobotModel> model_;
  control::JointPdGains gains_;
  Eigen::VectorXd h_, tau_, extra_;
  std::vector<int> actuators_;
};

}  // namespace vlab::testing
