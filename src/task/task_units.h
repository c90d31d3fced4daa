// Small shared pieces of the task library's numerics: degrees, the damped
// Newton steps of the inverse kinematics (task_motion.cc's moves and
// task_kinematics.cc's branches take the same steps), a cross-product matrix
// and the number format of error messages.
#pragma once

#include <cstdio>
#include <string>

#include <Eigen/Core>

namespace vlab::task {

/// Degrees to radians: scripts speak degrees, the planner radians.
inline constexpr double kDeg = 3.14159265358979323846 / 180.0;

/// Damping of a Newton step of the inverse kinematics (Levenberg-Marquardt, on J Jᵀ).
inline constexpr double kIkDamping = 1e-6;
/// Longest Newton step, rad (norm over the joints): keeps a far target on the near branch.
inline constexpr double kIkMaxStep_rad = 0.3;

/// The matrix of r × (.).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& r) {
  Eigen::Matrix3d s;
  s << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return s;
}

/// A number for an error message (printf `format`, default 4 significant digits).
inline std::string FormatNumber(double v, const char* format = "%.4g") {
  char b[48];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

}  // namespace vlab::task
