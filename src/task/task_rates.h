// Joint speed and acceleration limits of the task language's moves: what a
// sampled joint path needs (finite differences at the control period) against
// what the arm allows, and by how much its timing must be stretched to keep
// within.
//
// Defaults (docs/tasks.md, "Joint speed and acceleration limits"): 180 deg/s
// for every PA10 joint (Choreonoid's PA10 jointVelocityRange); 180 deg/s² for
// the arm joints (a PA10 device file's JointAccLimit of axis 0) and, an
// estimate, 360 deg/s² for the last three (the wrist).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace vlab::task {

/// 180 deg/s: the default speed limit of every joint, rad/s.
constexpr double kJointSpeedLimitDefault_rps = 3.14159265358979323846;
/// 180 deg/s²: the default acceleration limit of the arm's joints, rad/s².
constexpr double kJointAccelLimitDefault_rps2 = 3.14159265358979323846;
/// 360 deg/s²: the default acceleration limit of the wrist (the last three joints), rad/s².
constexpr double kWristAccelLimitDefault_rps2 = 2 * kJointAccelLimitDefault_rps2;

/// The arm's joint limits every move keeps, and what a move beyond them does.
struct JointRateLimits {
  Eigen::VectorXd v_rps;   ///< speed limit per chain joint, rad/s (> 0)
  Eigen::VectorXd a_rps2;  ///< acceleration limit per chain joint, rad/s² (> 0)
  bool refuse = false;     ///< true: a move beyond them is an error; false (default): it is slowed down
};

/// The defaults for a chain of `dof` joints (its last three the wrist).
JointRateLimits DefaultRateLimits(int dof);

/// Peak |speed| and |acceleration| per joint of a sampled joint path.
struct JointRates {
  Eigen::VectorXd v_rps;   ///< rad/s
  Eigen::VectorXd a_rps2;  ///< rad/s²
};

/// Peak rates of the samples q[0..] one period_s apart, by finite differences:
/// v_i = (q_i − q_{i−1})/T, a_i = (v_i − v_{i−1})/T. A path that starts at rest
/// repeats its start (q[0] = q[1]); one that ends at rest repeats its end.
/// Needs at least one sample.
JointRates PeakRates(const std::vector<Eigen::VectorXd>& q, double period_s);

/// How the peak rates compare with the limits: the time stretch that brings
/// them within (speeds scale by 1/k, accelerations by 1/k²), and the joint
/// that sets it.
struct RateExcess {
  double stretch = 1;  ///< k >= 1: 1 when within the limits
  int joint = -1;      ///< the joint of the largest k (-1: within)
};
RateExcess Excess(const JointRates& rates, const JointRateLimits& limits);

/// The refusal of a move beyond the limits: "joint S2 needs 535 deg/s and
/// 2.1e+04 deg/s^2; its limits are 180 deg/s and 180 deg/s^2 (...)".
std::string ExcessMessage(const JointRates& rates, const JointRateLimits& limits, const RateExcess& excess,
                          const std::string& joint_name);

}  // namespace vlab::task
