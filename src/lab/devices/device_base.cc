// Simulated holonomic base (kind base), like the Nomad XR4000's drive
// interface: velocities in, odometry out.
//
// Ports
//   input   [frame, vx, vy, wz]: frame 0 base (x forward, y left), 1 world;
//           m/s, m/s, rad/s; |v| within max_velocity
//   output  [status, x, y, yaw, vx, vy, wz]: odometry pose (world, m, rad)
//           and measured velocities in the base frame
//   rate    commands apply at the start of a period; the reference velocity
//           ramps toward the command within max_acceleration at every physics
//           step (velocity actuators on the planar joints track it)
// Watchdog/hold: the reference ramps down to zero (the base brakes).
// Odometry: without drift it equals the true planar pose; with drift it
// integrates the true motion of each period in the base frame with seeded
// scale errors (x, y, yaw) and a yaw-rate bias, as wheel odometry drifts.
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "core/core_errors.h"
#include "lab/devices/device_base.h"
#include "lab/scenario/lab_yaml.h"
#include "sensors/sensor_random.h"

namespace vlab::lab {

namespace {

class SimBase final : public Device, public CommandInput, public StepHooks {
 public:
  SimBase(const mjModel* m, const DeviceConfig& c, std::uint64_t seed) : Device(c), config_(c.ParamsAs<BaseParams>()) {
    capabilities_.command_input = this;
    capabilities_.step_hooks = this;
    const int want[3] = {mjJNT_SLIDE, mjJNT_SLIDE, mjJNT_HINGE};
    for (int i = 0; i < 3; ++i) {
      const std::string& j = config_.joints[i];
      const int id = mj_name2id(m, mjOBJ_JOINT, j.c_str());
      if (id < 0) throw InputError(c.where + ": device '" + c.name + "': the scene has no joint '" + j + "'");
      if (m->jnt_type[id] != want[i]) {
        throw InputError(c.where + ": device '" + c.name + "': joint '" + j + "' must be a " +
                         (want[i] == mjJNT_SLIDE ? "slide" : "hinge") + " joint (x, y slide; yaw hinge)");
      }
      qpos_[i] = m->jnt_qposadr[id];
      qvel_[i] = m->jnt_dofadr[id];
      const std::string& a = config_.actuators[i];
      const int act = mj_name2id(m, mjOBJ_ACTUATOR, a.c_str());
      if (act < 0) throw InputError(c.where + ": device '" + c.name + "': the scene has no actuator '" + a + "'");
      if (m->actuator_trntype[act] != mjTRN_JOINT || m->actuator_trnid[2 * act] != id ||
          m->actuator_biasprm[act * mjNBIAS + 2] >= 0) {
        throw InputError(c.where + ": device '" + c.name + "': actuator '" + a +
                         "' must be a velocity actuator of joint '" + j + "'");
      }
      ctrl_[i] = act;
    }
    if (config_.odometry_drift) {
      sensors::Xoshiro256pp rng(seed);
      sensors::ZigguratNormal normal;
      for (double& s : scale_) s = config_.drift_scale * normal(rng);
      yaw_bias_ = config_.drift_yaw_rate * normal(rng);
    }
  }

  void Reset(const mjData& d) override {
    for (int i = 0; i < 3; ++i) {
      odometry_[i] = last_pose_[i] = d.qpos[qpos_[i]];
      reference_[i] = target_[i] = 0.0;
    }
    holding_ = true;
    t_last_ = d.time;
    Sample(d, d.time);
  }

  int command_length() const override { return 4; }
  bridge::CommandCheck CheckCommand(const std::vector<double>& p) const override {
    if (p[0] != 0 && p[0] != 1) return bridge::CommandCheck::kMalformed;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(p[1 + i]) > config_.max_velocity[i]) return bridge::CommandCheck::kLimits;
    }
    return bridge::CommandCheck::kAccept;
  }
  void Command(const std::vector<double>& p) override {
    world_frame_ = p[0] == 1;
    for (int i = 0; i < 3; ++i) target_[i] = p[1 + i];
    holding_ = false;
  }
  void Hold() override {
    target_[0] = target_[1] = target_[2] = 0.0;
    holding_ = true;
  }
  int watchdog_periods() const override { return config_.input.watchdog_periods; }
  double owner_timeout_s() const override { return config_.input.owner_timeout_s; }

  void Actuate(mjData& d, double dt) override {
    // the target in the world frame, then the reference ramps toward it
    const double yaw = d.qpos[qpos_[2]];
    double goal[3] = {target_[0], target_[1], target_[2]};
    if (!world_frame_) {
      goal[0] = std::cos(yaw) * target_[0] - std::sin(yaw) * target_[1];
      goal[1] = std::sin(yaw) * target_[0] + std::cos(yaw) * target_[1];
    }
    const double dx = goal[0] - reference_[0], dy = goal[1] - reference_[1];
    const double step_xy = std::min(config_.max_acceleration[0], config_.max_acceleration[1]) * dt;
    const double norm = std::hypot(dx, dy);
    const double f = norm > step_xy ? step_xy / norm : 1.0;
    reference_[0] += f * dx;
    reference_[1] += f * dy;
    const double step_w = config_.max_acceleration[2] * dt;
    reference_[2] += std::clamp(goal[2] - reference_[2], -step_w, step_w);
    for (int i = 0; i < 3; ++i) d.ctrl[ctrl_[i]] = reference_[i];
  }

  void Sample(const mjData& d, double t) override {
    double pose[3], vel_w[3];
    for (int i = 0; i < 3; ++i) {
      pose[i] = d.qpos[qpos_[i]];
      vel_w[i] = d.qvel[qvel_[i]];
    }
    // the period's true motion in the base frame at its start, through the odometry's errors
    const double c0 = std::cos(last_pose_[2]), s0 = std::sin(last_pose_[2]);
    const double dx = pose[0] - last_pose_[0], dy = pose[1] - last_pose_[1];
    const double fwd = (c0 * dx + s0 * dy) * (1 + scale_[0]);
    const double left = (-s0 * dx + c0 * dy) * (1 + scale_[1]);
    const double co = std::cos(odometry_[2]), so = std::sin(odometry_[2]);
    odometry_[0] += co * fwd - so * left;
    odometry_[1] += so * fwd + co * left;
    odometry_[2] += (pose[2] - last_pose_[2]) * (1 + scale_[2]) + yaw_bias_ * (t - t_last_);
    const double c = std::cos(pose[2]), s = std::sin(pose[2]);
    velocity_[0] = c * vel_w[0] + s * vel_w[1];
    velocity_[1] = -s * vel_w[0] + c * vel_w[1];
    velocity_[2] = vel_w[2];
    for (int i = 0; i < 3; ++i) last_pose_[i] = pose[i];
    t_last_ = t;
  }

  void State(std::vector<double>* p) const override {
    p->assign({holding_ ? static_cast<double>(bridge::kStatusHolding) : 0.0, odometry_[0], odometry_[1], odometry_[2],
               velocity_[0], velocity_[1], velocity_[2]});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"x", "y", "yaw", "true_x", "true_y", "true_yaw", "vx", "vy", "wz"})
      out.push_back(name() + "." + c);
    return out;
  }
  int ColumnCount() const override { return 9; }
  void Row(const mjData&, double* out) const override {
    for (double v : {odometry_[0], odometry_[1], odometry_[2], last_pose_[0], last_pose_[1], last_pose_[2],
                     velocity_[0], velocity_[1], velocity_[2]}) {
      *out++ = v;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"x", "m (odometry, world)"}, {"yaw", "rad"}, {"vx", "m/s (base frame)"}, {"wz", "rad/s"}};
    j["frames"] = {{"base", 0}, {"world", 1}};
    j["status_bits"] = {{"holding", bridge::kStatusHolding},
                        {"refused", bridge::kStatusRefused},
                        {"watchdog", bridge::kStatusWatchdog},
                        {"not_owner", bridge::kStatusNotOwner}};
    j["joints"] = config_.joints;
    j["limits"] = {{"velocity_max", config_.max_velocity}, {"acceleration_max", config_.max_acceleration}};
    j["odometry_drift"] = config_.odometry_drift;
    j["watchdog_periods"] = config_.input.watchdog_periods;
    return j.dump();
  }

 private:
  BaseParams config_;
  int qpos_[3] = {}, qvel_[3] = {}, ctrl_[3] = {};
  double target_[3] = {}, reference_[3] = {};
  bool world_frame_ = false, holding_ = true;
  double scale_[3] = {}, yaw_bias_ = 0;
  double odometry_[3] = {}, last_pose_[3] = {}, velocity_[3] = {};
  double t_last_ = 0;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadBaseParams(MapReader& r) {
  auto p = std::make_shared<BaseParams>();

  p->joints = r.Strings("joints", {});
  if (p->joints.size() != 3) r.Fail("joints", "a base needs 3 joints: x, y (slide) and yaw (hinge)");
  p->actuators = r.Strings("actuators", p->joints);
  if (p->actuators.size() != 3) r.Fail("actuators", "needs one velocity actuator per joint (3)");
  p->max_velocity = r.Numbers("max_velocity", p->max_velocity);
  p->max_acceleration = r.Numbers("max_acceleration", p->max_acceleration);
  for (const char* key : {"max_velocity", "max_acceleration"}) {
    const auto& v = std::string(key) == "max_velocity" ? p->max_velocity : p->max_acceleration;
    if (v.size() != 3 || !(v[0] > 0 && v[1] > 0 && v[2] > 0)) r.Fail(key, "expected 3 numbers > 0 (x, y, yaw)");
  }
  MapReader odometry = r.Map("odometry");
  p->odometry_drift = odometry.Bool("drift", p->odometry_drift);
  p->drift_scale = odometry.Number("scale_std", p->drift_scale);
  p->drift_yaw_rate = odometry.Number("yaw_rate_std", p->drift_yaw_rate);
  if (!(p->drift_scale >= 0 && p->drift_scale < 0.5)) odometry.Fail("scale_std", "must be 0 to 0.5");
  if (!(p->drift_yaw_rate >= 0)) odometry.Fail("yaw_rate_std", "must be >= 0 rad/s");
  odometry.Finish();
  ReadCommandInput(r, &p->input);
  return p;
}

std::unique_ptr<Device> MakeBase(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimBase>(context.model, config, context.seed);
}

}  // namespace vlab::lab
