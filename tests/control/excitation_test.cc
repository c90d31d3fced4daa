#include <chrono>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "control/dynamics_regressor.h"
#include "control/excitation_optimizer.h"
#include "control/excitation_trajectory.h"
#include "mujoco_fixture.h"

namespace vlab::control {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;
const std::vector<std::string> kExcitedJoints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};

// the PA10's limits as the task language keeps them (docs/tasks.md): 180 deg/s; 180 deg/s²,
// 360 for the wrist; ranges from the model
JointLimits Pa10Limits(const DynamicsRegressor& r) {
  JointLimits l;
  l.lower = r.lower_limits();
  l.upper = r.upper_limits();
  l.v_max = Eigen::VectorXd::Constant(7, 180 * kDegree);
  l.a_max = Eigen::VectorXd::Constant(7, 180 * kDegree);
  l.a_max.tail(3).setConstant(360 * kDegree);
  return l;
}

Eigen::VectorXd ReadyPose() {
  Eigen::VectorXd q(7);
  q << 0, 30 * kDegree, 0, 60 * kDegree, 0, 90 * kDegree, 0;
  return q;
}

TEST(FourierExcitationTest, SweversConstraintsStartAndEndAtRestAtTheStartPose) {
  FourierExcitation t;
  t.period_s = 8;
  t.q_start = Eigen::VectorXd::Constant(2, 0.3);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  t.a.resize(2, 4);
  t.b.resize(2, 4);
  for (int i = 0; i < 2; ++i) {
    double sum_a = 0, sum_lb = 0;
    for (int l = 2; l <= 4; ++l) {
      t.a(i, l - 1) = u(rng), t.b(i, l - 1) = u(rng);
      sum_a += t.a(i, l - 1), sum_lb += l * t.b(i, l - 1);
    }
    t.a(i, 0) = -sum_a, t.b(i, 0) = -sum_lb;
  }
  EXPECT_LT(t.ConstraintResidual(), 1e-15);
  Eigen::VectorXd q, qd, qdd;
  for (double t0 : {0.0, 8.0, 16.0}) {
    t.Evaluate(t0, &q, &qd, &qdd);
    EXPECT_LT((q - t.q_start).cwiseAbs().maxCoeff(), 1e-12) << t0;
    EXPECT_LT(qd.cwiseAbs().maxCoeff(), 1e-12) << t0;
    EXPECT_LT(qdd.cwiseAbs().maxCoeff(), 1e-12) << t0;
  }
  // the derivatives are the position's (central differences)
  const double h = 1e-5;
  Eigen::VectorXd qp, qm, qdp, qdm;
  t.Evaluate(2.7 + h, &qp, &qdp, nullptr);
  t.Evaluate(2.7 - h, &qm, &qdm, nullptr);
  t.Evaluate(2.7, &q, &qd, &qdd);
  EXPECT_LT(((qp - qm) / (2 * h) - qd).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT(((qdp - qdm) / (2 * h) - qdd).cwiseAbs().maxCoeff(), 1e-8);
}

class ExcitationTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/pa10.xml");
    regressor_ = DynamicsRegressor::Create(model_, kExcitedJoints);
    reference_.assign(model_->qpos0, model_->qpos0 + model_->nq);
    config_.evaluations = 240;
    config_.restarts = 2;
    first_arm_body_ = mj_name2id(model_, mjOBJ_BODY, "pa10_link1");
  }
  ExcitationResult Optimize() {
    return OptimizeExcitation(model_, regressor_.get(), reference_, ReadyPose(), Pa10Limits(*regressor_), config_);
  }
  // contacts of the arm's geoms at the control-period samples of `t` that are not there at
  // its start pose, by MuJoCo's collision detection on the scene as it is
  int NewContacts(const FourierExcitation& t) {
    mjData* d = MakeData(model_);
    const auto contacts = [&](const Eigen::VectorXd& q) {
      std::set<std::pair<int, int>> pairs;
      for (int i = 0; i < 7; ++i) d->qpos[i] = q[i];
      mj_kinematics(model_, d);
      mj_collision(model_, d);
      for (int c = 0; c < d->ncon; ++c) {
        const int b1 = model_->geom_bodyid[d->contact[c].geom1], b2 = model_->geom_bodyid[d->contact[c].geom2];
        if (b1 >= first_arm_body_ || b2 >= first_arm_body_) pairs.insert({d->contact[c].geom1, d->contact[c].geom2});
      }
      return pairs;
    };
    const std::set<std::pair<int, int>> start = contacts(t.q_start);
    int found = 0;
    Eigen::VectorXd q;
    for (long k = 0; k <= std::lround(t.period_s / config_.control_period_s); ++k) {
      t.Evaluate(k * config_.control_period_s, &q, nullptr, nullptr);
      for (const auto& p : contacts(q)) found += start.count(p) ? 0 : 1;
    }
    return found;
  }
  const mjModel* model_ = nullptr;
  std::unique_ptr<DynamicsRegressor> regressor_;
  std::vector<double> reference_;
  ExcitationConfig config_;
  int first_arm_body_ = 0;
};

TEST_F(ExcitationTest, StaysWithinEveryLimitAndImprovesTheCondition) {
  const auto start = std::chrono::steady_clock::now();
  const ExcitationResult r = Optimize();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const JointLimits limits = Pa10Limits(*regressor_);
  std::printf("cond %.4g -> %.4g, %d evaluations, %.2f s, base parameters %zu, clearance %.4f m (%s)\n", r.cond_initial,
              r.cond_final, r.evaluations, seconds, r.base.independent.size(), r.clearance_m, r.closest.c_str());
  for (int i = 0; i < 7; ++i) {
    std::printf("%s: q %.1f .. %.1f deg (range %.0f .. %.0f), |qd| %.1f deg/s, |qdd| %.1f deg/s^2\n",
                kExcitedJoints[i].c_str(), r.peaks.q_min[i] / kDegree, r.peaks.q_max[i] / kDegree,
                limits.lower[i] / kDegree, limits.upper[i] / kDegree, r.peaks.v_abs[i] / kDegree,
                r.peaks.a_abs[i] / kDegree);
  }
  // the peaks measured again, independently of the search, within every limit less the margins
  const JointPeaks peaks = MeasurePeaks(r.trajectory, config_.control_period_s);
  EXPECT_EQ(CheckPeaks(peaks, limits, kExcitedJoints), "");
  JointLimits inner = limits;
  inner.lower.array() += config_.position_margin_rad - 1e-9;
  inner.upper.array() -= config_.position_margin_rad - 1e-9;
  inner.v_max *= config_.rate_fraction * (1 + 1e-9);
  inner.a_max *= config_.rate_fraction * (1 + 1e-9);
  EXPECT_EQ(CheckPeaks(peaks, inner, kExcitedJoints), "");
  EXPECT_LT(r.trajectory.ConstraintResidual(), 1e-12);
  EXPECT_TRUE(std::isfinite(r.cond_final));
  EXPECT_LT(r.cond_final, r.cond_initial);
  EXPECT_GE(r.clearance_m, config_.clearance_m - 1e-12);
  // clear of the table, the floor and itself: MuJoCo's own contacts (no margin) at every
  // control period, none but those at the start pose
  EXPECT_EQ(NewContacts(r.trajectory), 0);
  // and the check can fail: the same trajectory against tighter limits names the joint
  JointLimits tight = limits;
  tight.v_max *= 0.5 * config_.rate_fraction;
  const std::string message = CheckPeaks(peaks, tight, kExcitedJoints);
  EXPECT_NE(message.find("needs"), std::string::npos) << message;
  EXPECT_NE(message.find("deg/s, its limit is 81 deg/s"), std::string::npos) << message;
  tight = limits;
  tight.upper = peaks.q_max.array() - 0.01;
  EXPECT_NE(CheckPeaks(peaks, tight, kExcitedJoints).find("joint S1 reaches"), std::string::npos);
}

TEST_F(ExcitationTest, TheContactCheckSeesTheTable) {
  // the check above can fail: a period that swings the arm from the ready pose down over the
  // table (S2 forward) touches it
  FourierExcitation t;
  t.period_s = 2;
  t.q_start = ReadyPose();
  t.a = Eigen::MatrixXd::Zero(7, 2);
  t.b = Eigen::MatrixXd::Zero(7, 2);
  t.b(1, 0) = 2, t.b(1, 1) = -1;  // S2: forward by up to 73 deg (4/pi rad) and back
  EXPECT_GT(NewContacts(t), 0);
}

TEST_F(ExcitationTest, SameSeedSameTrajectory) {
  config_.evaluations = 60;
  const ExcitationResult a = Optimize(), b = Optimize();
  EXPECT_EQ(a.trajectory.a, b.trajectory.a);
  EXPECT_EQ(a.trajectory.b, b.trajectory.b);
  EXPECT_EQ(a.cond_final, b.cond_final);
  config_.seed = 2;
  const ExcitationResult c = Optimize();
  EXPECT_NE(a.trajectory.a, c.trajectory.a);
}

TEST_F(ExcitationTest, RefusesWhatCannotBeKept) {
  const auto message = [&](const Eigen::VectorXd& start) {
    try {
      OptimizeExcitation(model_, regressor_.get(), reference_, start, Pa10Limits(*regressor_), config_);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  Eigen::VectorXd start = ReadyPose();
  start[1] = 92 * kDegree;  // S2: 2 deg from its 94 deg limit, inside the 5 deg margin
  EXPECT_NE(message(start).find("joint S2 starts at 92"), std::string::npos) << message(start);
  config_.period_s = 10.001;
  EXPECT_NE(message(ReadyPose()).find("whole number"), std::string::npos);
  config_.period_s = 10;
  config_.harmonics = 1;
  EXPECT_NE(message(ReadyPose()).find("harmonics"), std::string::npos);
}

}  // namespace
}  // namespace vlab::control
