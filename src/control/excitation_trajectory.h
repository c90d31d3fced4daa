// An excitation trajectory for identifying an arm: a finite Fourier series per
// joint (Swevers, Ganseman, Tükel, De Schutter and Van Brussel, "Optimal robot
// excitation and identification", IEEE T-RA 13(5), 1997):
//
//   q_i(t) = q_i0 + sum_{l=1..N} a_il/(w l) sin(w l t) - b_il/(w l) cos(w l t)
//
// with w = 2 pi / period. It is periodic, so it can be run for several periods
// and the measurements averaged over them. With Swevers' constraints
//   sum_l a_il = 0 (qd(0) = 0), sum_l l b_il = 0 (qdd(0) = 0),
//   q_i0 = q_start_i + sum_l b_il/(w l) (q(0) = q_start)
// every period starts and ends at rest at the start pose, so a task can move
// the arm there, stream the series, and stop where it began without a ramp.
//
// Units: rad, rad/s, rad/s² for hinges (m for slides); coefficients a, b in
// rad/s (the velocity's amplitudes).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace vlab::control {

struct FourierExcitation {
  double period_s = 10;     ///< one period of the series, s (w = 2 pi / period_s)
  Eigen::VectorXd q_start;  ///< q(0) = q(k·period), the pose it starts and ends at rest in
  Eigen::MatrixXd a, b;     ///< dof x harmonics, rad/s (meeting the constraints above)

  int dof() const { return static_cast<int>(a.rows()); }
  int harmonics() const { return static_cast<int>(a.cols()); }
  /// q_i0 of the series (rad).
  Eigen::VectorXd Offsets() const;
  /// Position, velocity and acceleration at time t (s); any pointer may be null.
  void Evaluate(double t, Eigen::VectorXd* q, Eigen::VectorXd* qd, Eigen::VectorXd* qdd) const;
  /// The constraints' residuals: max |sum_l a_il| and |sum_l l b_il| (0 to rounding).
  double ConstraintResidual() const;
};

/// Limits of a trajectory, per joint (rad, rad/s, rad/s²).
struct JointLimits {
  Eigen::VectorXd lower, upper;  ///< position range
  Eigen::VectorXd v_max, a_max;  ///< speed and acceleration (> 0)
};

/// What a trajectory reaches, per joint, sampled as a task streams it: one
/// reference per control period T from rest at q_start, for one period of the
/// series, back to rest; speeds and accelerations by finite differences of the
/// samples, v_k = (q_k - q_{k-1})/T and a_k = (v_k - v_{k-1})/T (what the task
/// language's streaming command checks).
struct JointPeaks {
  Eigen::VectorXd q_min, q_max;  ///< rad
  Eigen::VectorXd v_abs, a_abs;  ///< max |qd|, max |qdd|, rad/s, rad/s²
};

/// The peaks of `traj` sampled every `control_period_s` (period_s must be a
/// whole number of control periods; std::invalid_argument otherwise).
JointPeaks MeasurePeaks(const FourierExcitation& traj, double control_period_s);

/// "" when every peak is within `limits`, else one line naming the first joint
/// beyond one (deg for hinges): "joint S2 reaches 95.3 deg, beyond its upper
/// limit 94 deg", "joint E1 needs 190.2 deg/s, its limit is 180 deg/s".
std::string CheckPeaks(const JointPeaks& peaks, const JointLimits& limits, const std::vector<std::string>& joints);

}  // namespace vlab::control
