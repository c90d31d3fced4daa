// The fit: box-constrained nonlinear least squares over the windows' residuals (Ceres,
// Levenberg-Marquardt), a finite-difference Jacobian from rollouts in parallel threads,
// and the statistics of the estimates.
//
// Determinism: every rollout (a window at one parameter vector) is computed alone and
// written to its own place, and Ceres sees one residual block, so the result is the same
// bit for bit for any thread count.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "identify/identify_linear.h"
#include "identify/identify_problem.h"

namespace vlab::identify {

/// Thresholds that flag a parameter the data cannot tell (docs/identify.md, "How it works").
/// A Jacobian column (in the scaled units value / scale) whose norm is at most this
/// fraction of the largest column's at the nominal values: the data do not excite it.
inline constexpr double kUnexcitedColumn = 1e-6;
/// A standard deviation above this fraction of the parameter's scale: poorly determined.
inline constexpr double kPoorSd = 0.1;
/// |correlation| above this with another parameter: the data cannot tell the two apart.
inline constexpr double kCorrelated = 0.99;

struct FitOptions {
  int threads = 1;  ///< rollout threads (>= 1)
  /// Where the fit starts; unset: the spec's `first_estimate`.
  std::optional<FirstEstimate> first_estimate;
  /// Called after each Ceres iteration: iteration, cost (half the sum of squares).
  std::function<void(int iteration, double cost)> progress;
  /// Called once before the iterations with a line on the start (which first estimate, its cost).
  std::function<void(const std::string& line)> message;
};

/// One parameter's result.
struct Estimate {
  std::string name;
  double nominal = 0;
  double value = 0;
  double sd = 0;             ///< standard deviation, windows as independent samples (infinite: not determined)
  double sd_iid = 0;         ///< the same from J^T J and the residual variance alone
  bool frozen = false;       ///< by the spec: not fitted
  bool excited = true;       ///< false: the data do not move it (kept at its nominal)
  bool identifiable = true;  ///< excited, sd small, no |correlation| above kCorrelated
  std::string note;          ///< why not identifiable ("" when it is)
};

struct FitResult {
  std::vector<Estimate> estimates;  ///< in the spec's order
  Eigen::MatrixXd correlation;      ///< over all parameters (0 rows/columns for those not fitted)
  double cost_nominal = 0;          ///< half the sum of squared residuals at the nominal values
  double cost_start = 0;            ///< the same where the fit started
  std::string first_estimate;       ///< where it started: "linear" or "nominal"
  std::string first_estimate_note;  ///< why "nominal" when the spec asked for "linear" ("" otherwise)
  LinearEstimate linear;            ///< the linear estimate (applies false: not made, or why not)
  double cost_fitted = 0;
  double residual_sd = 0;  ///< sqrt(sum r^2 / (residuals - fitted parameters)), weighted units
  int residuals = 0;
  int windows = 0;
  int iterations = 0;
  int rollouts = 0;         ///< window rollouts simulated in all
  std::string termination;  ///< Ceres's message
  double wall_s = 0;
  std::vector<double> nominal_values, start_values, fitted_values;  ///< all parameters
};

/// Fits the problem's free parameters from the first estimate (the linear estimate where it
/// applies and is asked for, else the nominal values). Throws std::runtime_error when the
/// starting model's rollouts diverge.
FitResult Fit(const Problem& problem, const FitOptions& options);

/// x with six significant digits (%.6g), for the progress line and the report.
std::string SixDigits(double x);

/// The predicted columns of every window at `values` (residual order), for plots; false
/// when a rollout diverged.
bool Predict(const Problem& problem, const std::vector<double>& values, int threads, std::vector<double>* predicted);

}  // namespace vlab::identify
