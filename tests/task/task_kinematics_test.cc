// The kinematics queries (task_kinematics.h) on the PA10 (scenes/pa10.xml, tool
// site "tool"): inverse kinematics round trips through an independent forward
// kinematics (a second RobotModel on the same model) at 1000 random joint
// configurations, the closed form's branches against the joints that made the
// frame, reachability against Newton's method from a grid of seeds, and the
// errors.
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pa10_planner_fixture.h"
#include "task/task_kinematics.h"

namespace vlab::task {
namespace {

class KinematicsTest : public Pa10PlannerTest {
 protected:
  // joints uniform within `fraction` of each joint's range (seeded)
  Eigen::VectorXd Random(std::mt19937* rng, double fraction = 1.0) {
    Eigen::VectorXd q(7);
    for (int i = 0; i < 7; ++i) {
      const double lo = chain_->lower_limits()[i], hi = chain_->upper_limits()[i], mid = (lo + hi) / 2;
      q[i] = std::uniform_real_distribution<double>(mid + (lo - mid) * fraction, mid + (hi - mid) * fraction)(*rng);
    }
    return q;
  }
  bool WithinLimits(const Eigen::VectorXd& q) {
    for (int i = 0; i < 7; ++i) {
      if (q[i] < chain_->lower_limits()[i] - 1e-9 || q[i] > chain_->upper_limits()[i] + 1e-9) return false;
    }
    return true;
  }
  // position of a body of the model at q (the independent chain)
  Eigen::Vector3d Body(const Eigen::VectorXd& q, const char* name) {
    fk_->SetState(q, Eigen::VectorXd::Zero(7));
    const int id = mj_name2id(model_, mjOBJ_BODY, name);
    return Eigen::Map<const Eigen::Vector3d>(fk_->data().xpos + 3 * id);
  }
  // Newton steps with S3 held, from a 3^6 grid of seeds over the other joints (an
  // independent search): whether one ends on the frame within the limits
  bool BruteForce(const Frame& goal, double s3) {
    const double grid[3] = {-2.0 / 3, 0, 2.0 / 3};
    for (int k = 0; k < 729; ++k) {
      Eigen::VectorXd q(7);
      for (int i = 0, c = k; i < 7; ++i) {
        if (i == 2) continue;
        q[i] = grid[c % 3] * std::min(chain_->upper_limits()[i], M_PI);
        c /= 3;
      }
      q[2] = s3;
      for (int it = 0; it < 100; ++it) {
        const Frame x = Fk(q);
        Eigen::Matrix<double, 6, 1> e;
        e.head<3>() = goal.p - x.p;
        const Eigen::AngleAxisd d(goal.q * x.q.conjugate());
        e.tail<3>() = d.angle() * d.axis();
        if (e.head<3>().norm() < 1e-9 && e.tail<3>().norm() < 1e-9) {
          for (const int i : {4, 6}) {  // E2, W2: ±255 deg, the same angle a turn away
            if (q[i] > chain_->upper_limits()[i]) q[i] -= 2 * M_PI;
            if (q[i] < chain_->lower_limits()[i]) q[i] += 2 * M_PI;
          }
          if (WithinLimits(q)) return true;
          break;
        }
        Eigen::MatrixXd J = fk_->Jacobian();  // the tool site: the fixture's tool is the tip
        J.col(2).setZero();
        const Eigen::VectorXd dq =
            J.transpose() * (J * J.transpose() + 1e-8 * Eigen::MatrixXd::Identity(6, 6)).ldlt().solve(e);
        if (dq.norm() < 1e-12) break;
        q += dq.norm() > 0.3 ? Eigen::VectorXd(dq * 0.3 / dq.norm()) : dq;
      }
    }
    return false;
  }
  std::string Error(const std::function<void()>& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no error)";
  }
};

TEST_F(KinematicsTest, ClosedFormAppliesToThePa10) {
  const Kinematics k(chain_.get(), planner_.get());
  EXPECT_TRUE(k.closed_form()) << k.why_not();
  EXPECT_EQ(k.redundant(), 2);
}

// 1000 frames made by fk of random joints: the nearest solution and every branch round trip
// to 1e-9 m and 1e-9 rad, within limits; the generating joints are among the branches
TEST_F(KinematicsTest, RoundTripAtRandomFrames) {
  const Kinematics k(chain_.get(), planner_.get());
  std::mt19937 rng(20240611);
  int branches = 0, max_branches = 0;
  for (int n = 0; n < 1000; ++n) {
    const Eigen::VectorXd q = Random(&rng);
    const Frame f = Fk(q);
    Eigen::VectorXd seed = q0_;
    seed[2] = q[2];
    const Eigen::VectorXd near = k.Nearest(f, seed);
    EXPECT_LT((Fk(near).p - f.p).norm(), 1e-9) << n;
    EXPECT_LT(Fk(near).q.angularDistance(f.q), 1e-9) << n;
    EXPECT_TRUE(WithinLimits(near)) << n;
    const std::vector<Eigen::VectorXd> all = k.All(f, seed);
    bool found = false;
    for (std::size_t i = 0; i < all.size(); ++i) {
      EXPECT_LT((Fk(all[i]).p - f.p).norm(), 1e-9) << n;
      EXPECT_LT(Fk(all[i]).q.angularDistance(f.q), 1e-9) << n;
      EXPECT_TRUE(WithinLimits(all[i])) << n;
      EXPECT_EQ(all[i][2], q[2]) << n;  // S3 held
      if (i > 0) {
        EXPECT_GE((all[i] - seed).norm(), (all[i - 1] - seed).norm()) << n;  // sorted
      }
      for (std::size_t j = 0; j < i; ++j) EXPECT_GT((all[i] - all[j]).cwiseAbs().maxCoeff(), 1e-6) << n;
      found = found || (all[i] - q).cwiseAbs().maxCoeff() < 1e-6;
    }
    EXPECT_TRUE(found) << "frame " << n << ": the generating joints are not among the " << all.size() << " branches";
    branches += static_cast<int>(all.size());
    max_branches = std::max(max_branches, static_cast<int>(all.size()));
  }
  RecordProperty("mean_branches", std::to_string(branches / 1000.0));
  RecordProperty("max_branches", max_branches);
}

// reachable against an independent search, on frames known to be inside (fk of joints within
// limits, some near the stretched elbow, some folded), just outside and far outside
TEST_F(KinematicsTest, ReachableAgreesWithBruteForce) {
  const Kinematics k(chain_.get(), planner_.get());
  std::mt19937 rng(7);
  const double reach = (Body(q0_, "pa10_link4") - Body(q0_, "pa10_link2")).norm() +
                       (Body(q0_, "pa10_link6") - Body(q0_, "pa10_link4")).norm();
  int inside = 0;
  for (int n = 0; n < 12; ++n) {
    Eigen::VectorXd q = Random(&rng, 0.8);
    if (n % 3 == 1) q[3] = (n % 2 ? 2 : -2) * kDeg;  // nearly stretched
    if (n % 3 == 2) q[3] = 135 * kDeg;               // folded, near E1's limit 137 deg
    Eigen::VectorXd seed = q0_;
    seed[2] = q[2];
    Frame f = Fk(q);
    // where it is: inside; 1 mm beyond the reach; 0.3 m beyond (the tool moved along the shoulder-wrist line)
    const Eigen::Vector3d s = Body(q, "pa10_link2"), w = Body(q, "pa10_link6");
    const Eigen::Vector3d out = (w - s).normalized();
    const int where = n % 4 == 3 ? 2 : (n % 4 == 1 ? 1 : 0);
    if (where == 1) f.p += out * (reach + 1e-3 - (w - s).norm());
    if (where == 2) f.p += out * (reach + 0.3 - (w - s).norm());
    const bool brute = BruteForce(f, q[2]);
    EXPECT_EQ(k.Reachable(f, seed), where == 0) << n;
    EXPECT_EQ(brute, where == 0) << n;
    inside += where == 0;
  }
  EXPECT_GE(inside, 6);
}

TEST_F(KinematicsTest, FkIsTheToolPoseAndNamesBadJoints) {
  const Kinematics k(chain_.get(), planner_.get());
  const Frame a = k.Fk(q0_), b = planner_->ToolPose(q0_);
  EXPECT_EQ((a.p - b.p).norm(), 0.0);
  EXPECT_LT(a.q.angularDistance(b.q), 1e-15);
  // the "ready" pose: upper arm 30 deg from vertical, forearm horizontal, tool (0.27 m from the
  // wrist centre) pointing down; the shoulder 0.315 m up (mjcf/pa10/pa10.xml)
  const Eigen::Vector3d ready(0.45 * std::sin(30 * kDeg) + 0.5, 0, 0.315 + 0.45 * std::cos(30 * kDeg) - 0.27);
  EXPECT_LT((a.p - ready).norm(), 1e-12);
  Eigen::VectorXd q = q0_;
  q[3] = NAN;
  EXPECT_NE(Error([&] { k.Fk(q); }).find("joint E1 is nan, not a finite angle"), std::string::npos);
  q[3] = 150 * kDeg;
  EXPECT_EQ(Error([&] { k.Fk(q); }), "joint E1 = 150 deg is beyond its upper limit 137 deg");
  EXPECT_EQ(Error([&] { k.Fk(Eigen::VectorXd::Zero(6)); }), "expected 7 joint angles, got 6");
}

TEST_F(KinematicsTest, IkErrorsSayWhatIsWrong) {
  const Kinematics k(chain_.get(), planner_.get());
  // out of reach: the wrist centre 1.2 m from the shoulder (at 0.315 m up), the arm 0.45 + 0.5 m
  Frame far = k.Fk(q0_);
  far.p = Eigen::Vector3d(0, 0, 0.315) + Eigen::Vector3d(1.2, 0, 0) - (Body(q0_, "pa10_link6") - Fk(q0_).p);
  const std::string reach = Error([&] { k.Nearest(far, q0_); });
  EXPECT_NE(reach.find("out of reach: the wrist centre would be 1.200 m from the shoulder, the arm reaches 0.950 m"),
            std::string::npos)
      << reach;
  EXPECT_EQ(Error([&] { k.All(far, q0_); }), reach);
  EXPECT_FALSE(k.Reachable(far, q0_));
  // every solution beyond a limit: |E1| = 150 deg is fixed by the shoulder-wrist distance
  Eigen::VectorXd bent = q0_;
  bent[3] = 150 * kDeg;
  const std::string limit = Error([&] { k.Nearest(Fk(bent), q0_); });
  EXPECT_NE(limit.find("beyond a joint limit; the nearest has joint E1 = "), std::string::npos) << limit;
  EXPECT_NE(limit.find("limit 137 deg"), std::string::npos) << limit;
  EXPECT_FALSE(k.Reachable(Fk(bent), q0_));
  // a singular target (W1 = 0: E2 and W2 in line): all its solutions form a continuum
  Eigen::VectorXd straight = q0_;
  straight[5] = 0;
  const std::string singular = Error([&] { k.All(Fk(straight), q0_); });
  EXPECT_NE(singular.find("singular target: wrist singularity near W1 = "), std::string::npos) << singular;
  EXPECT_TRUE(k.Reachable(Fk(straight), q0_));  // the nearest solution exists
  // not finite
  Frame nan = far;
  nan.p.x() = NAN;
  EXPECT_EQ(Error([&] { k.Reachable(nan, q0_); }), "the target position is not finite (a NaN or inf)");
  EXPECT_NE(Error([&] { k.Nearest(Fk(q0_), Eigen::VectorXd::Zero(3)); }).find("the seed has 3 joint angles"),
            std::string::npos);
}

// a shoulder offset (S2 3 cm off the S1 axis): the closed form does not apply; Newton from
// a fixed set of seeds still finds solutions that round trip
TEST_F(KinematicsTest, FallsBackToNewtonWithoutTheClosedForm) {
  model_->body_pos[3 * mj_name2id(model_, mjOBJ_BODY, "pa10_link2")] += 0.03;
  const Kinematics k(chain_.get(), planner_.get());
  EXPECT_FALSE(k.closed_form());
  EXPECT_EQ(k.why_not(), "the axes of S1 and S2 do not meet");
  std::mt19937 rng(3);
  for (int n = 0; n < 10; ++n) {
    const Eigen::VectorXd q = Random(&rng, 0.8);
    const Frame f = Fk(q);
    Eigen::VectorXd seed = q0_;
    seed[2] = q[2];
    const std::vector<Eigen::VectorXd> all = k.All(f, seed);
    ASSERT_FALSE(all.empty());
    for (const Eigen::VectorXd& s : all) {
      EXPECT_LT((Fk(s).p - f.p).norm(), 1e-9);
      EXPECT_EQ(s[2], q[2]);
    }
  }
}

}  // namespace
}  // namespace vlab::task
