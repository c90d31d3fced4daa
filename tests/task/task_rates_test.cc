// Joint speed and acceleration limits of every move type (task_rates.h and the
// planner): the commanded joint path of movej, movel, movec and a blended movel,
// differentiated here at the period, never exceeds a joint's limits; a movel
// asked for in 0.05 s is slowed and stays on its line, or refused; movej's
// timing against the trapezoid's closed form.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pa10_planner_fixture.h"

namespace vlab::task {
namespace {

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

// peak |speed| and |acceleration| per joint of the commanded sequence (own finite differences)
struct Peaks {
  std::vector<double> v, a;
};
Peaks PeaksOf(const std::vector<Eigen::VectorXd>& q) {
  const int n = static_cast<int>(q[0].size());
  Peaks p{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
  for (std::size_t i = 1; i < q.size(); ++i) {
    for (int j = 0; j < n; ++j) {
      const double v = (q[i][j] - q[i - 1][j]) / kPeriod;
      p.v[j] = std::max(p.v[j], std::abs(v));
      if (i >= 2) p.a[j] = std::max(p.a[j], std::abs(v - (q[i - 1][j] - q[i - 2][j]) / kPeriod) / kPeriod);
    }
  }
  return p;
}

class RatesTest : public Pa10PlannerTest {
 protected:
  void SetUp() override {
    Pa10PlannerTest::SetUp();
    start_ = planner_->ToolPose(q0_);
  }
  // tight limits, so that fast moves must be slowed: 20 deg/s and 40 deg/s² (W2: 30, 60)
  JointRateLimits Tight() const {
    JointRateLimits l = DefaultRateLimits(7);
    l.v_rps.setConstant(20 * kDeg);
    l.a_rps2.setConstant(40 * kDeg);
    l.v_rps[6] = 30 * kDeg;
    l.a_rps2[6] = 60 * kDeg;
    return l;
  }
  // from rest at q0: [q0, q0, plan..., end at rest]
  std::vector<Eigen::VectorXd> Commanded(const Plan& plan) const {
    std::vector<Eigen::VectorXd> q = {q0_, q0_};
    q.insert(q.end(), plan.q.begin(), plan.q.end());
    q.push_back(plan.q.back());
    return q;
  }
  // every joint within its limits (1e-6 relative); returns the largest fraction of a limit used
  double ExpectWithin(const std::vector<Eigen::VectorXd>& q, const JointRateLimits& l, const char* what) {
    const Peaks p = PeaksOf(q);
    double used = 0;
    for (int j = 0; j < 7; ++j) {
      EXPECT_LE(p.v[j], l.v_rps[j] * (1 + 1e-6)) << what << ": joint " << j << " speed";
      EXPECT_LE(p.a[j], l.a_rps2[j] * (1 + 1e-6)) << what << ": joint " << j << " acceleration";
      used = std::max({used, p.v[j] / l.v_rps[j], p.a[j] / l.a_rps2[j]});
    }
    return used;
  }
  Frame At(const Eigen::Vector3d& offset) const {
    Frame f = start_;
    f.p += offset;
    return f;
  }

  Frame start_;
};

TEST_F(RatesTest, PeakRatesOfAParabolaAreItsSpeedAndAcceleration) {
  std::vector<Eigen::VectorXd> q;
  for (int i = 0; i <= 100; ++i) q.push_back(Eigen::VectorXd::Constant(1, 0.5 * 3.0 * std::pow(i * kPeriod, 2)));
  const JointRates r = PeakRates(q, kPeriod);
  EXPECT_NEAR(r.a_rps2[0], 3.0, 1e-6);
  EXPECT_NEAR(r.v_rps[0], 3.0 * (100 - 0.5) * kPeriod, 1e-9);  // the last difference: the mean over its period
}

TEST_F(RatesTest, EveryMoveTypeKeepsEveryJointWithinItsLimits) {
  planner_->set_rate_limits(Tight());
  const JointRateLimits l = Tight();
  MotionLimits fast;
  fast.speed_mps = 1.0;
  fast.accel_mps2 = 10;
  fast.rot_speed_rps = 360 * kDeg;
  fast.joint_speed_rps = 300 * kDeg;
  fast.joint_accel_rps2 = 1000 * kDeg;
  Eigen::VectorXd q1 = q0_;
  q1 << 20 * kDeg, 45 * kDeg, -10 * kDeg, 80 * kDeg, 10 * kDeg, 70 * kDeg, 60 * kDeg;
  const Plan j = planner_->Joint(q0_, q1, fast);
  EXPECT_GT(ExpectWithin(Commanded(j), l, "movej"), 0.99);  // at the limits, not slower
  const Plan lin = planner_->Linear(q0_, At({0.10, 0.10, -0.10}), fast);
  EXPECT_GT(ExpectWithin(Commanded(lin), l, "movel"), 0.9);
  const Plan arc = planner_->Arc(q0_, At({0.05, 0.05, 0}).p, At({0.10, 0, 0}), fast);
  EXPECT_GT(ExpectWithin(Commanded(arc), l, "movec"), 0.9);
  const Plan timed = planner_->Joint(q0_, q1, fast, 0.1);  // a duration far too short: stretched
  EXPECT_GT(timed.duration_s, 1.0);
  ExpectWithin(Commanded(timed), l, "movej t");

  // a blended movel: A -> B with r = 20 mm, then on to C, entered at the first sample within r
  const Eigen::Vector3d B = At({0.10, 0, 0}).p;
  const Plan ab = planner_->Linear(q0_, At({0.10, 0, 0}), fast);
  std::size_t e = 0;
  while ((ab.tool_W[e].p - B).norm() > 0.02) ++e;
  ASSERT_GE(e, 1u);
  BlendStart b;
  b.q = ab.q[e];
  b.q_before = ab.q[e - 1];
  b.entry = ab.tool_W[e];
  b.corner = B;
  b.tangent = (B - start_.p).normalized();
  b.speed_mps = ab.speed_mps[e];
  const Plan bc = planner_->FromBlend(b, At({0.10, 0.10, 0}), fast);
  std::vector<Eigen::VectorXd> q = {q0_, q0_};
  q.insert(q.end(), ab.q.begin(), ab.q.begin() + static_cast<long>(e) + 1);
  q.insert(q.end(), bc.q.begin(), bc.q.end());
  q.push_back(bc.q.back());
  ExpectWithin(q, l, "blended movel");
}

TEST_F(RatesTest, AMovelAskedForInFiftyMillisecondsIsSlowedAndStaysOnItsLine) {
  MotionLimits limits;
  const Frame goal = At({0.10, 0.10, -0.05});
  const Plan p = planner_->Linear(q0_, goal, limits, 0.05);
  EXPECT_GT(p.duration_s, 0.2);  // stretched (measured: see docs/tasks.md)
  ExpectWithin(Commanded(p), planner_->rate_limits(), "movel t = 0.05");
  const Eigen::Vector3d d = (goal.p - start_.p).normalized();
  double off = 0;
  for (const Eigen::VectorXd& q : p.q) {
    fk_->SetState(q, Eigen::VectorXd::Zero(7));
    const Eigen::Vector3d r = fk_->TipPose().p_W - start_.p;
    off = std::max(off, (r - r.dot(d) * d).norm());
  }
  EXPECT_LT(off, 1e-7);  // every commanded sample's tool on the line (the independent chain)
  fk_->SetState(p.q.back(), Eigen::VectorXd::Zero(7));
  EXPECT_LT((fk_->TipPose().p_W - goal.p).norm(), 1e-7);

  JointRateLimits refuse = planner_->rate_limits();
  refuse.refuse = true;
  planner_->set_rate_limits(refuse);
  try {
    planner_->Linear(q0_, goal, limits, 0.05);
    FAIL() << "not refused";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_HAS(m, "joint ");
    EXPECT_HAS(m, " deg/s and ");
    EXPECT_HAS(m, "its limits are 180 deg/s and ");
  }
  EXPECT_NO_THROW(planner_->Linear(q0_, goal, limits));  // the default speeds are within
}

TEST_F(RatesTest, MovejTimingIsTheTrapezoidsClosedForm) {
  // fastest joint W2 by D; T = D/v + v/a (D >= v²/a), else 2 sqrt(D/a)
  const auto expect_T = [](double D, double v, double a) {
    return D >= v * v / a ? D / v + v / a : 2 * std::sqrt(D / a);
  };
  const struct {
    double D_deg, v, a, v_used, a_used;  // deg, deg/s, deg/s²: asked for, and the joint limits' cap
  } cases[] = {
      {90, 60, 120, 60, 120},     // trapezoid: 2.0 s
      {10, 60, 120, 60, 120},     // triangle: 0.577 s
      {90, 500, 1000, 180, 360},  // beyond W2's limits: at 180 deg/s, 360 deg/s²
  };
  for (const auto& c : cases) {
    MotionLimits limits;
    limits.joint_speed_rps = c.v * kDeg;
    limits.joint_accel_rps2 = c.a * kDeg;
    Eigen::VectorXd q1 = q0_;
    q1[6] += c.D_deg * kDeg;
    q1[4] += 0.5 * c.D_deg * kDeg;  // a second joint, half as far
    const Plan p = planner_->Joint(q0_, q1, limits);
    const double T = expect_T(c.D_deg, c.v_used, c.a_used);
    EXPECT_NEAR(p.duration_s, T, 0.01 * T) << c.D_deg << " deg at " << c.v << " deg/s";
    const Peaks pk = PeaksOf(Commanded(p));
    const double v_peak = c.D_deg >= c.v_used * c.v_used / c.a_used ? c.v_used : std::sqrt(c.D_deg * c.a_used);
    EXPECT_NEAR(pk.v[6] / kDeg, v_peak, 0.01 * v_peak);
    EXPECT_NEAR(pk.a[6] / kDeg, c.a_used, 0.01 * c.a_used);
  }
}

}  // namespace
}  // namespace vlab::task
