// Test helpers for the JR3 model: an independent reference of the filter cascade.
#pragma once

#include <cmath>
#include <complex>
#include <vector>

#include "sensors/sensor_wrench.h"

namespace vlab::sensors::wrench_testing {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFs = 8000.0;
constexpr double kTs = 1.0 / kFs;

inline WrenchSensorConfig QuietConfig() {
  WrenchSensorConfig config;
  config.enable_noise = false;
  config.enable_bias = false;
  config.enable_quantization = false;
  return config;
}

// Independent reference for one stage: 2-pole Butterworth mapped pole by pole with the
// bilinear transform (prewarped), run as a direct-form-I difference equation.
struct ReferenceStage {
  double gain, c1, c2;  // y = gain (x + 2 x1 + x2) + c1 y1 - c2 y2
  double x1 = 0, x2 = 0, y1 = 0, y2 = 0;
  ReferenceStage(double cutoff_hz, double rate_hz) {
    const double omega_analog = 2.0 * rate_hz * std::tan(kPi * cutoff_hz / rate_hz);
    const std::complex<double> s = omega_analog * std::complex<double>(-1.0, 1.0) / std::sqrt(2.0);
    const std::complex<double> p = (1.0 + s / (2.0 * rate_hz)) / (1.0 - s / (2.0 * rate_hz));
    c1 = 2.0 * p.real();
    c2 = std::norm(p);
    gain = std::norm(1.0 - p) / 4.0;  // unit gain at z = 1
  }
  double Step(double x) {
    const double y = gain * (x + 2.0 * x1 + x2) + c1 * y1 - c2 * y2;
    x2 = x1;
    x1 = x;
    y2 = y1;
    y1 = y;
    return y;
  }
};

// Independent reference cascade on one axis: stage k runs every 4^(k-1) samples.
struct ReferenceCascade {
  std::vector<ReferenceStage> stages;
  std::vector<double> out = std::vector<double>(7, 0.0);
  long sample = 0;
  ReferenceCascade() {
    for (int k = 1; k <= 6; ++k) {
      const double rate = kFs / std::pow(4.0, k - 1);
      stages.emplace_back(rate / 16.0, rate);
    }
  }
  void Step(double x) {
    ++sample;
    out[0] = x;
    long period = 1;
    for (int k = 1; k <= 6; ++k, period *= 4) {
      if (sample % period == 0) out[k] = stages[k - 1].Step(out[k - 1]);
    }
  }
};

}  // namespace vlab::sensors::wrench_testing
