// Joint-space and Cartesian trajectories through waypoints.
//
// Both trajectories are piecewise: segment i runs from waypoint i to waypoint
// i + 1 over its own duration with its own time scaling (time_scaling.h), so
// every waypoint is reached at rest. Time t (s) is measured from the start of the
// trajectory; before 0 the first waypoint is held, after the last segment the last
// waypoint is held and `done` is set.
//
// Cartesian trajectories move the position on the straight line between
// waypoints and the orientation by quaternion SLERP along the shorter of the two
// arcs (a waypoint given as q or −q yields the same motion). All vectors are in
// the world frame W.
//
// Construction validates (std::invalid_argument naming the waypoint or segment);
// Evaluate never throws and, with a pre-sized output, never allocates.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "control/robot_model.h"
#include "control/time_scaling.h"

namespace vlab::control {

/// Timing of one segment between consecutive waypoints.
struct SegmentTiming {
  double duration_s = 1.0;  ///< > 0, s
  TimeScaling scaling;      ///< shape of s(t) over the segment
};

/// Joint trajectory definition.
struct JointTrajectoryConfig {
  /// Joint positions (rad or m), all the same size; at least one. A single
  /// waypoint (with no segments) is a hold.
  std::vector<Eigen::VectorXd> waypoints;
  /// One entry per pair of consecutive waypoints (waypoints.size() − 1 entries).
  std::vector<SegmentTiming> segments;
};

/// Joint trajectory sample.
struct JointSample {
  Eigen::VectorXd q;    ///< position, rad or m
  Eigen::VectorXd qd;   ///< velocity, rad/s or m/s
  Eigen::VectorXd qdd;  ///< acceleration, rad/s² or m/s²
  bool done = false;    ///< t is at or past the end of the last segment
};

/// Straight-line joint-space trajectory through waypoints.
class JointTrajectory {
 public:
  /// Validates and stores the trajectory. Throws std::invalid_argument naming
  /// the waypoint (size mismatch, non-finite entry) or segment (count, duration,
  /// time scaling) that is wrong.
  static std::unique_ptr<JointTrajectory> Create(const JointTrajectoryConfig& config);

  /// Number of joints.
  int dof() const { return static_cast<int>(waypoints_.front().size()); }
  /// Total duration, s (0 for a hold).
  double duration_s() const { return end_times_.empty() ? 0.0 : end_times_.back(); }

  /// Sample at time t (s from the start); allocates the returned vectors.
  JointSample Evaluate(double t_s) const;
  /// Same, into `out`; does not allocate when out's vectors already have dof()
  /// entries.
  void Evaluate(double t_s, JointSample* out) const;

 private:
  JointTrajectory() = default;
  std::vector<Eigen::VectorXd> waypoints_;
  std::vector<SegmentTiming> segments_;
  std::vector<double> end_times_;  // cumulative end time of each segment, s
};

/// Cartesian trajectory definition.
struct CartesianTrajectoryConfig {
  /// Poses in the world frame; at least one. Rotations must be orthonormal with
  /// determinant +1 (tolerance 1e-6). A single waypoint is a hold.
  std::vector<Pose> waypoints;
  /// One entry per pair of consecutive waypoints.
  std::vector<SegmentTiming> segments;
};

/// Cartesian trajectory sample, everything in the world frame.
struct CartesianSample {
  Pose pose;                                          ///< p_W (m), R_W (world <- frame)
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();      ///< linear velocity, m/s
  Eigen::Vector3d w_W = Eigen::Vector3d::Zero();      ///< angular velocity, rad/s
  Eigen::Vector3d a_W = Eigen::Vector3d::Zero();      ///< linear acceleration, m/s²
  Eigen::Vector3d alpha_W = Eigen::Vector3d::Zero();  ///< angular acceleration, rad/s²
  bool done = false;                                  ///< t is at or past the end of the last segment
};

/// Straight-line / SLERP Cartesian trajectory through waypoint poses.
///
/// On a segment from (p0, q0) to (p1, q1) with path parameter s(t):
///   p(s) = p0 + s·(p1 − p0),   q(s) = slerp(q0, q1, s)  (shorter arc)
///   v = ṡ·(p1 − p0),           ω = ṡ·θ·u_W
/// where θ ∈ [0, π] and u_W are the angle and world-frame axis of the rotation
/// R1·R0ᵀ taken the short way; u_W is constant along the segment, so the angular
/// acceleration is s̈·θ·u_W.
class CartesianTrajectory {
 public:
  /// Validates and stores the trajectory. Throws std::invalid_argument naming
  /// the waypoint (non-finite, rotation not orthonormal) or segment (count,
  /// duration, time scaling) that is wrong.
  static std::unique_ptr<CartesianTrajectory> Create(const CartesianTrajectoryConfig& config);

  /// Total duration, s (0 for a hold).
  double duration_s() const { return end_times_.empty() ? 0.0 : end_times_.back(); }

  /// Sample at time t (s from the start). Never throws or allocates.
  CartesianSample Evaluate(double t_s) const;

 private:
  struct Segment {
    Eigen::Vector3d p0_W, dp_W;  // start position and displacement, m
    Eigen::Quaterniond q0, q1;   // start and end orientation, q1 on q0's hemisphere
    Eigen::Vector3d rotvec_W;    // θ·u_W of the segment's rotation, rad
    SegmentTiming timing;
  };
  CartesianTrajectory() = default;
  std::vector<Segment> segments_;
  Pose last_;                      // final (or only) waypoint, held at the end
  std::vector<double> end_times_;  // cumulative end time of each segment, s
};

/// Rotation vector θ·u (rad) of a rotation matrix, θ ∈ [0, π], computed through
/// the quaternion with non-negative scalar part (robust near 0 and π).
Eigen::Vector3d RotationVector(const Eigen::Matrix3d& R);

}  // namespace vlab::control
