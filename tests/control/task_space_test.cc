#include "control/task_space.h"

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "control/trajectory.h"
#include "control_test_models.h"
#include "mujoco_fixture.h"

// Counts heap allocations (malloc is what Eigen and operator new end in) while
// g_count_allocations is set; forwards to glibc's allocator.
namespace {
std::atomic<bool> g_count_allocations{false};
std::atomic<long> g_allocations{0};
}  // namespace
extern "C" void* __libc_malloc(size_t size);
extern "C" void* malloc(size_t size) {
  if (g_count_allocations.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_malloc(size);
}

namespace vlab::control {
namespace {

using testing::kPi;
using testing::Rot;
using Vector6d = Eigen::Matrix<double, 6, 1>;

class TaskSpaceTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModelFromString("arm7.xml", testing::kArm7Xml);
    RobotModel::Config config;
    config.tip_site = "tool";
    robot_ = RobotModel::Create(model_, config);
    WatchData(&robot_->data());
    q_start_.resize(7);
    q_start_ << 0.3, 0.5, -0.2, -1.2, 0.4, 0.8, 0.1;
    q_goal_.resize(7);
    q_goal_ << 0.6, 0.2, 0.3, -0.9, -0.3, 1.1, 0.5;
  }

  Pose PoseAt(const Eigen::VectorXd& q) {
    robot_->SetState(q, Eigen::VectorXd::Zero(q.size()));
    return robot_->TipPose();
  }
  // one kinematic Euler step q ← q + q̇_cmd·dt
  const TaskSpaceOutput& Step(TaskSpaceController& c, Eigen::VectorXd& q, const TaskSpaceTarget& target, double dt) {
    robot_->SetState(q, Eigen::VectorXd::Zero(q.size()));
    const TaskSpaceOutput& out = c.Update(*robot_, q, target);
    q += dt * out.qd_cmd;
    return out;
  }

  // maximum tracking error |e| (6-vector norm) following `traj` from q0 with
  // kinematic steps of dt, with or without the trajectory's twist fed forward
  double TrackingError(const CartesianTrajectory& traj, const Eigen::VectorXd& q0, double dt, bool feed_forward) {
    auto c = TaskSpaceController::Create(TaskSpaceConfig{}, *robot_);
    Eigen::VectorXd q = q0;
    double worst = 0.0;
    const int steps = static_cast<int>(std::lround(1.2 / dt));
    for (int k = 0; k <= steps; ++k) {
      const CartesianSample s = traj.Evaluate(k * dt);
      TaskSpaceTarget target;
      target.pose = s.pose;
      if (feed_forward) {
        target.v_W = s.v_W;
        target.w_W = s.w_W;
      }
      worst = std::max(worst, Step(*c, q, target, dt).error_W.norm());
    }
    return worst;
  }

  const mjModel* model_ = nullptr;
  std::unique_ptr<RobotModel> robot_;
  Eigen::VectorXd q_start_, q_goal_;
};

TEST(OrientationErrorTest, RotationVectorOfRdRtIncludingLargeAngles) {
  const Eigen::Matrix3d R = Rot(0.7, {0.3, -1, 0.2});
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -0.5).normalized();
  for (double deg : {0.0, 1e-6, 10.0, 90.0, 179.0, 179.9}) {
    const double angle = deg * kPi / 180.0;
    const Eigen::Vector3d e = OrientationError(Rot(angle, axis) * R, R);
    EXPECT_LT((e - angle * axis).norm(), 1e-9) << deg << " deg";
    // rotating R about e by |e| reaches R_d
    EXPECT_LT((Rot(angle, axis) * R - Eigen::AngleAxisd(e.norm(), axis) * R).norm(), 1e-9);
  }
  // past 180° the short way is about the opposite axis
  const Eigen::Vector3d e = OrientationError(Rot(181.0 * kPi / 180.0, axis) * R, R);
  EXPECT_LT((e + 179.0 * kPi / 180.0 * axis).norm(), 1e-9);
}

TEST(DampedPseudoInverseTest, NullSpaceProjectorDoesNotMoveTask) {
  Eigen::MatrixXd J(6, 7);
  J << 0.1, 0.5, -0.3, 0.2, 0.0, 0.4, 0.1,  //
      0.3, -0.2, 0.6, 0.1, 0.2, -0.1, 0.0,  //
      -0.4, 0.1, 0.2, 0.5, -0.3, 0.2, 0.1,  //
      0.0, 1.0, 0.0, 0.7, 0.1, 0.0, 0.3,    //
      0.0, 0.0, 1.0, 0.0, 0.7, 0.2, -0.6,   //
      1.0, 0.0, 0.0, 0.1, 0.0, 0.9, 0.7;
  const Eigen::MatrixXd Jp = DampedPseudoInverse(J, 0.0);
  EXPECT_LT((J * Jp - Eigen::MatrixXd::Identity(6, 6)).norm(), 1e-10);
  const Eigen::MatrixXd N = Eigen::MatrixXd::Identity(7, 7) - Jp * J;
  const Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(7, -1.0, 2.0);
  EXPECT_LT((J * N * v).norm(), 1e-10);
  EXPECT_GT((N * v).norm(), 1e-3);
  // damping trades accuracy for bounded gains: J·J⁺ is no longer the identity
  const Eigen::MatrixXd Jd = DampedPseudoInverse(J, 0.1);
  EXPECT_GT((J * Jd - Eigen::MatrixXd::Identity(6, 6)).norm(), 1e-4);
}

TEST_F(TaskSpaceTest, ConvergesToReachablePoseAtRateK) {
  TaskSpaceConfig config;  // k = 20/s, λ = 1e-3, posture term on
  auto c = TaskSpaceController::Create(config, *robot_);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  Eigen::VectorXd q = q_start_;
  const double dt = 1e-3;
  double first = 0.0, at_100ms = 0.0, previous = INFINITY;
  TaskSpaceOutput out;
  for (int k = 0; k <= 3000; ++k) {
    out = Step(*c, q, target, dt);
    const double err = out.error_W.norm();
    if (k == 0) first = err;
    if (k == 100) at_100ms = err;
    EXPECT_LE(err, previous * (1.0 + 1e-6) + 1e-12) << "step " << k;
    previous = err;
  }
  EXPECT_GT(first, 0.3);
  // exponential decay exp(−k·t): e(0.1 s)/e(0) ≈ e⁻² (Euler: 0.98¹⁰⁰)
  EXPECT_NEAR(at_100ms / first, std::exp(-2.0), 0.15 * std::exp(-2.0));
  EXPECT_LT(out.position_error_m, 1e-6);
  EXPECT_LT(out.orientation_error_rad, 1e-6);
  const Pose reached = PoseAt(q);
  EXPECT_LT((reached.p_W - target.pose.p_W).norm(), 1e-6);
  EXPECT_LT(OrientationError(target.pose.R_W, reached.R_W).norm(), 1e-6);
}

TEST_F(TaskSpaceTest, TracksMovingTargetWithErrorScalingWithDt) {
  CartesianTrajectoryConfig config;
  config.waypoints = {PoseAt(q_start_), PoseAt(q_goal_)};
  config.segments = {SegmentTiming{1.0, {TimeScalingType::kQuintic, 0.25}}};
  auto traj = CartesianTrajectory::Create(config);
  const double e1 = TrackingError(*traj, q_start_, 1e-3, true);
  const double e2 = TrackingError(*traj, q_start_, 2e-3, true);
  const double e_no_ff = TrackingError(*traj, q_start_, 1e-3, false);
  EXPECT_LT(e1, 2e-3);
  EXPECT_GT(e2 / e1, 1.6);  // first order in dt
  EXPECT_LT(e2 / e1, 2.4);
  EXPECT_LT(e1, 0.1 * e_no_ff);  // the feed-forward is what keeps the error small
  std::cout << "tracking error: dt 1 ms " << e1 << ", dt 2 ms " << e2 << ", no feed-forward " << e_no_ff << "\n";
}

TEST_F(TaskSpaceTest, NullSpaceTermDoesNotChangeTaskVelocity) {
  TaskSpaceConfig config;
  config.damping = 0.0;
  config.k_null = 0.0;
  auto plain = TaskSpaceController::Create(config, *robot_);
  config.k_null = 5.0;
  config.k_joint_limit = 3.0;
  auto posture = TaskSpaceController::Create(config, *robot_);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  target.v_W = Eigen::Vector3d(0.1, -0.2, 0.05);
  Eigen::VectorXd q = q_start_;
  q[1] = 1.9;  // inside j2's limit band
  robot_->SetState(q, Eigen::VectorXd::Zero(7));
  const Eigen::VectorXd a = plain->Update(*robot_, q, target).qd_cmd;
  const Eigen::VectorXd b = posture->Update(*robot_, q, target).qd_cmd;
  const Eigen::MatrixXd J = robot_->Jacobian();
  EXPECT_LT((J * (b - a)).norm(), 1e-9);
  EXPECT_GT((b - a).norm(), 1e-2);
}

TEST_F(TaskSpaceTest, MatchesClosedFormWithDampingAndLimitTerm) {
  TaskSpaceConfig config;
  config.damping = 0.05;
  config.k_position = 7.0;
  config.k_orientation = 3.0;
  config.k_null = 2.0;
  config.k_joint_limit = 4.0;
  config.q_rest = Eigen::VectorXd::LinSpaced(7, -0.5, 0.5);
  auto c = TaskSpaceController::Create(config, *robot_);
  Eigen::VectorXd q = q_start_;
  q[3] = -2.3;  // inside j4's lower band [-2.5, -2.0]
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  target.v_W = Eigen::Vector3d(0.1, 0.0, -0.2);
  target.w_W = Eigen::Vector3d(0.0, 0.3, 0.1);
  robot_->SetState(q, Eigen::VectorXd::Zero(7));
  const TaskSpaceOutput out = c->Update(*robot_, q, target);

  // independent evaluation of the documented law
  const Pose pose = robot_->TipPose();
  const Eigen::MatrixXd J = robot_->Jacobian();
  Vector6d x_ref;
  x_ref << target.v_W + 7.0 * (target.pose.p_W - pose.p_W),
      target.w_W + 3.0 * Eigen::AngleAxisd(target.pose.R_W * pose.R_W.transpose()).angle() *
                       Eigen::AngleAxisd(target.pose.R_W * pose.R_W.transpose()).axis();
  Eigen::VectorXd qd0 = 2.0 * (config.q_rest - q);
  qd0[3] += 4.0 * ((-2.5 + 0.1 * 5.0) - q[3]);
  const Eigen::MatrixXd Jp = DampedPseudoInverse(J, 0.05);
  const Eigen::VectorXd expected = Jp * x_ref + (Eigen::MatrixXd::Identity(7, 7) - Jp * J) * qd0;
  EXPECT_LT((out.qd_cmd - expected).norm(), 1e-9) << out.qd_cmd.transpose() << "\n" << expected.transpose();
  EXPECT_DOUBLE_EQ(out.damping, 0.05);
  EXPECT_EQ(out.speed_scale, 1.0);
  EXPECT_TRUE(out.ok);
}

TEST_F(TaskSpaceTest, PostureMovesTowardRestWhileHoldingPose) {
  TaskSpaceConfig config;
  config.damping = 0.0;
  config.k_null = 5.0;
  auto c = TaskSpaceController::Create(config, *robot_);
  // default rest posture: range centres (0 here), 0 for the unlimited j7
  EXPECT_LT(c->q_rest().norm(), 1e-15);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_start_);
  Eigen::VectorXd q = q_start_;
  const double initial = (q - c->q_rest()).norm();
  double previous = initial, worst_task = 0.0;
  for (int k = 0; k < 2000; ++k) {
    worst_task = std::max(worst_task, Step(*c, q, target, 1e-3).error_W.norm());
    const double distance = (q - c->q_rest()).norm();
    EXPECT_LE(distance, previous + 1e-12) << "step " << k;
    previous = distance;
  }
  std::cout << "posture distance " << initial << " -> " << previous << ", worst task error " << worst_task << "\n";
  EXPECT_LT(previous, initial - 0.01);
  EXPECT_LT(worst_task, 1e-4);
  // converged to a posture where the rest-pull has no null-space component left
  robot_->SetState(q, Eigen::VectorXd::Zero(7));
  const Eigen::MatrixXd J = robot_->Jacobian();
  const Eigen::MatrixXd N = Eigen::MatrixXd::Identity(7, 7) - DampedPseudoInverse(J, 0.0) * J;
  const Eigen::MatrixXd J0 = [&] {
    robot_->SetState(q_start_, Eigen::VectorXd::Zero(7));
    return robot_->Jacobian();
  }();
  const Eigen::MatrixXd N0 = Eigen::MatrixXd::Identity(7, 7) - DampedPseudoInverse(J0, 0.0) * J0;
  const double pull0 = (N0 * (c->q_rest() - q_start_)).norm();
  const double pull = (N * (c->q_rest() - q)).norm();
  std::cout << "null-space rest pull " << pull0 << " -> " << pull << "\n";
  EXPECT_LT(pull, 1e-3 * pull0);
}

TEST_F(TaskSpaceTest, LargeOrientationErrorDoesNotFlip) {
  TaskSpaceConfig config;
  config.k_null = 0.0;
  auto c = TaskSpaceController::Create(config, *robot_);
  const Pose start = PoseAt(q_start_);
  // about the last joint's axis through the tip: reachable without passing a
  // singularity, but the controller is not told so
  const int l7 = mj_name2id(model_, mjOBJ_BODY, "l7");
  const Eigen::Vector3d axis(robot_->data().xmat[9 * l7 + 2], robot_->data().xmat[9 * l7 + 5],
                             robot_->data().xmat[9 * l7 + 8]);
  const double angle = 179.0 * kPi / 180.0;
  TaskSpaceTarget target;
  target.pose.p_W = start.p_W;
  target.pose.R_W = Rot(angle, axis) * start.R_W;
  Eigen::VectorXd q = q_start_;
  double previous = INFINITY, at_50ms = 0.0;
  TaskSpaceOutput out;
  for (int k = 0; k <= 3000; ++k) {
    out = Step(*c, q, target, 1e-3);
    const Eigen::Vector3d e = out.error_W.tail<3>();
    if (k == 0) {
      EXPECT_LT((e - angle * axis).norm(), 1e-9);
    }
    if (k == 50) at_50ms = out.orientation_error_rad;
    if (e.norm() > 1e-9) {
      EXPECT_GT(e.normalized().dot(axis), 0.99) << "step " << k;
    }
    EXPECT_LE(out.orientation_error_rad, previous + 1e-12) << "step " << k;
    previous = out.orientation_error_rad;
  }
  EXPECT_NEAR(at_50ms, angle * std::pow(1.0 - 20.0 * 1e-3, 50), 0.05 * at_50ms);
  EXPECT_LT(out.orientation_error_rad, 1e-6);
  EXPECT_LT(out.position_error_m, 1e-6);
}

TEST_F(TaskSpaceTest, MaxJointSpeedScalesUniformly) {
  TaskSpaceConfig config;
  auto free = TaskSpaceController::Create(config, *robot_);
  config.max_joint_speed = 0.5;
  auto limited = TaskSpaceController::Create(config, *robot_);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  robot_->SetState(q_start_, Eigen::VectorXd::Zero(7));
  const Eigen::VectorXd a = free->Update(*robot_, q_start_, target).qd_cmd;
  const TaskSpaceOutput& out = limited->Update(*robot_, q_start_, target);
  ASSERT_GT(a.cwiseAbs().maxCoeff(), 0.5);
  EXPECT_NEAR(out.qd_cmd.cwiseAbs().maxCoeff(), 0.5, 1e-12);
  EXPECT_LT((out.qd_cmd - out.speed_scale * a).norm(), 1e-12);
  EXPECT_NEAR(out.speed_scale, 0.5 / a.cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(TaskSpaceTest, AdaptiveDampingRisesNearSingularity) {
  TaskSpaceConfig config;
  config.damping = 1e-3;
  config.adaptive_damping_max = 0.1;
  config.singular_value_threshold = 0.05;
  auto c = TaskSpaceController::Create(config, *robot_);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  for (const Eigen::VectorXd& q : {Eigen::VectorXd(Eigen::VectorXd::Zero(7)), q_start_}) {
    robot_->SetState(q, Eigen::VectorXd::Zero(7));
    const double sigma_min = Eigen::JacobiSVD<Eigen::MatrixXd>(robot_->Jacobian()).singularValues()[5];
    double lambda2 = 1e-6;
    if (sigma_min < 0.05) lambda2 += 0.01 * (1.0 - std::pow(sigma_min / 0.05, 2));
    const TaskSpaceOutput& out = c->Update(*robot_, q, target);
    EXPECT_NEAR(out.damping, std::sqrt(lambda2), 1e-9) << "sigma_min " << sigma_min;
    EXPECT_TRUE(out.qd_cmd.allFinite());
  }
  robot_->SetState(Eigen::VectorXd::Zero(7), Eigen::VectorXd::Zero(7));
  EXPECT_GT(c->Update(*robot_, Eigen::VectorXd::Zero(7), target).damping, 0.05);  // straight up
}

TEST_F(TaskSpaceTest, UpdateDoesNotAllocate) {
  auto c = TaskSpaceController::Create(TaskSpaceConfig{}, *robot_);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  robot_->SetState(q_start_, Eigen::VectorXd::Zero(7));
  c->Update(*robot_, q_start_, target);
  g_allocations = 0;
  g_count_allocations = true;
  for (int k = 0; k < 10; ++k) c->Update(*robot_, q_start_, target);
  g_count_allocations = false;
  EXPECT_EQ(g_allocations.load(), 0);
  // the counter works: an Eigen dynamic vector allocates
  g_count_allocations = true;
  Eigen::VectorXd v(100);
  g_count_allocations = false;
  v.setZero();
  EXPECT_GT(g_allocations.load(), 0);
}

TEST_F(TaskSpaceTest, NonFiniteTargetGivesZeroCommand) {
  auto c = TaskSpaceController::Create(TaskSpaceConfig{}, *robot_);
  TaskSpaceTarget target;
  target.pose = PoseAt(q_goal_);
  target.v_W.x() = std::nan("");
  robot_->SetState(q_start_, Eigen::VectorXd::Zero(7));
  const TaskSpaceOutput& out = c->Update(*robot_, q_start_, target);
  EXPECT_FALSE(out.ok);
  EXPECT_TRUE(out.qd_cmd.isZero());
}

TEST_F(TaskSpaceTest, ConfigAndSizeErrorsNameTheField) {
  auto expect_error = [&](const TaskSpaceConfig& config, const std::string& field) {
    try {
      TaskSpaceController::Create(config, *robot_);
      ADD_FAILURE() << "no throw for " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  TaskSpaceConfig config;
  config.k_position = -1.0;
  expect_error(config, "k_position");
  config = TaskSpaceConfig{};
  config.k_orientation = NAN;
  expect_error(config, "k_orientation");
  config = TaskSpaceConfig{};
  config.damping = -1e-3;
  expect_error(config, "damping");
  config = TaskSpaceConfig{};
  config.q_rest = Eigen::VectorXd::Zero(6);
  expect_error(config, "q_rest has size 6");
  config = TaskSpaceConfig{};
  config.joint_limit_margin = 0.0;
  expect_error(config, "joint_limit_margin");
  config = TaskSpaceConfig{};
  config.max_joint_speed = 0.0;
  expect_error(config, "max_joint_speed");
  config = TaskSpaceConfig{};
  config.adaptive_damping_max = 0.1;
  config.singular_value_threshold = 0.0;
  expect_error(config, "singular_value_threshold");

  auto c = TaskSpaceController::Create(TaskSpaceConfig{}, *robot_);
  EXPECT_THROW(c->Update(*robot_, Eigen::VectorXd::Zero(6), TaskSpaceTarget{}), std::invalid_argument);
}

}  // namespace
}  // namespace vlab::control
