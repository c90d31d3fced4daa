// Simulated parallel gripper (kind gripper), like a servo-electric gripper
// module's driver: an opening set-point or a grip force in; opening, force and
// a grasp flag out. The grasp itself is contact physics (friction on the pads).
//
// Ports
//   input   [mode, value]: mode 0 position, value = opening set-point (m,
//           within the servo's ctrlrange); mode 1 force, value = grip force
//           (N, >= 0, at most the force drive's range: closes the jaws until
//           they squeeze with that force)
//   output  [status, opening (m), opening_velocity (m/s), force (N: the mean
//           normal force of the pads), grasped (1: every pad presses with at
//           least grasp_force and the jaws are at rest)]
//   rate    commands apply at the start of a period; in position mode the
//           servo's set-point ramps toward the command at max_speed at every
//           physics step; in force mode the force drive pushes and the servo
//           is kept neutral (its set-point follows the measured opening)
// Hold (before the first command, watchdog): the set-point stops where it is;
// a grip force in effect is kept, so a held object is not dropped.
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "core/core_errors.h"
#include "lab/devices/device_gripper.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

constexpr double kAtRest_m_per_s = 0.005;  // jaw speed below which a grasp can be reported

class SimGripper final : public Device, public CommandInput, public StepHooks {
 public:
  SimGripper(const mjModel* m, const DeviceConfig& c) : Device(c), config_(c.ParamsAs<GripperParams>()) {
    capabilities_.command_input = this;
    capabilities_.step_hooks = this;
    servo_ = Actuator(m, c, config_.servo);
    drive_ = Actuator(m, c, config_.force_actuator);
    if (m->actuator_trntype[servo_] != mjTRN_TENDON || m->actuator_trntype[drive_] != mjTRN_TENDON ||
        m->actuator_trnid[2 * servo_] != m->actuator_trnid[2 * drive_]) {
      throw InputError(c.where + ": device '" + c.name + "': actuators '" + config_.servo + "' and '" +
                       config_.force_actuator + "' must drive the same tendon (the gripper's opening)");
    }
    if (!m->actuator_ctrllimited[servo_] || !m->actuator_ctrllimited[drive_]) {
      throw InputError(c.where + ": device '" + c.name + "': the gripper's actuators need a ctrlrange");
    }
    opening_min_ = m->actuator_ctrlrange[2 * servo_];
    opening_max_ = m->actuator_ctrlrange[2 * servo_ + 1];
    force_max_ = -m->actuator_ctrlrange[2 * drive_];
    for (const std::string& s : config_.touch) {
      const int id = mj_name2id(m, mjOBJ_SENSOR, s.c_str());
      if (id < 0 || m->sensor_type[id] != mjSENS_TOUCH) {
        throw InputError(c.where + ": device '" + c.name + "': the scene has no touch sensor '" + s + "'");
      }
      touch_.push_back(m->sensor_adr[id]);
    }
  }

  void Reset(const mjData& d) override {
    force_mode_ = false;
    grip_force_ = 0;
    reference_ = target_ = std::clamp(d.actuator_length[servo_], opening_min_, opening_max_);
    holding_ = true;
    Sample(d, d.time);
  }

  int command_length() const override { return 2; }
  bridge::CommandCheck CheckCommand(const std::vector<double>& p) const override {
    if (p[0] == 0)
      return p[1] >= opening_min_ && p[1] <= opening_max_ ? bridge::CommandCheck::kAccept
                                                          : bridge::CommandCheck::kLimits;
    if (p[0] == 1)
      return p[1] >= 0 && p[1] <= force_max_ ? bridge::CommandCheck::kAccept : bridge::CommandCheck::kLimits;
    return bridge::CommandCheck::kMalformed;
  }
  void Command(const std::vector<double>& p) override {
    force_mode_ = p[0] == 1;
    if (force_mode_) {
      grip_force_ = p[1];
    } else {
      target_ = p[1];
    }
    holding_ = false;
  }
  void Hold() override {
    target_ = reference_;
    holding_ = true;
  }
  int watchdog_periods() const override { return config_.input.watchdog_periods; }
  double owner_timeout_s() const override { return config_.input.owner_timeout_s; }

  void Actuate(mjData& d, double dt) override {
    if (force_mode_) {
      reference_ = target_ = std::clamp(d.actuator_length[servo_], opening_min_, opening_max_);
      d.ctrl[servo_] = reference_;
      d.ctrl[drive_] = -grip_force_;
      return;
    }
    const double step = config_.max_speed * dt;
    reference_ += std::clamp(target_ - reference_, -step, step);
    d.ctrl[servo_] = reference_;
    d.ctrl[drive_] = 0;
  }

  void Sample(const mjData& d, double) override {
    opening_ = d.actuator_length[servo_];
    velocity_ = d.actuator_velocity[servo_];
    double sum = 0, least = INFINITY;
    for (int adr : touch_) {
      sum += d.sensordata[adr];
      least = std::min(least, d.sensordata[adr]);
    }
    force_ = sum / static_cast<double>(touch_.size());
    grasped_ = least >= config_.grasp_force && std::abs(velocity_) < kAtRest_m_per_s;
  }

  void State(std::vector<double>* p) const override {
    p->assign({holding_ ? static_cast<double>(bridge::kStatusHolding) : 0.0, opening_, velocity_, force_,
               grasped_ ? 1.0 : 0.0});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"opening", "velocity", "force", "grasped", "setpoint", "grip_force"}) {
      out.push_back(name() + "." + c);
    }
    return out;
  }
  int ColumnCount() const override { return 6; }
  void Row(const mjData&, double* out) const override {
    for (double v : {opening_, velocity_, force_, grasped_ ? 1.0 : 0.0, reference_, force_mode_ ? grip_force_ : 0.0}) {
      *out++ = v;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"opening", "m"}, {"opening_velocity", "m/s"}, {"force", "N"}, {"value", "m (mode 0), N (mode 1)"}};
    j["modes"] = {{"position", 0}, {"force", 1}};
    j["status_bits"] = {{"holding", bridge::kStatusHolding},
                        {"refused", bridge::kStatusRefused},
                        {"watchdog", bridge::kStatusWatchdog},
                        {"not_owner", bridge::kStatusNotOwner}};
    j["limits"] = {{"opening_min", opening_min_},
                   {"opening_max", opening_max_},
                   {"force_max", force_max_},
                   {"speed_max", config_.max_speed}};
    j["grasp_force"] = config_.grasp_force;
    j["watchdog_periods"] = config_.input.watchdog_periods;
    return j.dump();
  }

 private:
  static int Actuator(const mjModel* m, const DeviceConfig& c, const std::string& name) {
    const int id = mj_name2id(m, mjOBJ_ACTUATOR, name.c_str());
    if (id < 0) throw InputError(c.where + ": device '" + c.name + "': the scene has no actuator '" + name + "'");
    return id;
  }

  GripperParams config_;
  int servo_ = -1, drive_ = -1;
  std::vector<int> touch_;
  double opening_min_ = 0, opening_max_ = 0, force_max_ = 0;
  bool force_mode_ = false, holding_ = true, grasped_ = false;
  double grip_force_ = 0, target_ = 0, reference_ = 0;
  double opening_ = 0, velocity_ = 0, force_ = 0;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadGripperParams(MapReader& r) {
  auto p = std::make_shared<GripperParams>();

  p->servo = r.String("servo", p->servo);
  p->force_actuator = r.String("force_actuator", p->force_actuator);
  p->touch = r.Strings("touch", p->touch);
  if (p->touch.empty()) r.Fail("touch", "needs at least one pad touch sensor");
  p->max_speed = r.Number("max_speed", p->max_speed);
  if (!(p->max_speed > 0)) r.Fail("max_speed", "must be > 0 m/s");
  p->grasp_force = r.Number("grasp_force", p->grasp_force);
  if (!(p->grasp_force > 0)) r.Fail("grasp_force", "must be > 0 N");
  ReadCommandInput(r, &p->input);
  return p;
}

std::unique_ptr<Device> MakeGripper(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimGripper>(context.model, config);
}

}  // namespace vlab::lab
