// PA10-7C kinematics of scenes/pa10.xml against the published DH table.
//
// RobotModel (MuJoCo's kinematics of the MJCF body tree, base `world`, tip site
// `flange`) is compared with an independent standard-DH product written here from
// DATASHEET 1.2, variant A (MBDyn tests/invdyn/pa10, Fumagalli et al. 2007):
//   d = [0.315, 0, 0.450, 0, 0.500, 0, 0.080] m, a = 0,
//   alpha = [-90, +90, -90, +90, -90, +90, 0] deg.
// Joint mapping, theta_i = sign_i * q_i + offset_i with sign = +1 and offset = 0 for
// all seven joints: the MJCF turns roll joints about z and pitch joints about +y, and
// with alpha_1 = -90 deg the DH z_1 axis is R_z(theta_1)·(+y), i.e. the S2 axis, and
// R_x(-90)·R_z(theta)·R_x(+90) = R_y(theta), so each DH pitch step is exactly the
// MJCF y-hinge; in the zero pose every even DH frame and the flange are parallel to
// the base frame. The DH frame 0 is the pa10_base frame (floor plane, z up), and the
// DH frame 7 is the flange site frame.
//
// Also checked: the Jacobian against central differences of TipPose and against the
// DH geometric Jacobian, the zero-pose flange height (1.345 m above the base plane),
// and the joint limits (MHI data, DATASHEET 1.4).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

#include "control/robot_model.h"
#include "mujoco_fixture.h"

namespace vlab::control {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr int kDof = 7;

// standard DH, variant A (DATASHEET 1.2)
constexpr double kD[kDof] = {0.315, 0.0, 0.450, 0.0, 0.500, 0.0, 0.080};
constexpr double kA[kDof] = {0, 0, 0, 0, 0, 0, 0};
constexpr double kAlpha[kDof] = {-90 * kDeg, 90 * kDeg, -90 * kDeg, 90 * kDeg, -90 * kDeg, 90 * kDeg, 0.0};
// theta_i = kSign[i] * q_i + kOffset[i] (see the file comment)
constexpr double kSign[kDof] = {1, 1, 1, 1, 1, 1, 1};
constexpr double kOffset[kDof] = {0, 0, 0, 0, 0, 0, 0};
// MHI joint limits, deg (DATASHEET 1.4)
constexpr double kLimitDeg[kDof] = {177, 94, 174, 137, 255, 165, 255};

// A_i = Rz(theta) Tz(d) Tx(a) Rx(alpha)
Eigen::Isometry3d DhStep(double theta, double d, double a, double alpha) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.rotate(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()));
  t.translate(Eigen::Vector3d(a, 0, d));  // Tz(d) and Tx(a) commute
  t.rotate(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()));
  return t;
}

// frames[i] = pose of DH frame i in the base frame, i = 0..7
std::vector<Eigen::Isometry3d> DhFrames(const Eigen::VectorXd& q) {
  std::vector<Eigen::Isometry3d> frames{Eigen::Isometry3d::Identity()};
  for (int i = 0; i < kDof; ++i) {
    const double theta = kSign[i] * q[i] + kOffset[i];
    frames.push_back(frames.back() * DhStep(theta, kD[i], kA[i], kAlpha[i]));
  }
  return frames;
}

// geometric Jacobian of DH frame 7 (columns z_{i-1} x (p - o_{i-1}); z_{i-1}), times dtheta/dq
Eigen::MatrixXd DhJacobian(const Eigen::VectorXd& q) {
  const auto f = DhFrames(q);
  const Eigen::Vector3d p = f[kDof].translation();
  Eigen::MatrixXd j(6, kDof);
  for (int i = 0; i < kDof; ++i) {
    const Eigen::Vector3d z = f[i].linear().col(2);
    j.block<3, 1>(0, i) = kSign[i] * z.cross(p - f[i].translation());
    j.block<3, 1>(3, i) = kSign[i] * z;
  }
  return j;
}

Eigen::VectorXd RandomConfiguration(const RobotModel& rm, std::mt19937& rng) {
  Eigen::VectorXd q(rm.dof());
  for (int i = 0; i < rm.dof(); ++i) {
    std::uniform_real_distribution<double> u(rm.lower_limits()[i], rm.upper_limits()[i]);
    q[i] = u(rng);
  }
  return q;
}

class Pa10Kinematics : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/pa10.xml");
    robot_ = RobotModel::Create(model_, {"world", "flange"});
    WatchData(&robot_->data());
    ASSERT_EQ(robot_->dof(), kDof);
    // base frame in the world, from the scene's placement of pa10_base (fixed body)
    const int base = mj_name2id(model_, mjOBJ_BODY, "pa10_base");
    ASSERT_GE(base, 0);
    ASSERT_EQ(model_->body_parentid[base], 0) << "scene mounts pa10_base on the world";
    const double* p = model_->body_pos + 3 * base;
    const double* w = model_->body_quat + 4 * base;
    X_W_base_ = Eigen::Translation3d(p[0], p[1], p[2]) * Eigen::Quaterniond(w[0], w[1], w[2], w[3]);
  }

  Pose Tip(const Eigen::VectorXd& q) {
    robot_->SetState(q, Eigen::VectorXd::Zero(kDof));
    return robot_->TipPose();
  }

  const mjModel* model_ = nullptr;
  std::unique_ptr<RobotModel> robot_;
  Eigen::Isometry3d X_W_base_;
};

TEST_F(Pa10Kinematics, JointNamesAndLimitsAreTheMhiData) {
  const std::vector<std::string> names = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
  EXPECT_EQ(robot_->joint_names(), names);
  for (int i = 0; i < kDof; ++i) {
    EXPECT_NEAR(robot_->lower_limits()[i], -kLimitDeg[i] * kDeg, 1e-12) << names[i];
    EXPECT_NEAR(robot_->upper_limits()[i], kLimitDeg[i] * kDeg, 1e-12) << names[i];
  }
}

TEST_F(Pa10Kinematics, ZeroPoseFlangeIsStraightUpAt1345mm) {
  // base frame: the pa10_base body frame, on the mounting (floor) plane, z up
  const Pose tip = Tip(Eigen::VectorXd::Zero(kDof));
  const Eigen::Vector3d p_base = X_W_base_.inverse() * tip.p_W;
  const Eigen::Matrix3d R_base = X_W_base_.linear().transpose() * tip.R_W;
  EXPECT_NEAR((p_base - Eigen::Vector3d(0, 0, 0.315 + 0.450 + 0.500 + 0.080)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((R_base - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  // this scene puts the base on the floor at the world origin
  EXPECT_NEAR((tip.p_W - Eigen::Vector3d(0, 0, 1.345)).norm(), 0.0, 1e-12);
}

TEST_F(Pa10Kinematics, ForwardKinematicsEqualsDhTable) {
  std::mt19937 rng(20240601);
  double worst_p = 0, worst_r = 0;
  for (int k = 0; k < 100; ++k) {
    const Eigen::VectorXd q = RandomConfiguration(*robot_, rng);
    const Pose tip = Tip(q);
    const Eigen::Isometry3d X_W_dh = X_W_base_ * DhFrames(q)[kDof];
    const double err_p = (tip.p_W - X_W_dh.translation()).norm();
    const double err_r = (tip.R_W - X_W_dh.linear()).cwiseAbs().maxCoeff();
    worst_p = std::max(worst_p, err_p);
    worst_r = std::max(worst_r, err_r);
    ASSERT_LT(err_p, 1e-9) << "position, configuration " << k << ": " << q.transpose();
    ASSERT_LT(err_r, 1e-9) << "rotation, configuration " << k << ": " << q.transpose();
  }
  std::cout << "FK vs DH: worst position error " << worst_p << " m, rotation " << worst_r << "\n";
}

TEST_F(Pa10Kinematics, JacobianMatchesFiniteDifferencesAndDh) {
  std::mt19937 rng(7);
  const double h = 1e-6;
  for (int k = 0; k < 20; ++k) {
    const Eigen::VectorXd q = RandomConfiguration(*robot_, rng);
    robot_->SetState(q, Eigen::VectorXd::Zero(kDof));
    const Eigen::MatrixXd J = robot_->Jacobian();
    ASSERT_EQ(J.rows(), 6);
    ASSERT_EQ(J.cols(), kDof);
    Eigen::MatrixXd J_fd(6, kDof);
    for (int i = 0; i < kDof; ++i) {
      Eigen::VectorXd qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      const Pose tp = Tip(qp), tm = Tip(qm);
      J_fd.block<3, 1>(0, i) = (tp.p_W - tm.p_W) / (2 * h);
      // angular velocity: log(R+ R-^T) / 2h, both rotations in the world frame
      const Eigen::AngleAxisd aa(Eigen::Matrix3d(tp.R_W * tm.R_W.transpose()));
      J_fd.block<3, 1>(3, i) = aa.angle() * aa.axis() / (2 * h);
    }
    // central differences: truncation O(h^2) ~ 1e-12, round-off ~ 1e-16 / h ~ 1e-10
    EXPECT_LT((J.topRows(3) - J_fd.topRows(3)).cwiseAbs().maxCoeff(), 1e-7) << "linear rows, k=" << k;
    EXPECT_LT((J.bottomRows(3) - J_fd.bottomRows(3)).cwiseAbs().maxCoeff(), 1e-7) << "angular rows, k=" << k;

    // geometric Jacobian of the DH chain, rotated from the base into the world frame
    Eigen::MatrixXd J_dh = DhJacobian(q);
    J_dh.topRows(3) = X_W_base_.linear() * J_dh.topRows(3);
    J_dh.bottomRows(3) = X_W_base_.linear() * J_dh.bottomRows(3);
    EXPECT_LT((J - J_dh).cwiseAbs().maxCoeff(), 1e-9) << "k=" << k;
  }
}

}  // namespace
}  // namespace vlab::control
