#include "control/excitation_trajectory.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace vlab::control {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

std::string Format(const char* format, const std::string& joint, double x, double limit) {
  char line[200];
  std::snprintf(line, sizeof line, format, joint.c_str(), x, limit);
  return line;
}

}  // namespace

Eigen::VectorXd FourierExcitation::Offsets() const {
  const double w = 2 * kPi / period_s;
  Eigen::VectorXd q0 = q_start;
  for (int i = 0; i < dof(); ++i) {
    for (int l = 1; l <= harmonics(); ++l) q0[i] += b(i, l - 1) / (w * l);
  }
  return q0;
}

void FourierExcitation::Evaluate(double t, Eigen::VectorXd* q, Eigen::VectorXd* qd, Eigen::VectorXd* qdd) const {
  const double w = 2 * kPi / period_s;
  const int n = dof();
  if (q) *q = Offsets();
  if (qd) qd->setZero(n);
  if (qdd) qdd->setZero(n);
  for (int l = 1; l <= harmonics(); ++l) {
    const double wl = w * l, s = std::sin(wl * t), c = std::cos(wl * t);
    for (int i = 0; i < n; ++i) {
      const double ai = a(i, l - 1), bi = b(i, l - 1);
      if (q) (*q)[i] += (ai * s - bi * c) / wl;
      if (qd) (*qd)[i] += ai * c + bi * s;
      if (qdd) (*qdd)[i] += wl * (bi * c - ai * s);
    }
  }
}

double FourierExcitation::ConstraintResidual() const {
  double worst = 0;
  for (int i = 0; i < dof(); ++i) {
    double sum_a = 0, sum_lb = 0;
    for (int l = 1; l <= harmonics(); ++l) sum_a += a(i, l - 1), sum_lb += l * b(i, l - 1);
    worst = std::max({worst, std::abs(sum_a), std::abs(sum_lb)});
  }
  return worst;
}

JointPeaks MeasurePeaks(const FourierExcitation& traj, double control_period_s) {
  const double steps = traj.period_s / control_period_s;
  const long k_end = std::lround(steps);
  if (!(control_period_s > 0) || k_end < 3 || std::abs(steps - k_end) > 1e-6) {
    throw std::invalid_argument("excitation: the period must be a whole number (at least 3) of control periods");
  }
  const int n = traj.dof();
  JointPeaks p;
  p.q_min = p.q_max = traj.q_start;
  p.v_abs.setZero(n);
  p.a_abs.setZero(n);
  // from rest at q_start (two samples there), one period, then held at its end (rest)
  Eigen::VectorXd q_prev = traj.q_start, v_prev = Eigen::VectorXd::Zero(n), q;
  for (long k = 1; k <= k_end + 1; ++k) {
    if (k <= k_end) {
      traj.Evaluate(k * control_period_s, &q, nullptr, nullptr);
    } else {
      q = q_prev;
    }
    const Eigen::VectorXd v = (q - q_prev) / control_period_s;
    const Eigen::VectorXd acc = (v - v_prev) / control_period_s;
    p.q_min = p.q_min.cwiseMin(q);
    p.q_max = p.q_max.cwiseMax(q);
    p.v_abs = p.v_abs.cwiseMax(v.cwiseAbs());
    p.a_abs = p.a_abs.cwiseMax(acc.cwiseAbs());
    q_prev = q;
    v_prev = v;
  }
  return p;
}

std::string CheckPeaks(const JointPeaks& peaks, const JointLimits& limits, const std::vector<std::string>& joints) {
  for (int i = 0; i < static_cast<int>(joints.size()); ++i) {
    const std::string& j = joints[i];
    if (peaks.q_max[i] > limits.upper[i]) {
      return Format("joint %s reaches %.4g deg, beyond its upper limit %.4g deg", j, peaks.q_max[i] / kDeg,
                    limits.upper[i] / kDeg);
    }
    if (peaks.q_min[i] < limits.lower[i]) {
      return Format("joint %s reaches %.4g deg, beyond its lower limit %.4g deg", j, peaks.q_min[i] / kDeg,
                    limits.lower[i] / kDeg);
    }
    if (peaks.v_abs[i] > limits.v_max[i]) {
      return Format("joint %s needs %.4g deg/s, its limit is %.4g deg/s", j, peaks.v_abs[i] / kDeg,
                    limits.v_max[i] / kDeg);
    }
    if (peaks.a_abs[i] > limits.a_max[i]) {
      return Format("joint %s needs %.4g deg/s^2, its limit is %.4g deg/s^2", j, peaks.a_abs[i] / kDeg,
                    limits.a_max[i] / kDeg);
    }
  }
  return "";
}

}  // namespace vlab::control
