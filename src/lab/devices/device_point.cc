// A task-space interface to an arm's tool (kind point), like a robot
// controller's Cartesian position input: the point (an MJCF site at the end of
// the arm's chain) goes where it is told, keeping the orientation it had when
// the run started; the device turns that into joint velocity commands for its
// arm device every control period (resolved rate, control/task_space.h).
//
// Ports
//   input   [x, y, z]: where the point should go, m, world frame; refused
//           (limits) outside the workspace box, (malformed) when not finite
//   output  [status, x, y, z, vx, vy, vz]: the site's position (m) and linear
//           velocity (m/s), world frame; status kStatusHolding while holding
//   rate    at the start of every control period the set-point moves toward
//           the newest command by at most max_speed * period (a rate limit,
//           not a refusal: a far command is reached in a straight line at
//           max_speed), and the arm gets qd = J+ (v_ff + k_position e) + null
//           space term toward the start posture, v_ff = the set-point's motion
//           over the period / period; the arm's velocity servo follows it
//   log     NAME.x, .y, .z, .vx, .vy, .vz; NAME.setpoint.x, .y, .z (m); NAME.error
//           (|set-point - site|, m); NAME.rot_error (rad from the start orientation)
// Hold (before the first command, on the watchdog, after a reset): the arm
// holds its joints where they are (arm hold mode); the next command starts the
// set-point from where the site then is.
// Ownership: the device holds its arm's claim (a command source:
// lab/run/lab_command_writer.h) and drives it in every period, from the start. The
// arm device stays readable on its own port, but what it is sent is overridden
// by the point device's command of the same period (and lockstep does not wait
// for the arm's owner).
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "control/task_space.h"
#include "lab/devices/device_arm_chain.h"
#include "lab/devices/device_point.h"
#include "lab/devices/device_task_space.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

class SimPoint final : public TaskSpaceDevice<PointParams> {
 public:
  SimPoint(const DeviceContext& context, const DeviceConfig& c) : TaskSpaceDevice(context, c, "point") {}

  int command_length() const override { return 3; }
  bridge::CommandCheck CheckCommand(const std::vector<double>& p) const override {
    if (p.size() != 3) return bridge::CommandCheck::kMalformed;
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(p[i])) return bridge::CommandCheck::kMalformed;
      if (p[i] < config_.workspace_min[i] || p[i] > config_.workspace_max[i]) return bridge::CommandCheck::kLimits;
    }
    return bridge::CommandCheck::kAccept;
  }
  void Command(const std::vector<double>& p) override {
    command_ = Eigen::Vector3d(p[0], p[1], p[2]);
    Commanded();
  }

  void Sample(const mjData& d, double) override {
    const SiteMotion site = ReadSiteMotion(model_, d, chain_);
    p_ = site.p_W;
    v_ = site.v_W;
    rot_error_ = control::OrientationError(R_start_, site.R_WS).norm();
  }

  void State(std::vector<double>* p) const override {
    p->assign({StatusValue(), p_.x(), p_.y(), p_.z(), v_.x(), v_.y(), v_.z()});
  }
  std::vector<std::string> Columns() const override {
    return NamedColumns(
        {"x", "y", "z", "vx", "vy", "vz", "setpoint.x", "setpoint.y", "setpoint.z", "error", "rot_error"});
  }
  int ColumnCount() const override { return 11; }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_.x(), p_.y(), p_.z(), v_.x(), v_.y(), v_.z(), setpoint_.x(), setpoint_.y(), setpoint_.z(),
                     (setpoint_ - p_).norm(), rot_error_}) {
      *out++ = v;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j = ArmChainFacts(chain_, config_, kind());
    j["units"] = {{"x", "m"}, {"vx", "m/s"}};
    j["limits"] = {{"workspace_min", config_.workspace_min},
                   {"workspace_max", config_.workspace_max},
                   {"speed_max", config_.max_speed}};  // an unbounded side reads null
    return j.dump();
  }

 private:
  // the orientation is the one the site had at the reset, kept
  void Start(const control::Pose& tip) override {
    R_start_ = tip.R_W;
    setpoint_ = command_ = tip.p_W;
  }
  void Resume(const control::Pose& tip) override { setpoint_ = tip.p_W; }
  // rate limit: the set-point moves toward the command at most max_speed
  control::TaskSpaceTarget Advance() override {
    Eigen::Vector3d step = command_ - setpoint_;
    const double longest = config_.max_speed * period_s_;
    if (step.norm() > longest) step *= longest / step.norm();
    control::TaskSpaceTarget target;
    target.pose.p_W = setpoint_;
    target.pose.R_W = R_start_;
    target.v_W = step / period_s_;
    setpoint_ += step;
    return target;
  }

  Eigen::Matrix3d R_start_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d command_ = Eigen::Vector3d::Zero(), setpoint_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero();
  double rot_error_ = 0;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadPointParams(MapReader& r) {
  auto p = std::make_shared<PointParams>();
  MapReader gains = ReadArmChainParams(r, p.get());
  if (!(p->k_position > 0 && p->k_orientation >= 0 && p->k_null >= 0 && p->damping >= 0)) {
    gains.Fail("position", "position must be > 0, the other gains >= 0");
  }
  gains.Finish();
  p->max_speed = r.Number("max_speed", p->max_speed);
  if (!(p->max_speed > 0)) r.Fail("max_speed", "must be > 0 m/s");
  MapReader box = r.Map("workspace");
  p->workspace_min = box.Numbers("min", p->workspace_min);
  p->workspace_max = box.Numbers("max", p->workspace_max);
  for (int i = 0; i < 3 && p->workspace_min.size() == 3 && p->workspace_max.size() == 3; ++i) {
    if (!(p->workspace_min[i] < p->workspace_max[i])) box.Fail("max", "must be > min in x, y and z");
  }
  if (p->workspace_min.size() != 3 || p->workspace_max.size() != 3)
    box.Fail("min", "min and max need 3 numbers (x, y, z), m, world frame");
  box.Finish();
  ReadCommandInput(r, &p->input);
  return p;
}

std::unique_ptr<Device> MakePoint(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimPoint>(context, config);
}

}  // namespace vlab::lab
