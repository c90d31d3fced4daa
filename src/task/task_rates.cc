#include "task/task_rates.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "task/task_units.h"

namespace vlab::task {

JointRateLimits DefaultRateLimits(int dof) {
  JointRateLimits l;
  l.v_rps = Eigen::VectorXd::Constant(dof, kJointSpeedLimitDefault_rps);
  l.a_rps2 = Eigen::VectorXd::Constant(dof, kJointAccelLimitDefault_rps2);
  for (int j = std::max(0, dof - 3); j < dof; ++j) l.a_rps2[j] = kWristAccelLimitDefault_rps2;
  return l;
}

JointRates PeakRates(const std::vector<Eigen::VectorXd>& q, double period_s) {
  const long n = q.empty() ? 0 : q[0].size();
  JointRates r;
  r.v_rps = Eigen::VectorXd::Zero(n);
  r.a_rps2 = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd v_prev = Eigen::VectorXd::Zero(n), v(n);
  for (std::size_t i = 1; i < q.size(); ++i) {
    v = (q[i] - q[i - 1]) / period_s;
    r.v_rps = r.v_rps.cwiseMax(v.cwiseAbs());
    // the first difference has no speed before it: it is the path's own start
    if (i >= 2) r.a_rps2 = r.a_rps2.cwiseMax(((v - v_prev) / period_s).cwiseAbs());
    v_prev = v;
  }
  return r;
}

RateExcess Excess(const JointRates& rates, const JointRateLimits& limits) {
  RateExcess e;
  for (long j = 0; j < rates.v_rps.size(); ++j) {
    const double k = std::max(rates.v_rps[j] / limits.v_rps[j], std::sqrt(rates.a_rps2[j] / limits.a_rps2[j]));
    if (k > e.stretch) {
      e.stretch = k;
      e.joint = static_cast<int>(j);
    }
  }
  return e;
}

std::string ExcessMessage(const JointRates& rates, const JointRateLimits& limits, const RateExcess& e,
                          const std::string& joint_name) {
  const int j = e.joint;
  char b[400];
  std::snprintf(b, sizeof b,
                "joint %s needs %.4g deg/s and %.4g deg/s^2; its limits are %.4g deg/s and %.4g deg/s^2 "
                "(limits(\"refuse\"): refused; at the limits the move would take %.3g times as long)",
                joint_name.c_str(), rates.v_rps[j] / kDeg, rates.a_rps2[j] / kDeg, limits.v_rps[j] / kDeg,
                limits.a_rps2[j] / kDeg, e.stretch);
  return b;
}

}  // namespace vlab::task
