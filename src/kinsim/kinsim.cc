#include "kinsim/kinsim.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/core_errors.h"

namespace vlab::kinsim {

namespace {

[[noreturn]] void Fail(const KinArmConfig& c, const std::string& what) {
  throw vlab::InputError("arm '" + c.name + "': " + what);
}

std::string Num(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

}  // namespace

std::unique_ptr<KinArm> KinArm::Create(const KinArmConfig& c) {
  if (c.name.empty()) throw vlab::InputError("arm: empty name");
  const std::size_t n = c.joints.size();
  if (n == 0) Fail(c, "no joints");
  if (n > static_cast<std::size_t>(bridge::kMaxPacketValues - bridge::kHeaderValues - 1) / 3) {
    Fail(c, std::to_string(n) + " joints do not fit in one state datagram");
  }
  auto sized = [&](const std::vector<double>& v, const char* field) {
    if (v.size() != n) {
      Fail(c, std::string(field) + " has " + std::to_string(v.size()) + " values for " + std::to_string(n) + " joints");
    }
  };
  sized(c.position_min, "position_min");
  sized(c.position_max, "position_max");
  sized(c.velocity_max, "velocity_max");
  sized(c.initial, "initial");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string joint = "joint '" + c.joints[i] + "'";
    if (c.joints[i].empty()) Fail(c, "joint " + std::to_string(i + 1) + " has an empty name");
    if (!seen.insert(c.joints[i]).second) Fail(c, joint + " is listed twice");
    const double lo = c.position_min[i], hi = c.position_max[i];
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) {
      Fail(c, joint + ": position limits [" + Num(lo) + ", " + Num(hi) + "] rad are not a finite range");
    }
    const double v = c.velocity_max[i];
    if (!std::isfinite(v) || !(v > 0)) Fail(c, joint + ": velocity limit " + Num(v) + " rad/s is not > 0");
    const double q = c.initial[i];
    if (!std::isfinite(q) || q < lo || q > hi) {
      Fail(c, joint + ": initial position " + Num(q) + " rad is outside [" + Num(lo) + ", " + Num(hi) + "]");
    }
  }
  return std::unique_ptr<KinArm>(new KinArm(c));
}

KinArm::KinArm(const KinArmConfig& c)
    : config_(c), q_(c.initial), qd_(c.initial.size(), 0.0), value_(c.initial.size(), 0.0) {}

bool KinArm::Valid(const bridge::ArmCommandMsg& c) const {
  if (c.mode < 0 || c.mode > 3) return false;
  if (c.value.size() != q_.size()) return false;
  for (std::size_t i = 0; i < c.value.size(); ++i) {
    const double v = c.value[i];
    if (!std::isfinite(v)) return false;
    if (c.mode == static_cast<int>(ArmMode::kPosition) &&
        (v < config_.position_min[i] || v > config_.position_max[i])) {
      return false;
    }
    if (c.mode == static_cast<int>(ArmMode::kVelocity) && std::abs(v) > config_.velocity_max[i]) return false;
  }
  return true;
}

bool KinArm::Command(const bridge::ArmCommandMsg& c) {
  // torque mode is refused on purpose: with no masses and no motors there is
  // nothing a torque could be applied to, and a torque controller must not
  // believe its commands move this arm. Like every refusal it leaves the
  // previous command in force and sets kStatusRefused.
  const bool torque = c.mode == static_cast<int>(ArmMode::kTorque);
  if (torque || !Valid(c)) {
    ++refused_;
    if (torque) ++refused_torque_;
    last_refused_ = true;
    return false;
  }
  last_refused_ = false;
  mode_ = static_cast<ArmMode>(c.mode);
  std::copy(c.value.begin(), c.value.end(), value_.begin());
  return true;
}

void KinArm::Hold() { mode_ = ArmMode::kHold; }

void KinArm::Step(double dt) {
  if (!(dt > 0)) return;
  for (std::size_t i = 0; i < q_.size(); ++i) {
    const double q0 = q_[i];
    const double lo = config_.position_min[i], hi = config_.position_max[i];
    switch (mode_) {
      case ArmMode::kHold:
      case ArmMode::kTorque:  // never in force (refused), listed for completeness
        qd_[i] = 0.0;
        break;
      case ArmMode::kVelocity: {
        // integrate, then clamp at the limits: the applied velocity is what moved
        const double v = value_[i];
        const double q = q0 + v * dt;
        if (q < lo || q > hi) {
          q_[i] = std::clamp(q, lo, hi);
          qd_[i] = (q_[i] - q0) / dt;
        } else {
          q_[i] = q;
          qd_[i] = v;
        }
        break;
      }
      case ArmMode::kPosition: {
        // at most velocity_max dt per step; the last step lands on the target exactly
        const double error = value_[i] - q0;
        const double step = config_.velocity_max[i] * dt;
        q_[i] = std::abs(error) <= step ? value_[i] : q0 + std::copysign(step, error);
        q_[i] = std::clamp(q_[i], lo, hi);
        qd_[i] = (q_[i] - q0) / dt;
        break;
      }
    }
  }
}

std::uint32_t KinArm::status() const {
  std::uint32_t bits = 0;
  if (mode_ == ArmMode::kHold) bits |= bridge::kStatusHolding;
  if (last_refused_) bits |= bridge::kStatusRefused;
  for (std::size_t i = 0; i < q_.size(); ++i) {
    if (q_[i] <= config_.position_min[i] || q_[i] >= config_.position_max[i]) {
      bits |= bridge::kStatusAtLimit;
      break;
    }
  }
  return bits;
}

void KinArm::Sample(bridge::ArmStateMsg* s) const {
  s->status = status();
  s->q.assign(q_.begin(), q_.end());
  s->qd.assign(qd_.begin(), qd_.end());
  s->tau.assign(q_.size(), 0.0);
}

}  // namespace vlab::kinsim
