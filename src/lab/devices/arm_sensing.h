// What an arm's servo drive senses of its joints (the arm key `sensing`):
// positions in whole encoder counts and velocities either exact (the
// integrator's) or the backward difference of the counts over one physics
// step, as a drive that closes its loop on its encoders computes them.
//
// A count is the nearest whole multiple of the resolution d (rounding, not
// truncation): the sensed q is within d/2 of the true q and its error has zero
// mean, as for an encoder whose zero was calibrated to the joint's zero; a
// truncating counter is the same with the zero moved by d/2.
//
// The backward difference of a joint moving at a constant speed v over a step
// T takes the two values floor(vT/d)·d/T and ceil(vT/d)·d/T; its mean is v and
// its standard deviation (d/T)·sqrt(f (1 − f)), f = frac(vT/d).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace vlab::lab {

class MapReader;

/// The arm key `sensing`: encoder resolution and velocity source.
struct SensingConfig {
  /// Where the sensed velocity comes from.
  enum class Velocity { kModel, kDifference };
  /// Encoder resolution per joint, rad (slide joints: m) per count; empty:
  /// exact positions (no key: today's arm). One value applies to every joint.
  std::vector<double> resolution;
  Velocity velocity = Velocity::kModel;
  bool enabled() const { return !resolution.empty(); }
};

/// Reads the mapping `sensing` of an arm entry for `joints` joints ({} when
/// absent). Throws InputError naming the file, line and key (sensing.resolution,
/// sensing.velocity) for a resolution that is not > 0 and finite, a list whose
/// length is not 1 or `joints`, or a velocity other than model or difference.
SensingConfig ReadSensing(MapReader& arm, int joints);

/// The encoders of an arm's joints and the velocity its drive derives from them.
class JointSensing {
 public:
  /// Sets up `joints` encoders from `config` (a one-value resolution applies to
  /// all). An empty config senses exactly.
  void Configure(const SensingConfig& config, int joints);
  bool enabled() const { return !resolution_.empty(); }
  bool differencing() const { return enabled() && velocity_ == SensingConfig::Velocity::kDifference; }
  /// Resolution of joint i, rad per count (0 when sensing is exact).
  double resolution(int i) const { return enabled() ? resolution_[i] : 0.0; }

  /// The whole count nearest to q/d for joint i.
  std::int64_t Count(int i, double q) const;
  /// Senses every joint at true positions `q` and velocities `qd`, a step `dt`
  /// (s) after the last Sense: fills the sensed q and qd and keeps the counts
  /// for the next difference. dt <= 0 (the servo's start): a difference
  /// velocity of 0. Sensing must be enabled.
  void Sense(const double* q, const double* qd, double dt);
  /// What Sense would report now without keeping it (the state a sample
  /// reports between two steps): sensed q and qd into `q_out`, `qd_out`.
  void Peek(const double* q, const double* qd, double dt, double* q_out, double* qd_out) const;

  /// The last Sense's sensed positions (rad) and velocities (rad/s).
  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& qd() const { return qd_; }

 private:
  std::vector<double> resolution_;
  SensingConfig::Velocity velocity_ = SensingConfig::Velocity::kModel;
  std::vector<std::int64_t> counts_;  // the last Sense's counts
  Eigen::VectorXd q_, qd_;
};

}  // namespace vlab::lab
