#include "models/head_gaze.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

namespace vlab::models::testing {

namespace {

constexpr int kEyeTilt = 4, kLeftPan = 5, kRightPan = 6;  // indices in kHeadJoints

Eigen::Vector3d OpticalAxis(const mjData* d, int camera) {
  const mjtNum* r = d->cam_xmat + 9 * camera;  // row-major; optical axis = -(third column)
  return Eigen::Vector3d(-r[2], -r[5], -r[8]);
}

Eigen::Vector3d Direction(const mjData* d, int camera, const Eigen::Vector3d& target_W) {
  return (target_W - Eigen::Vector3d(d->cam_xpos[3 * camera], d->cam_xpos[3 * camera + 1], d->cam_xpos[3 * camera + 2]))
      .normalized();
}

int JointId(const mjModel* m, const char* name) {
  const int j = mj_name2id(m, mjOBJ_JOINT, name);
  if (j < 0) ADD_FAILURE() << "no joint '" << name << "'";
  return std::max(j, 0);
}

}  // namespace

double GazeError(const mjModel*, const mjData* d, int camera, const Eigen::Vector3d& target_W) {
  const double c = std::clamp(OpticalAxis(d, camera).dot(Direction(d, camera, target_W)), -1.0, 1.0);
  return std::acos(c);
}

GazeSolver::GazeSolver(const mjModel* m) : model_(m), scratch_(mj_makeData(m)) {
  for (const char* name : kHeadJoints) {
    const int j = JointId(m, name);
    qpos_adr_.push_back(m->jnt_qposadr[j]);
    lower_.push_back(m->jnt_range[2 * j]);
    upper_.push_back(m->jnt_range[2 * j + 1]);
  }
  left_camera_ = mj_name2id(m, mjOBJ_CAMERA, "left_eye");
  right_camera_ = mj_name2id(m, mjOBJ_CAMERA, "right_eye");
  if (left_camera_ < 0 || right_camera_ < 0) ADD_FAILURE() << "no cameras left_eye / right_eye";
}

GazeSolver::~GazeSolver() { mj_deleteData(scratch_); }

void GazeSolver::SetHead(const Eigen::VectorXd& q) {
  for (size_t i = 0; i < qpos_adr_.size(); ++i) scratch_->qpos[qpos_adr_[i]] = q[i];
  mj_kinematics(model_, scratch_);
  mj_camlight(model_, scratch_);
}

// optical axis minus target direction, both eyes (6 values)
Eigen::VectorXd GazeSolver::Residual(const Eigen::Vector3d& target_W) {
  Eigen::VectorXd r(6);
  r.head<3>() = OpticalAxis(scratch_, left_camera_) - Direction(scratch_, left_camera_, target_W);
  r.tail<3>() = OpticalAxis(scratch_, right_camera_) - Direction(scratch_, right_camera_, target_W);
  return r;
}

Eigen::VectorXd GazeSolver::Solve(const Eigen::VectorXd& q_in, const Eigen::Vector3d& target_W, double* error_rad) {
  constexpr int kEyes[3] = {kEyeTilt, kLeftPan, kRightPan};
  constexpr double kStep = 1e-6;
  Eigen::VectorXd q = q_in;
  for (int iteration = 0; iteration < 20; ++iteration) {
    SetHead(q);
    const Eigen::VectorXd r = Residual(target_W);
    if (r.norm() < 1e-10) break;
    Eigen::Matrix<double, 6, 3> jac;
    for (int k = 0; k < 3; ++k) {
      Eigen::VectorXd qk = q;
      qk[kEyes[k]] += kStep;
      SetHead(qk);
      jac.col(k) = (Residual(target_W) - r) / kStep;
    }
    const Eigen::Vector3d step = (jac.transpose() * jac).ldlt().solve(-jac.transpose() * r);
    for (int k = 0; k < 3; ++k) {
      const int i = kEyes[k];
      q[i] = std::clamp(q[i] + step[k], lower_[i], upper_[i]);
    }
  }
  SetHead(q);
  *error_rad = std::max(GazeError(model_, scratch_, left_camera_, target_W),
                        GazeError(model_, scratch_, right_camera_, target_W));
  return q;
}

HeadServo::HeadServo(const mjModel* m, const mjData& d, double bandwidth_hz) : model_(m) {
  const double w = 2 * M_PI * bandwidth_hz;
  kp_.resize(kHeadJoints.size());
  kd_.resize(kHeadJoints.size());
  for (size_t i = 0; i < kHeadJoints.size(); ++i) {
    const int j = JointId(m, kHeadJoints[i]);
    qpos_adr_.push_back(m->jnt_qposadr[j]);
    dof_adr_.push_back(m->jnt_dofadr[j]);
    const int a = mj_name2id(m, mjOBJ_ACTUATOR, kHeadJoints[i]);
    if (a < 0) ADD_FAILURE() << "no motor '" << kHeadJoints[i] << "'";
    actuators_.push_back(std::max(a, 0));
    const double inertia = d.qM[m->dof_Madr[dof_adr_[i]]];
    kp_[i] = inertia * w * w;
    kd_[i] = 2 * inertia * w;
  }
}

Eigen::VectorXd HeadServo::Positions(const mjData& d) const {
  Eigen::VectorXd q(dof());
  for (int i = 0; i < dof(); ++i) q[i] = d.qpos[qpos_adr_[i]];
  return q;
}

void HeadServo::Actuate(const Eigen::VectorXd& q_ref, const Eigen::VectorXd& qd_ref, mjData& d) const {
  for (int i = 0; i < dof(); ++i) {
    const int v = dof_adr_[i], a = actuators_[i];
    const double tau = kp_[i] * (q_ref[i] - d.qpos[qpos_adr_[i]]) + kd_[i] * (qd_ref[i] - d.qvel[v]) + d.qfrc_bias[v];
    d.ctrl[a] = std::clamp(tau, model_->actuator_ctrlrange[2 * a], model_->actuator_ctrlrange[2 * a + 1]);
  }
}

}  // namespace vlab::models::testing
