// The excitation trajectory an identification runs (excitation_trajectory.h):
// the Fourier coefficients that minimise the condition number of the
// regressor (dynamics_regressor.h) stacked over the trajectory, within the
// joints' position, speed and acceleration limits and clear of the scene.
//
// Criterion: cond(W) of W = Y(q(t_k), qd(t_k), qdd(t_k)) stacked over samples
// t_k of one period, its columns the base parameters (FindBaseParameters over
// random states in the joints' ranges: the columns that are zero or linear
// combinations of others for any motion are dropped first, or cond is inf).
// Parameters in SI units, unscaled (Swevers et al. 1997).
//
// Constraints, kept exactly: every joint within its range less a margin, its
// speed and acceleration within a fraction of its limits, sampled as a task
// streams the trajectory (MeasurePeaks). A candidate beyond them is brought
// within by scaling each joint's coefficients (the motion about q_start is
// linear in them), so the search only sees trajectories that keep them.
// Workspace: every geom of the arm (the bodies its joints move) at least
// `clearance_m` from every other geom (the scene's table and floor, the arm's
// other links) at the samples, pairs already that close at the start pose
// excepted (MuJoCo's collision detection with the margin set to the
// clearance); a candidate that comes closer is penalised.
//
// Search: a (1+1) evolution strategy with the one-fifth success rule
// (Rechenberg 1973) from seeded random starts, the best kept; deterministic
// for a seed (its own generator: mt19937_64 and Box-Muller).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include "control/dynamics_regressor.h"
#include "control/excitation_trajectory.h"

namespace vlab::control {

struct ExcitationConfig {
  int harmonics = 5;                          ///< N, per joint (>= 2: two coefficients go to the constraints)
  double period_s = 10;                       ///< one period of the series, s
  double control_period_s = 0.002;            ///< the task's period: the limits are checked at its samples
  int regressor_samples = 100;                ///< samples of one period in W
  int clearance_samples = 250;                ///< samples of one period checked for clearance in the search
  double position_margin_rad = 0.0872664626;  ///< 5 deg inside each joint's range
  double rate_fraction = 0.9;                 ///< of the speed and acceleration limits
  double clearance_m = 0.01;                  ///< from the scene and between links
  std::uint64_t seed = 1;
  int restarts = 4;        ///< random starts
  int evaluations = 1600;  ///< of the criterion, all starts together
};

struct ExcitationResult {
  FourierExcitation trajectory;
  double cond_initial = 0;  ///< the best random start's, before the search
  double cond_final = 0;
  BaseParameters base;     ///< the columns of Y in the criterion
  int evaluations = 0;     ///< of the criterion
  JointPeaks peaks;        ///< of the result (MeasurePeaks at the control period)
  double clearance_m = 0;  ///< the smallest distance found at the control-period samples (capped at the margin)
  std::string closest;     ///< the geoms of that distance, "GEOM1 / GEOM2" ("" when none came within)
};

/// Optimises the excitation of `regressor`'s joints from `q_start` (rad).
/// `model` is the scene (the regressor's), `reference_qpos` its pose for the
/// joints outside the chain (nq values). `limits.lower/upper` the joint
/// ranges (the margin is applied here), v_max and a_max the speed and
/// acceleration limits. Throws std::invalid_argument naming the bad input (a
/// start pose within the margin of a limit, a period that is no whole number
/// of control periods, harmonics < 2, ...) or, when no candidate keeps clear
/// of the scene, naming the closest pair of geoms.
ExcitationResult OptimizeExcitation(const mjModel* model, DynamicsRegressor* regressor,
                                    const std::vector<double>& reference_qpos, const Eigen::VectorXd& q_start,
                                    const JointLimits& limits, const ExcitationConfig& config);

}  // namespace vlab::control
