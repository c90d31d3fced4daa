#include "control/trajectory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vlab::control {

namespace {

std::string SegmentName(size_t i) {
  return "trajectory segment " + std::to_string(i) + " (waypoint " + std::to_string(i) + " -> " +
         std::to_string(i + 1) + ")";
}

// checks the segment count and timings; returns cumulative end times
std::vector<double> ValidateSegments(size_t num_waypoints, const std::vector<SegmentTiming>& segments) {
  if (num_waypoints == 0) throw std::invalid_argument("trajectory: no waypoints (need at least 1)");
  if (segments.size() != num_waypoints - 1) {
    throw std::invalid_argument("trajectory: " + std::to_string(num_waypoints) + " waypoints need " +
                                std::to_string(num_waypoints - 1) + " segments, got " +
                                std::to_string(segments.size()));
  }
  std::vector<double> end_times;
  double t = 0.0;
  for (size_t i = 0; i < segments.size(); ++i) {
    ValidateTimeScaling(segments[i].scaling, segments[i].duration_s, SegmentName(i));
    t += segments[i].duration_s;
    end_times.push_back(t);
  }
  return end_times;
}

// index of the segment active at time t (t inside [0, end)), or -1 past the end
int FindSegment(const std::vector<double>& end_times, double t) {
  const auto it = std::upper_bound(end_times.begin(), end_times.end(), t);
  if (it == end_times.end()) return -1;
  return static_cast<int>(it - end_times.begin());
}

}  // namespace

Eigen::Vector3d RotationVector(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  // θ = 2·atan2(|ε|, η); θ/|ε| → 2/η as |ε| → 0
  if (n < 1e-12) return (2.0 / q.w()) * q.vec();
  return (2.0 * std::atan2(n, q.w()) / n) * q.vec();
}

// --- joint trajectory -----------------------------------------------------

std::unique_ptr<JointTrajectory> JointTrajectory::Create(const JointTrajectoryConfig& config) {
  std::vector<double> end_times = ValidateSegments(config.waypoints.size(), config.segments);
  const Eigen::Index n = config.waypoints.front().size();
  if (n == 0) throw std::invalid_argument("joint trajectory: waypoint 0 is empty");
  for (size_t i = 0; i < config.waypoints.size(); ++i) {
    const Eigen::VectorXd& w = config.waypoints[i];
    if (w.size() != n) {
      throw std::invalid_argument("joint trajectory: waypoint " + std::to_string(i) + " has " +
                                  std::to_string(w.size()) + " joints, waypoint 0 has " + std::to_string(n));
    }
    if (!w.allFinite()) {
      throw std::invalid_argument("joint trajectory: waypoint " + std::to_string(i) + " is not finite");
    }
  }
  std::unique_ptr<JointTrajectory> traj(new JointTrajectory());
  traj->waypoints_ = config.waypoints;
  traj->segments_ = config.segments;
  traj->end_times_ = std::move(end_times);
  return traj;
}

JointSample JointTrajectory::Evaluate(double t) const {
  JointSample out;
  Evaluate(t, &out);
  return out;
}

void JointTrajectory::Evaluate(double t, JointSample* out) const {
  const int i = t < 0.0 ? -2 : FindSegment(end_times_, t);
  out->done = (i == -1);
  if (i < 0) {
    // hold the first waypoint before the start, the last one after the end
    out->q = i == -2 ? waypoints_.front() : waypoints_.back();
    out->qd.setZero(dof());
    out->qdd.setZero(dof());
    return;
  }
  const SegmentTiming& seg = segments_[i];
  const double t0 = end_times_[i] - seg.duration_s;
  const ScalingSample s = EvaluateTimeScaling(seg.scaling, seg.duration_s, t - t0);
  const Eigen::VectorXd& a = waypoints_[i];
  const Eigen::VectorXd& b = waypoints_[i + 1];
  out->q = a + s.s * (b - a);
  out->qd = s.sd * (b - a);
  out->qdd = s.sdd * (b - a);
}

// --- Cartesian trajectory --------------------------------------------------

std::unique_ptr<CartesianTrajectory> CartesianTrajectory::Create(const CartesianTrajectoryConfig& config) {
  std::vector<double> end_times = ValidateSegments(config.waypoints.size(), config.segments);
  std::vector<Eigen::Quaterniond> quats;
  for (size_t i = 0; i < config.waypoints.size(); ++i) {
    const Pose& w = config.waypoints[i];
    const std::string name = "cartesian trajectory: waypoint " + std::to_string(i);
    if (!w.p_W.allFinite() || !w.R_W.allFinite()) throw std::invalid_argument(name + " is not finite");
    const double orth = (w.R_W.transpose() * w.R_W - Eigen::Matrix3d::Identity()).norm();
    if (orth > 1e-6 || w.R_W.determinant() < 0.0) {
      throw std::invalid_argument(name + ": R_W is not a rotation (|RᵀR − I| = " + std::to_string(orth) +
                                  ", det = " + std::to_string(w.R_W.determinant()) + ")");
    }
    quats.push_back(Eigen::Quaterniond(w.R_W).normalized());
  }
  std::unique_ptr<CartesianTrajectory> traj(new CartesianTrajectory());
  for (size_t i = 0; i + 1 < config.waypoints.size(); ++i) {
    Segment seg;
    seg.p0_W = config.waypoints[i].p_W;
    seg.dp_W = config.waypoints[i + 1].p_W - seg.p0_W;
    seg.q0 = quats[i];
    // pick the representative of the end orientation on q0's hemisphere (short arc)
    seg.q1 = quats[i + 1];
    if (seg.q0.dot(seg.q1) < 0.0) seg.q1.coeffs() = -seg.q1.coeffs();
    // world-frame rotation vector of R1·R0ᵀ, consistent with the chosen arc
    const Eigen::Quaterniond dq = seg.q1 * seg.q0.conjugate();
    const double n = dq.vec().norm();
    seg.rotvec_W = n < 1e-12 ? Eigen::Vector3d((2.0 / dq.w()) * dq.vec())
                             : Eigen::Vector3d((2.0 * std::atan2(n, dq.w()) / n) * dq.vec());
    seg.timing = config.segments[i];
    traj->segments_.push_back(seg);
  }
  traj->last_.p_W = config.waypoints.back().p_W;
  traj->last_.R_W = quats.back().toRotationMatrix();
  traj->end_times_ = std::move(end_times);
  return traj;
}

CartesianSample CartesianTrajectory::Evaluate(double t) const {
  CartesianSample out;
  const int i = t < 0.0 ? -2 : FindSegment(end_times_, t);
  out.done = (i == -1);
  if (i == -1 || segments_.empty()) {
    out.pose = last_;
    return out;
  }
  if (i == -2) {
    out.pose.p_W = segments_.front().p0_W;
    out.pose.R_W = segments_.front().q0.toRotationMatrix();
    return out;
  }
  const Segment& seg = segments_[i];
  const double t0 = end_times_[i] - seg.timing.duration_s;
  const ScalingSample s = EvaluateTimeScaling(seg.timing.scaling, seg.timing.duration_s, t - t0);
  out.pose.p_W = seg.p0_W + s.s * seg.dp_W;
  out.pose.R_W = seg.q0.slerp(s.s, seg.q1).toRotationMatrix();
  out.v_W = s.sd * seg.dp_W;
  out.a_W = s.sdd * seg.dp_W;
  out.w_W = s.sd * seg.rotvec_W;
  out.alpha_W = s.sdd * seg.rotvec_W;
  return out;
}

}  // namespace vlab::control
