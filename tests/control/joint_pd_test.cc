#include "control/joint_pd.h"

#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace vlab::control {
namespace {

Eigen::VectorXd Random(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

TEST(JointPdTest, EqualsFormulaOnRandomInputs) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 1 + trial % 7;
    JointPdGains gains{Random(rng, n).cwiseAbs() * 100.0, Random(rng, n).cwiseAbs() * 10.0};
    const Eigen::VectorXd q = Random(rng, n), qd = Random(rng, n), q_des = Random(rng, n), qd_des = Random(rng, n),
                          g = Random(rng, n);
    const Eigen::VectorXd tau = JointPdGravityTorque(gains, q, qd, q_des, qd_des, g);
    ASSERT_EQ(tau.size(), n);
    for (int i = 0; i < n; ++i) {
      const double expected = gains.kp[i] * (q_des[i] - q[i]) + gains.kd[i] * (qd_des[i] - qd[i]) + g[i];
      EXPECT_NEAR(tau[i], expected, 1e-12);
    }
  }
}

TEST(JointPdTest, AtTargetGivesGravityOnly) {
  const Eigen::VectorXd q = Eigen::Vector3d(0.1, -0.2, 0.3), qd = Eigen::Vector3d(0.5, 0, 1);
  const Eigen::VectorXd g = Eigen::Vector3d(1, 2, 3);
  JointPdGains gains{Eigen::Vector3d::Constant(50), Eigen::Vector3d::Constant(5)};
  EXPECT_EQ(JointPdGravityTorque(gains, q, qd, q, qd, g), g);
}

TEST(JointPdTest, SizeMismatchNamesArgument) {
  const Eigen::VectorXd v3 = Eigen::Vector3d::Zero(), v2 = Eigen::Vector2d::Zero();
  const JointPdGains good{v3, v3};
  struct Case {
    const char* name;
    JointPdGains gains;
    Eigen::VectorXd qd, q_des, qd_des, g;
  };
  const Case cases[] = {
      {"kp", {v2, v3}, v3, v3, v3, v3}, {"kd", {v3, v2}, v3, v3, v3, v3}, {"qd", good, v2, v3, v3, v3},
      {"q_des", good, v3, v2, v3, v3},  {"qd_des", good, v3, v3, v2, v3}, {"g", good, v3, v3, v3, v2},
  };
  for (const Case& c : cases) {
    try {
      JointPdGravityTorque(c.gains, v3, c.qd, c.q_des, c.qd_des, c.g);
      ADD_FAILURE() << "no throw for " << c.name;
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(std::string(c.name) + " has size 2"), std::string::npos) << msg;
      EXPECT_NE(msg.find("q has size 3"), std::string::npos) << msg;
    }
  }
}

}  // namespace
}  // namespace vlab::control
