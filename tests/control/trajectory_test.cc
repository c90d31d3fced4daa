#include "control/trajectory.h"

#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "control_test_models.h"

namespace vlab::control {
namespace {

using testing::kPi;
using testing::Rot;

Pose MakePose(const Eigen::Vector3d& p, const Eigen::Matrix3d& R) {
  Pose pose;
  pose.p_W = p;
  pose.R_W = R;
  return pose;
}

void ExpectThrowsWith(const std::function<void()>& f, const std::string& substring) {
  try {
    f();
    ADD_FAILURE() << "expected std::invalid_argument containing '" << substring << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(substring), std::string::npos)
        << "message '" << e.what() << "' lacks '" << substring << "'";
  }
}

// --- rotation vector --------------------------------------------------------

TEST(RotationVectorTest, MatchesAngleAxisIncludingLargeAngles) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double angle : {0.0, 1e-9, 1e-4, 0.5, 2.0, kPi - 1e-3, kPi - 1e-7}) {
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Eigen::Vector3d r = RotationVector(Rot(angle, axis));
    EXPECT_LT((r - angle * axis).norm(), 1e-9) << "angle " << angle;
  }
  // a rotation by more than π is reported the short way, about the opposite axis
  const Eigen::Vector3d axis(0, 0, 1);
  EXPECT_LT((RotationVector(Rot(kPi + 0.1, axis)) - (kPi - 0.1) * -axis).norm(), 1e-12);
}

// --- joint trajectory ---------------------------------------------------------

JointTrajectoryConfig ThreeWaypoints() {
  JointTrajectoryConfig c;
  c.waypoints = {Eigen::Vector3d(0.0, 1.0, -0.5), Eigen::Vector3d(0.8, 0.2, 0.1), Eigen::Vector3d(-0.3, 0.4, 0.9)};
  c.segments = {SegmentTiming{1.2, {TimeScalingType::kQuintic, 0.25}},
                SegmentTiming{0.7, {TimeScalingType::kTrapezoidal, 0.3}}};
  return c;
}

TEST(JointTrajectoryTest, HitsWaypointsAndHolds) {
  const JointTrajectoryConfig c = ThreeWaypoints();
  auto traj = JointTrajectory::Create(c);
  EXPECT_EQ(traj->dof(), 3);
  EXPECT_DOUBLE_EQ(traj->duration_s(), 1.9);
  EXPECT_EQ(traj->Evaluate(-1.0).q, c.waypoints[0]);
  EXPECT_EQ(traj->Evaluate(0.0).q, c.waypoints[0]);
  EXPECT_LT((traj->Evaluate(1.2).q - c.waypoints[1]).norm(), 1e-12);
  EXPECT_LT((traj->Evaluate(1.9).q - c.waypoints[2]).norm(), 1e-12);
  const JointSample after = traj->Evaluate(5.0);
  EXPECT_EQ(after.q, c.waypoints[2]);
  EXPECT_TRUE(after.qd.isZero());
  EXPECT_TRUE(after.qdd.isZero());
  EXPECT_TRUE(after.done);
  EXPECT_FALSE(traj->Evaluate(1.0).done);
  // halfway through a symmetric scaling is the midpoint of the segment
  EXPECT_LT((traj->Evaluate(0.6).q - 0.5 * (c.waypoints[0] + c.waypoints[1])).norm(), 1e-12);
}

TEST(JointTrajectoryTest, ContinuousAtSegmentBoundaries) {
  auto traj = JointTrajectory::Create(ThreeWaypoints());
  for (double tb : {1.2, 1.9}) {
    const double e = 1e-7;
    const JointSample before = traj->Evaluate(tb - e);
    const JointSample after = traj->Evaluate(tb + e);
    EXPECT_LT((before.q - after.q).norm(), 1e-6) << "t = " << tb;
    EXPECT_LT((before.qd - after.qd).norm(), 1e-5) << "t = " << tb;
    EXPECT_LT(before.qd.norm(), 1e-5);  // waypoints are reached at rest
  }
}

TEST(JointTrajectoryTest, VelocityAndAccelerationMatchFiniteDifferences) {
  auto traj = JointTrajectory::Create(ThreeWaypoints());
  const double h = 1e-6;
  for (double t : {0.1, 0.5, 0.9, 1.3, 1.6}) {
    const JointSample s = traj->Evaluate(t);
    const Eigen::VectorXd fd_q = (traj->Evaluate(t + h).q - traj->Evaluate(t - h).q) / (2 * h);
    const Eigen::VectorXd fd_qd = (traj->Evaluate(t + h).qd - traj->Evaluate(t - h).qd) / (2 * h);
    EXPECT_LT((s.qd - fd_q).norm(), 1e-6) << "t = " << t;
    EXPECT_LT((s.qdd - fd_qd).norm(), 1e-5) << "t = " << t;
  }
}

TEST(JointTrajectoryTest, PresizedEvaluateDoesNotChangeCapacity) {
  auto traj = JointTrajectory::Create(ThreeWaypoints());
  JointSample s = traj->Evaluate(0.3);
  const double* q_data = s.q.data();
  traj->Evaluate(1.5, &s);
  EXPECT_EQ(s.q.data(), q_data);  // same buffer: no reallocation
}

TEST(JointTrajectoryTest, SingleWaypointIsHold) {
  JointTrajectoryConfig c;
  c.waypoints = {Eigen::Vector2d(0.3, -0.2)};
  auto traj = JointTrajectory::Create(c);
  EXPECT_EQ(traj->duration_s(), 0.0);
  EXPECT_EQ(traj->Evaluate(2.0).q, c.waypoints[0]);
  EXPECT_TRUE(traj->Evaluate(2.0).done);
}

TEST(JointTrajectoryTest, ValidationNamesWaypointOrSegment) {
  ExpectThrowsWith([] { JointTrajectory::Create({}); }, "no waypoints");
  JointTrajectoryConfig c = ThreeWaypoints();
  c.waypoints[2] = Eigen::Vector2d(1, 2);
  ExpectThrowsWith([&] { JointTrajectory::Create(c); }, "waypoint 2 has 2 joints");
  c = ThreeWaypoints();
  c.waypoints[1][0] = std::nan("");
  ExpectThrowsWith([&] { JointTrajectory::Create(c); }, "waypoint 1 is not finite");
  c = ThreeWaypoints();
  c.segments[1].duration_s = 0.0;
  ExpectThrowsWith([&] { JointTrajectory::Create(c); }, "segment 1 (waypoint 1 -> 2)");
  c = ThreeWaypoints();
  c.segments.pop_back();
  ExpectThrowsWith([&] { JointTrajectory::Create(c); }, "need 2 segments");
}

// --- Cartesian trajectory ---------------------------------------------------

CartesianTrajectoryConfig TwoSegments() {
  CartesianTrajectoryConfig c;
  c.waypoints = {MakePose({0.4, 0.0, 0.5}, Rot(0.3, {1, 0, 0})), MakePose({0.5, 0.2, 0.3}, Rot(2.5, {0.2, 1, -0.4})),
                 MakePose({0.3, -0.1, 0.6}, Rot(-1.0, {1, 1, 1}))};
  c.segments = {SegmentTiming{1.0, {TimeScalingType::kQuintic, 0.25}},
                SegmentTiming{1.5, {TimeScalingType::kTrapezoidal, 0.2}}};
  return c;
}

double AngleBetween(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return Eigen::AngleAxisd(A * B.transpose()).angle();
}

TEST(CartesianTrajectoryTest, EndpointsExact) {
  const CartesianTrajectoryConfig c = TwoSegments();
  auto traj = CartesianTrajectory::Create(c);
  EXPECT_DOUBLE_EQ(traj->duration_s(), 2.5);
  const double times[] = {0.0, 1.0, 2.5};
  for (int i = 0; i < 3; ++i) {
    const CartesianSample s = traj->Evaluate(times[i]);
    EXPECT_LT((s.pose.p_W - c.waypoints[i].p_W).norm(), 1e-12) << "waypoint " << i;
    EXPECT_LT(AngleBetween(s.pose.R_W, c.waypoints[i].R_W), 1e-9) << "waypoint " << i;
    EXPECT_LT(s.v_W.norm() + s.w_W.norm(), 1e-12) << "waypoint " << i;
  }
  EXPECT_FALSE(traj->Evaluate(2.4).done);
  const CartesianSample end = traj->Evaluate(3.0);
  EXPECT_TRUE(end.done);
  EXPECT_LT((end.pose.p_W - c.waypoints[2].p_W).norm(), 1e-15);
  EXPECT_LT(AngleBetween(end.pose.R_W, c.waypoints[2].R_W), 1e-9);
  EXPECT_LT((traj->Evaluate(-1.0).pose.p_W - c.waypoints[0].p_W).norm(), 1e-15);
}

TEST(CartesianTrajectoryTest, PositionStaysOnSegmentLine) {
  const CartesianTrajectoryConfig c = TwoSegments();
  auto traj = CartesianTrajectory::Create(c);
  const Eigen::Vector3d a = c.waypoints[0].p_W, b = c.waypoints[1].p_W;
  const Eigen::Vector3d u = (b - a).normalized();
  for (double t = 0.0; t <= 1.0; t += 0.01) {
    const Eigen::Vector3d p = traj->Evaluate(t).pose.p_W;
    const Eigen::Vector3d d = p - a;
    EXPECT_LT((d - d.dot(u) * u).norm(), 1e-14) << "t = " << t;  // distance from the line
    EXPECT_GE(d.dot(u), -1e-15);
    EXPECT_LE(d.dot(u), (b - a).norm() + 1e-15);
  }
}

TEST(CartesianTrajectoryTest, VelocitiesMatchFiniteDifferences) {
  auto traj = CartesianTrajectory::Create(TwoSegments());
  const double h = 1e-6;
  for (double t : {0.05, 0.3, 0.5, 0.77, 1.1, 1.5, 2.0, 2.4}) {
    const CartesianSample s = traj->Evaluate(t);
    const CartesianSample sp = traj->Evaluate(t + h);
    const CartesianSample sm = traj->Evaluate(t - h);
    const Eigen::Vector3d v_fd = (sp.pose.p_W - sm.pose.p_W) / (2 * h);
    // world-frame angular velocity: log(R(t+h)·R(t−h)ᵀ) / 2h
    const Eigen::Vector3d w_fd = RotationVector(sp.pose.R_W * sm.pose.R_W.transpose()) / (2 * h);
    EXPECT_LT((s.v_W - v_fd).norm(), 1e-6) << "t = " << t;
    EXPECT_LT((s.w_W - w_fd).norm(), 1e-6) << "t = " << t;
    EXPECT_LT((s.a_W - (sp.v_W - sm.v_W) / (2 * h)).norm(), 1e-5) << "t = " << t;
    EXPECT_LT((s.alpha_W - (sp.w_W - sm.w_W) / (2 * h)).norm(), 1e-5) << "t = " << t;
    EXPECT_GT(s.w_W.norm(), 1e-3);  // the check is not vacuous
  }
}

TEST(CartesianTrajectoryTest, SlerpTakesShortWayForEitherQuaternionSign) {
  // 170° apart: the short way is 170° about +z, the long way 190° about −z
  const Eigen::Matrix3d R0 = Rot(0.4, {0, 1, 0});
  const Eigen::Matrix3d R1 = Rot(170.0 * kPi / 180.0, {0, 0, 1}) * R0;
  const Eigen::Quaterniond q1(R1);
  for (double sign : {1.0, -1.0}) {
    Eigen::Quaterniond q1s = q1;
    q1s.coeffs() *= sign;
    CartesianTrajectoryConfig c;
    c.waypoints = {MakePose({0, 0, 0}, R0), MakePose({0, 0, 0}, q1s.toRotationMatrix())};
    c.segments = {SegmentTiming{}};
    auto traj = CartesianTrajectory::Create(c);
    const CartesianSample mid = traj->Evaluate(0.5);
    EXPECT_LT(AngleBetween(mid.pose.R_W, Rot(85.0 * kPi / 180.0, {0, 0, 1}) * R0), 1e-9) << "sign " << sign;
    EXPECT_GT(mid.w_W.z(), 0.0);
    EXPECT_LT(mid.w_W.head<2>().norm(), 1e-12);
    // the rotation swept over the segment is 170°, not 190°
    double swept = 0.0;
    for (int k = 0; k < 1000; ++k) swept += traj->Evaluate((k + 0.5) / 1000.0).w_W.norm() / 1000.0;
    EXPECT_NEAR(swept, 170.0 * kPi / 180.0, 1e-5);
  }
  // a quaternion passed as −q (via a rotation matrix, both signs equal) too:
  // the internal representative flip is exercised when q0·q1 < 0
  const Eigen::Matrix3d Ra = Rot(3.0, {1, 0, 0});
  const Eigen::Matrix3d Rb = Rot(-3.0, {1, 0, 0});  // 0.28 rad from Ra the short way
  CartesianTrajectoryConfig c;
  c.waypoints = {MakePose({0, 0, 0}, Ra), MakePose({0, 0, 0}, Rb)};
  c.segments = {SegmentTiming{}};
  auto traj = CartesianTrajectory::Create(c);
  EXPECT_LT(AngleBetween(traj->Evaluate(0.5).pose.R_W, Rot(kPi, {1, 0, 0})), 1e-9);
}

TEST(CartesianTrajectoryTest, ValidationNamesWaypointOrSegment) {
  ExpectThrowsWith([] { CartesianTrajectory::Create({}); }, "no waypoints");
  CartesianTrajectoryConfig c = TwoSegments();
  c.waypoints[1].R_W(0, 0) += 0.01;
  ExpectThrowsWith([&] { CartesianTrajectory::Create(c); }, "waypoint 1: R_W is not a rotation");
  c = TwoSegments();
  c.waypoints[2].R_W = -c.waypoints[2].R_W;  // reflection
  ExpectThrowsWith([&] { CartesianTrajectory::Create(c); }, "waypoint 2: R_W is not a rotation");
  c = TwoSegments();
  c.waypoints[0].p_W.x() = INFINITY;
  ExpectThrowsWith([&] { CartesianTrajectory::Create(c); }, "waypoint 0 is not finite");
  c = TwoSegments();
  c.segments[0].duration_s = -1.0;
  ExpectThrowsWith([&] { CartesianTrajectory::Create(c); }, "segment 0 (waypoint 0 -> 1)");
  c = TwoSegments();
  c.segments.push_back(SegmentTiming{});
  ExpectThrowsWith([&] { CartesianTrajectory::Create(c); }, "need 2 segments");
  // a single pose is a hold
  c = TwoSegments();
  c.waypoints.resize(1);
  c.segments.clear();
  auto hold = CartesianTrajectory::Create(c);
  EXPECT_TRUE(hold->Evaluate(0.0).done);
  EXPECT_LT((hold->Evaluate(1.0).pose.p_W - c.waypoints[0].p_W).norm(), 1e-15);
}

}  // namespace
}  // namespace vlab::control
