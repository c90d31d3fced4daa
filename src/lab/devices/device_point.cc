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
// Ownership: the device drives its arm in every period, from the start. The
// arm device stays readable on its own port, but what it is sent is overridden
// by the point device's command of the same period (and lockstep does not wait
// for the arm's owner).
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

#include "bridge/bridge_yoyo.h"
#include "control/robot_model.h"
#include "control/task_space.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_point.h"
#include "core/core_errors.h"
#include "lab/lab_yaml.h"

namespace vlab::lab {

namespace {

using Matrix3RowMajor = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

class SimPoint final : public Device {
 public:
  SimPoint(const DeviceContext& context, const DeviceConfig& c)
      : Device(c), model_(context.model), config_(c.ParamsAs<PointParams>()), period_s_(context.control_period_s) {
    try {
      chain_ = control::RobotModel::Create(model_, {config_.base_body, config_.site});
    } catch (const std::invalid_argument& e) {
      throw InputError(who() + ": " + e.what());
    }
    site_ = chain_->tip_site_id();
    for (int i = 0; i < 3; ++i) {
      box_min_[i] = config_.workspace_min[i];
      box_max_[i] = config_.workspace_max[i];
    }
    q_.setZero(chain_->dof());
    qd_.setZero(chain_->dof());
    velocity_.mode = bridge::ArmMode::kVelocity;
    hold_.mode = bridge::ArmMode::kHold;
  }

  // its arm: an arm device of the scenario, driven by this device alone
  void Bind(const std::vector<Device*>& devices) override {
    const std::string who = this->who() + ": arm: ";
    arm_ = nullptr;
    for (Device* d : devices) {
      if (d->name() == config_.arm) arm_ = dynamic_cast<SimArm*>(d);
    }
    if (!arm_) throw InputError(who + "the scenario has no arm device '" + config_.arm + "'");
    arm_->SetDriver(name(), who);
    arm_index_.clear();
    const std::vector<std::string>& joints = arm_->joint_names();
    for (const std::string& joint : chain_->joint_names()) {
      const auto it = std::find(joints.begin(), joints.end(), joint);
      if (it == joints.end()) {
        throw InputError(this->who() + ": chain joint '" + joint + "' (from '" + config_.base_body + "' to site '" +
                         config_.site + "') is not a joint of arm '" + arm_->name() + "'");
      }
      arm_index_.push_back(static_cast<int>(it - joints.begin()));
    }
    velocity_.value.setZero(arm_->dof());
  }
  std::string drives() const override { return config_.arm; }
  int log_rank() const override { return 3; }  // after the other devices, as in every log written so far


  void Reset(const mjData& d) override {
    ReadChain(d);
    chain_->SetState(q_, qd_);
    const control::Pose tip = chain_->TipPose();
    R_start_ = tip.R_W;
    setpoint_ = command_ = tip.p_W;
    // the posture the null-space term keeps: the start posture (allocates: not in the step loop)
    control::TaskSpaceConfig tc;
    tc.k_position = config_.k_position;
    tc.k_orientation = config_.k_orientation;
    tc.k_null = config_.k_null;
    tc.damping = config_.damping;
    tc.q_rest = q_;
    if (arm_->max_velocity().size() > 0) {
      double slowest = INFINITY;  // uniform scaling below the slowest chain joint's limit: never refused
      for (int i : arm_index_) slowest = std::min(slowest, arm_->max_velocity()[i]);
      tc.max_joint_speed = 0.999 * slowest;
    }
    controller_ = control::TaskSpaceController::Create(tc, *chain_);
    holding_ = true;
    Sample(d, d.time);
  }

  int command_length() const override { return 3; }
  bridge::CommandCheck CheckCommand(const std::vector<double>& p) const override {
    if (p.size() != 3) return bridge::CommandCheck::kMalformed;
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(p[i])) return bridge::CommandCheck::kMalformed;
      if (p[i] < box_min_[i] || p[i] > box_max_[i]) return bridge::CommandCheck::kLimits;
    }
    return bridge::CommandCheck::kAccept;
  }
  void Command(const std::vector<double>& p) override {
    command_ = Eigen::Vector3d(p[0], p[1], p[2]);
    resume_ = holding_;
    holding_ = false;
  }
  void Hold() override { holding_ = true; }
  int watchdog_periods() const override { return config_.input.watchdog_periods; }
  double owner_timeout_s() const override { return config_.input.owner_timeout_s; }

  void BeginPeriod(const mjData& d, double) override {
    if (holding_) {
      arm_->Command(hold_);
      return;
    }
    ReadChain(d);
    chain_->SetState(q_, qd_);
    if (resume_) setpoint_ = chain_->TipPose().p_W;  // from a hold: start where the site is
    resume_ = false;
    // rate limit: the set-point moves toward the command at most max_speed
    Eigen::Vector3d step = command_ - setpoint_;
    const double longest = config_.max_speed * period_s_;
    if (step.norm() > longest) step *= longest / step.norm();
    control::TaskSpaceTarget target;
    target.pose.p_W = setpoint_;
    target.pose.R_W = R_start_;
    target.v_W = step / period_s_;
    const control::TaskSpaceOutput& out = controller_->Update(*chain_, q_, target);
    velocity_.value.setZero();
    for (std::size_t i = 0; i < arm_index_.size(); ++i) velocity_.value[arm_index_[i]] = out.qd_cmd[i];
    if (!out.ok || !arm_->Command(velocity_)) arm_->Command(hold_);  // non-finite state: hold, never drift
    setpoint_ += step;
  }

  void Sample(const mjData& d, double) override {
    p_ = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * site_);
    mjtNum velocity[6];
    mj_objectVelocity(model_, &d, mjOBJ_SITE, site_, velocity, 0);  // [angular, linear], world frame
    v_ = Eigen::Vector3d(velocity[3], velocity[4], velocity[5]);
    const Eigen::Matrix3d R_WS = Eigen::Map<const Matrix3RowMajor>(d.site_xmat + 9 * site_);
    rot_error_ = control::OrientationError(R_start_, R_WS).norm();
  }

  void State(std::vector<double>* p) const override {
    p->assign({holding_ ? static_cast<double>(bridge::kStatusHolding) : 0.0, p_.x(), p_.y(), p_.z(), v_.x(), v_.y(),
               v_.z()});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"x", "y", "z", "vx", "vy", "vz", "setpoint.x", "setpoint.y", "setpoint.z", "error",
                          "rot_error"}) {
      out.push_back(name() + "." + c);
    }
    return out;
  }
  int ColumnCount() const override { return 11; }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_.x(), p_.y(), p_.z(), v_.x(), v_.y(), v_.z(), setpoint_.x(), setpoint_.y(), setpoint_.z(),
                     (setpoint_ - p_).norm(), rot_error_}) {
      *out++ = v;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"x", "m"}, {"vx", "m/s"}};
    j["frame"] = "world";
    j["arm"] = arm_->name();
    j["site"] = config_.site;
    j["status_bits"] = {{"holding", bridge::kStatusHolding}, {"refused", bridge::kStatusRefused},
                        {"watchdog", bridge::kStatusWatchdog}, {"not_owner", bridge::kStatusNotOwner}};
    j["limits"] = {{"workspace_min", config_.workspace_min}, {"workspace_max", config_.workspace_max},
                   {"speed_max", config_.max_speed}};  // an unbounded side reads null
    j["gains"] = {{"position", config_.k_position}, {"orientation", config_.k_orientation},
                  {"null_space", config_.k_null}, {"damping", config_.damping}};
    j["watchdog_periods"] = config_.input.watchdog_periods;
    return j.dump();
  }

 private:
  // the chain's joint positions and velocities out of mjData (no allocation)
  void ReadChain(const mjData& d) {
    for (int i = 0; i < chain_->dof(); ++i) {
      q_[i] = d.qpos[chain_->qpos_addresses()[i]];
      qd_[i] = d.qvel[chain_->dof_addresses()[i]];
    }
  }

  const mjModel* model_;
  PointParams config_;
  SimArm* arm_ = nullptr;  // bound by Bind
  double period_s_;
  std::unique_ptr<control::RobotModel> chain_;
  std::unique_ptr<control::TaskSpaceController> controller_;
  std::vector<int> arm_index_;  // chain joint i is arm joint arm_index_[i]
  int site_ = -1;
  double box_min_[3] = {0, 0, 0}, box_max_[3] = {0, 0, 0};
  Eigen::VectorXd q_, qd_;
  bridge::ArmCommand velocity_, hold_;
  Eigen::Matrix3d R_start_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d command_ = Eigen::Vector3d::Zero(), setpoint_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero();
  double rot_error_ = 0;
  bool holding_ = true, resume_ = false;
};

}  // namespace

std::shared_ptr<const DeviceParams> ReadPointParams(MapReader& r) {
  auto p = std::make_shared<PointParams>();

  p->arm = r.String("arm");
  p->site = r.String("site", p->site);
  p->base_body = r.String("base_body", p->base_body);
  MapReader gains = r.Map("gains");
  p->k_position = gains.Number("position", p->k_position);
  p->k_orientation = gains.Number("orientation", p->k_orientation);
  p->k_null = gains.Number("null_space", p->k_null);
  p->damping = gains.Number("damping", p->damping);
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
  if (p->workspace_min.size() != 3 || p->workspace_max.size() != 3) box.Fail("min", "min and max need 3 numbers (x, y, z), m, world frame");
  box.Finish();
  ReadCommandInput(r, &p->input);
  return p;
}

std::unique_ptr<Device> MakePoint(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimPoint>(context, config);
}

}  // namespace vlab::lab
