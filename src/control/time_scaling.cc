#include "control/time_scaling.h"

#include <cmath>
#include <stdexcept>

namespace vlab::control {

void ValidateTimeScaling(const TimeScaling& scaling, double duration_s, const std::string& where) {
  if (!std::isfinite(duration_s) || duration_s <= 0.0) {
    throw std::invalid_argument(where + ": duration_s must be finite and > 0, got " + std::to_string(duration_s));
  }
  if (scaling.type == TimeScalingType::kTrapezoidal) {
    const double a = scaling.acceleration_fraction;
    if (!std::isfinite(a) || a <= 0.0 || a > 0.5) {
      throw std::invalid_argument(where + ": acceleration_fraction must lie in (0, 0.5], got " + std::to_string(a));
    }
  } else if (scaling.type != TimeScalingType::kQuintic) {
    throw std::invalid_argument(where + ": unknown time scaling type");
  }
}

ScalingSample EvaluateTimeScaling(const TimeScaling& scaling, double T, double t) {
  ScalingSample out;
  // clamp: at rest at 0 before the start, at rest at 1 after the end
  if (t <= 0.0) return out;
  if (t >= T) {
    out.s = 1.0;
    return out;
  }
  if (scaling.type == TimeScalingType::kQuintic) {
    const double tau = t / T;
    const double tau2 = tau * tau;
    const double tau3 = tau2 * tau;
    out.s = tau3 * (10.0 - 15.0 * tau + 6.0 * tau2);
    out.sd = 30.0 * tau2 * (1.0 - 2.0 * tau + tau2) / T;
    out.sdd = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * tau2) / (T * T);
    return out;
  }
  // trapezoid: accelerate for ta, cruise at v, decelerate for the last ta
  const double ta = scaling.acceleration_fraction * T;
  const double v = 1.0 / (T - ta);
  const double acc = v / ta;
  if (t < ta) {
    out.s = 0.5 * acc * t * t;
    out.sd = acc * t;
    out.sdd = acc;
  } else if (t <= T - ta) {
    out.s = 0.5 * acc * ta * ta + v * (t - ta);
    out.sd = v;
    out.sdd = 0.0;
  } else {
    const double r = T - t;
    out.s = 1.0 - 0.5 * acc * r * r;
    out.sd = acc * r;
    out.sdd = -acc;
  }
  return out;
}

double PeakScalingSpeed(const TimeScaling& scaling, double T) {
  if (scaling.type == TimeScalingType::kQuintic) return 15.0 / (8.0 * T);
  return 1.0 / (T * (1.0 - scaling.acceleration_fraction));
}

}  // namespace vlab::control
