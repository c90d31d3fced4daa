// The linear first estimate of an identification: the joint torques of a rigid chain are
// linear in its dynamic parameters (tau = Y(q, qd, qdd) · pi, control/dynamics_regressor.h),
// and pi is affine in a body's mass (its first moments and inertia scale with it at a fixed
// centre), a joint's damping, armature and friction loss. So those parameters follow from the
// logs' q, qd and tau by linear least squares, without a rollout; the nonlinear fit
// (identify_fit.h) starts from there. docs/identify.md, "How it works".
//
// Per log row r (the rows within `half_window` of a log's end left out): each joint's q and
// qd are fitted by a cubic over rows r - H .. r + H (Savitzky-Golay); qdd is the fitted qd's
// slope in the middle of the period that ends at the row (the row's torque acted over it),
// q and qd are read where the simulator evaluated its forces in that period (MuJoCo's Euler:
// at the start of each step, the damping at each step's end). The rows of the arm joints are
// stacked: tau - Y·pi(nominal) = sum_p Y·dpi/dtheta_p · (theta_p - nominal_p), solved by
// weighted least squares (each joint's rows weighted by 1 / the rms of its residual after an
// unweighted pass).
//
// Left out: a sample whose recorded state is in contact; a joint's row whose torque is at
// its motor's limit (clipped); a joint's row slower than `min_speed` when the joint has
// friction loss (nominal or fitted: the Coulomb model holds only in motion). Parameters of
// other kinds (a sensor's bias, gain, delay) and frozen ones keep their nominal values
// (the frozen ones are known terms); so do those the regression cannot determine (a column
// of Y·dpi/dtheta that is zero or a combination of others: QR with column pivoting).
// Estimates are clamped within their bounds.
#pragma once

#include <string>
#include <vector>

#include "identify/identify_problem.h"

namespace vlab::identify {

/// The parameter kinds the linear estimate covers: pi (the regressor's parameters) must be
/// affine in them. The one place to add a kind (a payload's mass, say); a kind listed here
/// whose pi is not affine is caught at run time (std::logic_error).
bool LinearKind(TargetKind kind);

struct LinearOptions {
  int half_window = 40;          ///< rows on each side of the Savitzky-Golay polynomial, > degree
  int degree = 3;                ///< of the Savitzky-Golay polynomial, >= 2
  double min_speed = 0.05;       ///< rad/s (m/s): slower rows of a joint with friction loss left out
  double rank_tolerance = 1e-8;  ///< pivots below this fraction of the largest: undetermined
};

/// How the linear estimate treats a parameter.
enum class LinearStatus {
  kEstimated,     ///< estimated by the regression
  kUndetermined,  ///< covered, but the data cannot tell it (rank): nominal
  kNotCovered,    ///< not a LinearKind, or frozen: nominal
};

struct LinearEstimate {
  bool applies = false;        ///< false: nothing to estimate, or the model is no chain (why)
  std::string why;             ///< why it does not apply ("" when it does)
  std::vector<double> values;  ///< every parameter: the estimate, clamped; nominal where not estimated
  std::vector<double> raw;     ///< the estimate before clamping (nominal where not estimated)
  std::vector<LinearStatus> status;
  int samples = 0;                   ///< log rows used
  int torque_rows = 0;               ///< joint equations in the least squares
  int left_out_contact = 0;          ///< samples in contact
  int left_out_clipped = 0;          ///< joint rows at a torque limit
  int left_out_slow = 0;             ///< joint rows slower than min_speed with friction loss
  int rank = 0;                      ///< of the estimated columns
  std::vector<double> residual_rms;  ///< per arm joint: the weighted pass's torque residual (N·m)
};

/// The linear estimate of the problem's parameters from its logs. Never throws for a model
/// it does not apply to (applies false, why set).
LinearEstimate EstimateLinear(const Problem& problem, const LinearOptions& options = {});

/// "S2 damping estimated", ... : the status as words for outputs.
const char* LinearStatusText(LinearStatus status);

}  // namespace vlab::identify
