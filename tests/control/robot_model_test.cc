#include "control/robot_model.h"

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "control/trajectory.h"
#include "control_test_models.h"
#include "mujoco_fixture.h"

namespace vlab::control {
namespace {

using testing::kArm7Xml;

class RobotModelTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModelFromString("arm7.xml", kArm7Xml);
    RobotModel::Config config;
    config.tip_site = "tool";
    robot_ = RobotModel::Create(model_, config);
    WatchData(&robot_->data());
    q_.resize(7);
    q_ << 0.3, 0.5, -0.2, -1.2, 0.4, 0.8, 0.1;
    qd_.resize(7);
    qd_ << 0.7, -0.4, 1.1, 0.5, -0.9, 0.3, 1.4;
  }
  // a full simulation state with the chain at (q, qd), computed by mj_forward
  mjData* SimData(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    mjData* d = MakeData(model_);
    for (int i = 0; i < 7; ++i) {
      d->qpos[robot_->qpos_addresses()[i]] = q[i];
      d->qvel[robot_->dof_addresses()[i]] = qd[i];
    }
    mj_forward(model_, d);
    return d;
  }

  Pose PoseAt(const Eigen::VectorXd& q) {
    robot_->SetState(q, Eigen::VectorXd::Zero(7));
    return robot_->TipPose();
  }
  Eigen::MatrixXd MassAt(const Eigen::VectorXd& q) {
    robot_->SetState(q, Eigen::VectorXd::Zero(7));
    return robot_->MassMatrix();
  }
  // potential energy Σ m·(−g)·x_com over all bodies, J
  double PotentialAt(const Eigen::VectorXd& q) {
    robot_->SetState(q, Eigen::VectorXd::Zero(7));
    double v = 0.0;
    for (int b = 1; b < model_->nbody; ++b) {
      for (int r = 0; r < 3; ++r) {
        v -= model_->body_mass[b] * model_->opt.gravity[r] * robot_->data().xipos[3 * b + r];
      }
    }
    return v;
  }

  const mjModel* model_ = nullptr;
  std::unique_ptr<RobotModel> robot_;
  Eigen::VectorXd q_, qd_;
};

TEST_F(RobotModelTest, ChainStructure) {
  ASSERT_EQ(robot_->dof(), 7);
  const std::vector<std::string> names = {"j1", "j2", "j3", "j4", "j5", "j6", "j7"};
  EXPECT_EQ(robot_->joint_names(), names);
  // the free joint of the box comes first: 7 qpos / 6 dofs before the arm
  EXPECT_EQ(robot_->qpos_addresses().front(), 7);
  EXPECT_EQ(robot_->dof_addresses().front(), 6);
  EXPECT_DOUBLE_EQ(robot_->lower_limits()[1], -2.0);
  EXPECT_DOUBLE_EQ(robot_->upper_limits()[3], 2.5);
  EXPECT_TRUE(std::isinf(robot_->upper_limits()[6]));

  RobotModel::Config sub;
  sub.base_body = "l2";
  sub.tip_site = "tool";
  auto sub_chain = RobotModel::Create(model_, sub);
  EXPECT_EQ(sub_chain->joint_names(), std::vector<std::string>(names.begin() + 2, names.end()));
}

TEST_F(RobotModelTest, JacobianMatchesFiniteDifferencesOfTipPose) {
  robot_->SetState(q_, qd_);
  const Eigen::MatrixXd J = robot_->Jacobian();
  ASSERT_EQ(J.rows(), 6);
  ASSERT_EQ(J.cols(), 7);
  const double h = 1e-6;
  for (int i = 0; i < 7; ++i) {
    Eigen::VectorXd qp = q_, qm = q_;
    qp[i] += h;
    qm[i] -= h;
    const Pose pp = PoseAt(qp), pm = PoseAt(qm);
    const Eigen::Vector3d v_fd = (pp.p_W - pm.p_W) / (2 * h);
    const Eigen::Vector3d w_fd = RotationVector(pp.R_W * pm.R_W.transpose()) / (2 * h);
    EXPECT_LT((J.col(i).head<3>() - v_fd).norm(), 1e-8) << "joint " << i;
    EXPECT_LT((J.col(i).tail<3>() - w_fd).norm(), 1e-8) << "joint " << i;
  }
  // and the tip velocity J·qd equals the velocity of the tip over time
  robot_->SetState(q_, qd_);
  const Eigen::VectorXd twist = J * qd_;
  const Pose a = PoseAt(q_ - h * qd_), b = PoseAt(q_ + h * qd_);
  EXPECT_LT((twist.head<3>() - (b.p_W - a.p_W) / (2 * h)).norm(), 1e-7);
  EXPECT_LT((twist.tail<3>() - RotationVector(b.R_W * a.R_W.transpose()) / (2 * h)).norm(), 1e-7);
}

TEST_F(RobotModelTest, TipPoseMatchesSimulation) {
  mjData* d = SimData(q_, qd_);
  robot_->SetState(q_, qd_);
  const Pose pose = robot_->TipPose();
  const int s = robot_->tip_site_id();
  for (int r = 0; r < 3; ++r) {
    EXPECT_DOUBLE_EQ(pose.p_W[r], d->site_xpos[3 * s + r]);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(pose.R_W(r, c), d->site_xmat[9 * s + 3 * r + c]);
  }
}

TEST_F(RobotModelTest, MassMatrixEqualsFullMSubBlock) {
  mjData* d = SimData(q_, qd_);
  std::vector<mjtNum> full(model_->nv * model_->nv);
  mj_fullM(model_, full.data(), d->qM);
  robot_->SetState(q_, qd_);
  const Eigen::MatrixXd H = robot_->MassMatrix();
  for (int i = 0; i < 7; ++i) {
    for (int j = 0; j < 7; ++j) {
      const int vi = robot_->dof_addresses()[i], vj = robot_->dof_addresses()[j];
      EXPECT_NEAR(H(i, j), full[vi * model_->nv + vj], 1e-12) << i << "," << j;
    }
  }
  // armature is on the diagonal: H − armature is still positive definite and
  // the smallest-inertia last joint carries it
  EXPECT_GT(H(6, 6), model_->dof_armature[robot_->dof_addresses()[6]]);
  EXPECT_LT((H - H.transpose()).norm(), 1e-12);
}

TEST_F(RobotModelTest, GravityEqualsGradientOfPotentialEnergy) {
  robot_->SetState(q_, qd_);
  const Eigen::VectorXd g = robot_->Gravity();
  const double h = 1e-6;
  for (int i = 0; i < 7; ++i) {
    Eigen::VectorXd qp = q_, qm = q_;
    qp[i] += h;
    qm[i] -= h;
    EXPECT_NEAR(g[i], (PotentialAt(qp) - PotentialAt(qm)) / (2 * h), 1e-6) << "joint " << i;
  }
  EXPECT_GT(g.norm(), 1.0);  // not vacuous
}

TEST_F(RobotModelTest, BiasMinusGravityVanishesAtRest) {
  robot_->SetState(q_, Eigen::VectorXd::Zero(7));
  EXPECT_LT((robot_->Bias() - robot_->Gravity()).norm(), 1e-12);
}

// C(q,qd)·qd from the Lagrangian: Ḣ·qd − ½·∂(qdᵀ H qd)/∂q, by finite differences of H
TEST_F(RobotModelTest, BiasEqualsCoriolisFromLagrangianPlusGravity) {
  const double h = 1e-6;
  const Eigen::MatrixXd H_dot = (MassAt(q_ + h * qd_) - MassAt(q_ - h * qd_)) / (2 * h);
  Eigen::VectorXd grad(7);
  for (int i = 0; i < 7; ++i) {
    Eigen::VectorXd qp = q_, qm = q_;
    qp[i] += h;
    qm[i] -= h;
    grad[i] = (qd_.dot(MassAt(qp) * qd_) - qd_.dot(MassAt(qm) * qd_)) / (2 * h);
  }
  const Eigen::VectorXd c_qd = H_dot * qd_ - 0.5 * grad;
  robot_->SetState(q_, qd_);
  const Eigen::VectorXd bias = robot_->Bias();
  const Eigen::VectorXd g = robot_->Gravity();
  EXPECT_LT((bias - g - c_qd).norm(), 1e-6) << (bias - g).transpose() << "\n" << c_qd.transpose();
  EXPECT_GT(c_qd.norm(), 0.1);  // not vacuous
  // Gravity() restores the velocity state: Bias is unchanged after it
  EXPECT_LT((robot_->Bias() - bias).norm(), 1e-14);
}

TEST_F(RobotModelTest, BiasEqualsInverseDynamicsAtZeroAcceleration) {
  mjData* d = SimData(q_, qd_);
  mju_zero(d->qacc, model_->nv);
  mj_inverse(model_, d);
  robot_->SetState(q_, qd_);
  const Eigen::VectorXd bias = robot_->Bias();
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(bias[i], d->qfrc_inverse[robot_->dof_addresses()[i]], 1e-9) << "joint " << i;
  }
}

TEST_F(RobotModelTest, SetStateLeavesCallerDataUntouched) {
  mjData* d = SimData(q_, qd_);
  const std::vector<mjtNum> qpos(d->qpos, d->qpos + model_->nq);
  const std::vector<mjtNum> qvel(d->qvel, d->qvel + model_->nv);
  const std::vector<mjtNum> xpos(d->xpos, d->xpos + 3 * model_->nbody);
  const std::vector<mjtNum> qm(d->qM, d->qM + model_->nM);
  robot_->SetState(*d);
  EXPECT_EQ(robot_->ChainPositions(*d), q_);
  EXPECT_EQ(robot_->ChainVelocities(*d), qd_);
  robot_->SetState(-q_, 2 * qd_);
  robot_->Bias();
  robot_->Gravity();
  robot_->MassMatrix();
  robot_->Jacobian();
  EXPECT_EQ(std::vector<mjtNum>(d->qpos, d->qpos + model_->nq), qpos);
  EXPECT_EQ(std::vector<mjtNum>(d->qvel, d->qvel + model_->nv), qvel);
  EXPECT_EQ(std::vector<mjtNum>(d->xpos, d->xpos + 3 * model_->nbody), xpos);
  EXPECT_EQ(std::vector<mjtNum>(d->qM, d->qM + model_->nM), qm);
  EXPECT_NE(robot_->ChainPositions(robot_->data()), q_);  // the scratch state did change
}

TEST_F(RobotModelTest, SetStateSizeMismatchThrows) {
  try {
    robot_->SetState(Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(7));
    FAIL() << "expected throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dof 7"), std::string::npos) << e.what();
  }
}

TEST_F(RobotModelTest, CreateErrorsNameTheEntity) {
  struct Case {
    const char* base;
    const char* tip;
    const char* message;
  };
  const Case cases[] = {
      {"world", "no_such_site", "no site 'no_such_site'"},
      {"no_such_body", "tool", "no body 'no_such_body'"},
      {"world", "box_site", "joint 'box_free'"},
      {"box", "tool", "body 'box' is not an ancestor of site 'tool'"},
      {"l7", "tool", "no joints between body 'l7'"},
  };
  for (const Case& c : cases) {
    RobotModel::Config config;
    config.base_body = c.base;
    config.tip_site = c.tip;
    try {
      RobotModel::Create(model_, config);
      ADD_FAILURE() << "no throw for " << c.base << " -> " << c.tip;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
  RobotModel::Config config;
  config.tip_site = "tool";
  EXPECT_THROW(RobotModel::Create(nullptr, config), std::invalid_argument);
}

}  // namespace
}  // namespace vlab::control
