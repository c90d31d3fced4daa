#include "lab/devices/arm_sensing.h"

#include <cmath>
#include <string>

#include "lab/scenario/lab_yaml.h"
#include "sensors/sensor_round.h"

namespace vlab::lab {

SensingConfig ReadSensing(MapReader& arm, int joints) {
  SensingConfig config;
  MapReader s = arm.Map("sensing");
  if (s.node().size() == 0) return config;
  // resolution: one number for every joint, or one per joint
  const YAML::Node node = s.Raw("resolution");
  if (!node.IsDefined() || node.IsNull()) s.Fail("resolution", "required (rad per count, one value or one per joint)");
  if (node.IsSequence()) {
    config.resolution = YamlNumbers(s.file(), node, s.Child("resolution"));
    if (config.resolution.size() != 1 && static_cast<int>(config.resolution.size()) != joints) {
      s.Fail("resolution", "needs one value or one per joint (" + std::to_string(joints) + "), got " +
                               std::to_string(config.resolution.size()));
    }
  } else {
    config.resolution = {YamlNumber(s.file(), node, s.Child("resolution"))};
  }
  for (double d : config.resolution) {
    if (!(d > 0)) s.Fail("resolution", "values must be > 0 (rad per count)");
  }
  const std::string velocity = s.String("velocity", "model");
  if (velocity == "difference") {
    config.velocity = SensingConfig::Velocity::kDifference;
  } else if (velocity != "model") {
    s.Fail("velocity", "must be model or difference, got '" + velocity + "'");
  }
  s.Finish();
  return config;
}

void JointSensing::Configure(const SensingConfig& config, int joints) {
  resolution_.clear();
  velocity_ = config.velocity;
  if (!config.enabled()) return;
  resolution_.assign(joints, config.resolution[0]);
  if (static_cast<int>(config.resolution.size()) == joints) resolution_ = config.resolution;
  counts_.assign(joints, 0);
  q_ = Eigen::VectorXd::Zero(joints);
  qd_ = Eigen::VectorXd::Zero(joints);
}

std::int64_t JointSensing::Count(int i, double q) const { return sensors::RoundToCount(q / resolution_[i]); }

void JointSensing::Peek(const double* q, const double* qd, double dt, double* q_out, double* qd_out) const {
  for (std::size_t i = 0; i < resolution_.size(); ++i) {
    const int j = static_cast<int>(i);
    const std::int64_t count = Count(j, q[i]);
    q_out[i] = static_cast<double>(count) * resolution_[i];
    if (velocity_ == SensingConfig::Velocity::kModel) {
      qd_out[i] = qd[i];
    } else {
      // whole counts moved over the step: the difference is exact in counts
      qd_out[i] = dt > 0 ? static_cast<double>(count - counts_[i]) * resolution_[i] / dt : 0.0;
    }
  }
}

void JointSensing::Sense(const double* q, const double* qd, double dt) {
  Peek(q, qd, dt, q_.data(), qd_.data());
  for (std::size_t i = 0; i < resolution_.size(); ++i) counts_[i] = Count(static_cast<int>(i), q[i]);
}

}  // namespace vlab::lab
