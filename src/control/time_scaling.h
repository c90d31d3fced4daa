// Time scalings: maps of time t ∈ [0, T] to a path parameter s ∈ [0, 1].
//
// A time scaling turns a geometric path x(s) into a trajectory x(s(t)); its first
// and second derivatives ṡ (1/s) and s̈ (1/s²) give the chain rule factors
// ẋ = x'(s)·ṡ and ẍ = x''(s)·ṡ² + x'(s)·s̈. Every scaling here starts and ends at
// rest (ṡ(0) = ṡ(T) = 0) and is clamped outside [0, T]: s = 0 before, s = 1 after,
// with ṡ = s̈ = 0 in both cases.
#pragma once

#include <string>

namespace vlab::control {

/// Shape of a time scaling.
enum class TimeScalingType {
  /// s = 10τ³ − 15τ⁴ + 6τ⁵ with τ = t/T: zero velocity and acceleration at both
  /// ends, peak speed 15/(8T) at τ = ½.
  kQuintic,
  /// Trapezoidal velocity: constant acceleration for a·T, cruise at 1/(T(1 − a)),
  /// constant deceleration for the last a·T. Acceleration jumps at the switches.
  kTrapezoidal,
};

/// Time-scaling configuration (plain data; validate with ValidateTimeScaling).
struct TimeScaling {
  TimeScalingType type = TimeScalingType::kQuintic;
  /// Trapezoidal only: fraction a of the duration spent accelerating (and the
  /// same fraction decelerating); must lie in (0, 0.5]. 0.5 gives a triangle.
  double acceleration_fraction = 0.25;
};

/// Value and time derivatives of s at one instant.
struct ScalingSample {
  double s = 0.0;    ///< path parameter, in [0, 1]
  double sd = 0.0;   ///< ds/dt, 1/s
  double sdd = 0.0;  ///< d²s/dt², 1/s²
};

/// Throws std::invalid_argument if `scaling` or `duration_s` is invalid
/// (duration must be finite and > 0; acceleration_fraction in (0, 0.5]). The
/// message starts with `where` (e.g. "segment 2") and names the field.
void ValidateTimeScaling(const TimeScaling& scaling, double duration_s, const std::string& where);

/// Evaluates the scaling of duration `duration_s` (s) at time `t_s` (s, measured
/// from the start of the scaling), clamped outside [0, duration_s]. Assumes
/// valid arguments (see ValidateTimeScaling); never throws or allocates.
ScalingSample EvaluateTimeScaling(const TimeScaling& scaling, double duration_s, double t_s);

/// Peak ṡ (1/s) of the scaling over its duration: 15/(8T) for the quintic,
/// 1/(T(1 − a)) for the trapezoid.
double PeakScalingSpeed(const TimeScaling& scaling, double duration_s);

}  // namespace vlab::control
