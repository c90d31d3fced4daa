// A task-space pose interface to an arm's tool (kind tool), like a robot
// controller's Cartesian pose input: the tool frame (an MJCF site at the end
// of the arm's chain) goes where it is told and turns as it is told; the device
// turns that into joint velocity commands for its arm device every control
// period (resolved rate, control/task_space.h), so that a script or an
// external controller needs no inverse kinematics of its own.
//
// Ports
//   input   [x, y, z, qw, qx, qy, qz]: where the tool should go (m) and the
//           orientation it should take (unit quaternion), world frame;
//           refused (malformed) when not finite or |q| is not 1 +- 0.001;
//           refused (limits) outside the workspace box, beyond the reach
//           sphere (by default the chain's length from its first joint: no
//           posture gets there), or with the tool's z axis outside the tilt cone
//   output  [status, x, y, z, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz]: the
//           site's pose, linear (m/s) and angular (rad/s) velocity, world
//           frame (qw >= 0); status kStatusHolding while holding
//   rate    at the start of every control period the set-point moves toward
//           the newest command by at most max_speed * period in position and
//           max_angular_speed * period in orientation (along the shortest
//           rotation): a far command is reached in a straight line, at those
//           speeds, and not refused; the arm gets qd = J+ (xd_ff + K e) + null
//           space term toward the start posture, xd_ff = the set-point's motion
//           over the period / period; the arm's velocity servo follows it
//   log     NAME.x, .y, .z, .qw, .qx, .qy, .qz; NAME.setpoint.x, .y, .z;
//           NAME.error (|set-point - site|, m); NAME.rot_error (rad, the
//           angle from the site's orientation to the set-point's)
// Hold (before the first command, on the watchdog, after a reset): the arm
// holds its joints where they are (arm hold mode); the next command starts the
// set-point from where the tool then is.
// Ownership: as the point device: the device drives its arm in every period;
// what the arm is sent on its own port is overridden.
// A target inside every limit may still be out of the arm's reach with that
// orientation: the tool then stops as near as the damped least squares gets it
// and NAME.error / .rot_error stay large (the limits are the refusal).
#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "control/robot_model.h"
#include "control/task_space.h"
#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_tool.h"
#include "lab/lab_yaml.h"

namespace vlab::lab {

namespace {

using Matrix3RowMajor = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
constexpr double kQuaternionNormTolerance = 1e-3;
constexpr int kCommandValues = 7;

class SimTool final : public Device {
 public:
  SimTool(const DeviceContext& context, const DeviceConfig& c)
      : Device(c), model_(context.model), config_(c.ParamsAs<ToolParams>()), period_s_(context.control_period_s) {
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
    reach_centre_ = Eigen::Vector3d(config_.reach_centre[0], config_.reach_centre[1], config_.reach_centre[2]);
    reach_radius_ = config_.reach == ToolParams::Reach::kFixed ? config_.reach_radius : INFINITY;
    if (config_.reach == ToolParams::Reach::kAuto) ChainLength();
    tilt_axis_ = Eigen::Vector3d(config_.tilt_axis[0], config_.tilt_axis[1], config_.tilt_axis[2]).normalized();
    cos_max_tilt_ = std::cos(config_.max_tilt_deg * M_PI / 180);
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
  int log_rank() const override { return 3; }  // after the other devices, as the point device

  void Reset(const mjData& d) override {
    ReadChain(d);
    chain_->SetState(q_, qd_);
    const control::Pose tip = chain_->TipPose();
    p_set_ = p_cmd_ = tip.p_W;
    R_set_ = R_cmd_ = tip.R_W;
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

  int command_length() const override { return kCommandValues; }
  bridge::CommandCheck CheckCommand(const std::vector<double>& c) const override {
    if (c.size() != kCommandValues) return bridge::CommandCheck::kMalformed;
    for (double v : c) {
      if (!std::isfinite(v)) return bridge::CommandCheck::kMalformed;
    }
    const Eigen::Quaterniond q(c[3], c[4], c[5], c[6]);
    if (std::abs(q.norm() - 1) > kQuaternionNormTolerance) return bridge::CommandCheck::kMalformed;
    const Eigen::Vector3d p(c[0], c[1], c[2]);
    for (int i = 0; i < 3; ++i) {
      if (p[i] < box_min_[i] || p[i] > box_max_[i]) return bridge::CommandCheck::kLimits;
    }
    if ((p - reach_centre_).norm() > reach_radius_) return bridge::CommandCheck::kLimits;
    const Eigen::Vector3d tool_z = q.normalized() * Eigen::Vector3d::UnitZ();
    if (tool_z.dot(tilt_axis_) < cos_max_tilt_) return bridge::CommandCheck::kLimits;
    return bridge::CommandCheck::kAccept;
  }
  void Command(const std::vector<double>& c) override {
    p_cmd_ = Eigen::Vector3d(c[0], c[1], c[2]);
    R_cmd_ = Eigen::Quaterniond(c[3], c[4], c[5], c[6]).normalized().toRotationMatrix();
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
    if (resume_) {  // from a hold: start where the tool is
      const control::Pose tip = chain_->TipPose();
      p_set_ = tip.p_W;
      R_set_ = tip.R_W;
    }
    resume_ = false;
    // rate limits: the set-point moves toward the command at most max_speed, turns at most max_angular_speed
    Eigen::Vector3d step = p_cmd_ - p_set_;
    const double longest = config_.max_speed * period_s_;
    if (step.norm() > longest) step *= longest / step.norm();
    Eigen::Vector3d turn = control::OrientationError(R_cmd_, R_set_);  // world frame: R_cmd = exp(turn) R_set
    const double widest = config_.max_angular_speed * period_s_;
    if (turn.norm() > widest) turn *= widest / turn.norm();
    control::TaskSpaceTarget target;
    target.pose.p_W = p_set_;
    target.pose.R_W = R_set_;
    target.v_W = step / period_s_;
    target.w_W = turn / period_s_;
    const control::TaskSpaceOutput& out = controller_->Update(*chain_, q_, target);
    velocity_.value.setZero();
    for (std::size_t i = 0; i < arm_index_.size(); ++i) velocity_.value[arm_index_[i]] = out.qd_cmd[i];
    if (!out.ok || !arm_->Command(velocity_)) arm_->Command(hold_);  // non-finite state: hold, never drift
    p_set_ += step;
    if (turn.norm() > 0) R_set_ = Eigen::AngleAxisd(turn.norm(), turn / turn.norm()).toRotationMatrix() * R_set_;
  }

  void Sample(const mjData& d, double) override {
    if (config_.reach == ToolParams::Reach::kAuto) {
      reach_centre_ = Eigen::Map<const Eigen::Vector3d>(d.xanchor + 3 * chain_->joint_ids().front());
    }
    p_ = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * site_);
    const Eigen::Matrix3d R_WS = Eigen::Map<const Matrix3RowMajor>(d.site_xmat + 9 * site_);
    q_WS_ = Eigen::Quaterniond(R_WS);
    if (q_WS_.w() < 0) q_WS_.coeffs() *= -1;
    mjtNum velocity[6];
    mj_objectVelocity(model_, &d, mjOBJ_SITE, site_, velocity, 0);  // [angular, linear], world frame
    w_ = Eigen::Vector3d(velocity[0], velocity[1], velocity[2]);
    v_ = Eigen::Vector3d(velocity[3], velocity[4], velocity[5]);
    rot_error_ = control::OrientationError(R_set_, R_WS).norm();
  }

  void State(std::vector<double>* p) const override {
    p->assign({holding_ ? static_cast<double>(bridge::kStatusHolding) : 0.0, p_.x(), p_.y(), p_.z(), q_WS_.w(),
               q_WS_.x(), q_WS_.y(), q_WS_.z(), v_.x(), v_.y(), v_.z(), w_.x(), w_.y(), w_.z()});
  }
  std::vector<std::string> Columns() const override {
    std::vector<std::string> out;
    for (const char* c : {"x", "y", "z", "qw", "qx", "qy", "qz", "setpoint.x", "setpoint.y", "setpoint.z", "error",
                          "rot_error"}) {
      out.push_back(name() + "." + c);
    }
    return out;
  }
  int ColumnCount() const override { return 12; }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_.x(), p_.y(), p_.z(), q_WS_.w(), q_WS_.x(), q_WS_.y(), q_WS_.z(), p_set_.x(), p_set_.y(),
                     p_set_.z(), (p_set_ - p_).norm(), rot_error_}) {
      *out++ = v;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j;
    j["layout"] = bridge::LayoutJson(kind());
    j["units"] = {{"x", "m"}, {"qw", ""}, {"vx", "m/s"}, {"wx", "rad/s"}};
    j["frame"] = "world";
    j["arm"] = arm_->name();
    j["site"] = config_.site;
    j["status_bits"] = {{"holding", bridge::kStatusHolding}, {"refused", bridge::kStatusRefused},
                        {"watchdog", bridge::kStatusWatchdog}, {"not_owner", bridge::kStatusNotOwner}};
    // an unbounded side or reach reads null
    j["limits"] = {{"workspace_min", config_.workspace_min}, {"workspace_max", config_.workspace_max},
                   {"reach_centre", {reach_centre_.x(), reach_centre_.y(), reach_centre_.z()}},
                   {"reach", reach_radius_},
                   {"tilt_axis", config_.tilt_axis},         {"max_tilt_deg", config_.max_tilt_deg},
                   {"speed_max", config_.max_speed},         {"angular_speed_max", config_.max_angular_speed},
                   {"quaternion_norm_tolerance", kQuaternionNormTolerance}};
    j["gains"] = {{"position", config_.k_position}, {"orientation", config_.k_orientation},
                  {"null_space", config_.k_null}, {"damping", config_.damping}};
    j["limits"]["reach_mode"] = config_.reach == ToolParams::Reach::kAuto    ? "auto"
                                : config_.reach == ToolParams::Reach::kFixed ? "fixed"
                                                                              : "off";
    j["watchdog_periods"] = config_.input.watchdog_periods;
    return j.dump();
  }

 private:
  // the reach sphere of kAuto: the anchors of the chain's joints and the site
  // at the model's reference posture; the distances between them are those of
  // every posture (each lies on one rigid link)
  void ChainLength() {
    std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(model_), mj_deleteData);
    if (!d) throw InputError(who() + ": cannot allocate MuJoCo data");
    mj_kinematics(model_, d.get());
    const std::vector<int>& joints = chain_->joint_ids();
    reach_radius_ = 0;
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const Eigen::Map<const Eigen::Vector3d> a(d->xanchor + 3 * joints[i]);
      const Eigen::Map<const Eigen::Vector3d> b(i + 1 < joints.size() ? d->xanchor + 3 * joints[i + 1]
                                                                      : d->site_xpos + 3 * site_);
      reach_radius_ += (b - a).norm();
    }
    reach_centre_ = Eigen::Map<const Eigen::Vector3d>(d->xanchor + 3 * joints.front());
  }

  // the chain's joint positions and velocities out of mjData (no allocation)
  void ReadChain(const mjData& d) {
    for (int i = 0; i < chain_->dof(); ++i) {
      q_[i] = d.qpos[chain_->qpos_addresses()[i]];
      qd_[i] = d.qvel[chain_->dof_addresses()[i]];
    }
  }

  const mjModel* model_;
  ToolParams config_;
  SimArm* arm_ = nullptr;  // bound by Bind
  double period_s_;
  std::unique_ptr<control::RobotModel> chain_;
  std::unique_ptr<control::TaskSpaceController> controller_;
  std::vector<int> arm_index_;  // chain joint i is arm joint arm_index_[i]
  int site_ = -1;
  double box_min_[3] = {0, 0, 0}, box_max_[3] = {0, 0, 0};
  Eigen::Vector3d reach_centre_ = Eigen::Vector3d::Zero(), tilt_axis_ = -Eigen::Vector3d::UnitZ();
  double cos_max_tilt_ = -1;
  double reach_radius_ = INFINITY;  // m
  Eigen::VectorXd q_, qd_;
  bridge::ArmCommand velocity_, hold_;
  Eigen::Vector3d p_cmd_ = Eigen::Vector3d::Zero(), p_set_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_cmd_ = Eigen::Matrix3d::Identity(), R_set_ = Eigen::Matrix3d::Identity();
  // last sample
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero(), w_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WS_ = Eigen::Quaterniond::Identity();
  double rot_error_ = 0;
  bool holding_ = true, resume_ = false;
};

std::vector<double> Vector3(MapReader& r, const std::string& key, std::vector<double> fallback) {
  std::vector<double> v = r.Numbers(key, std::move(fallback));
  if (v.size() != 3) r.Fail(key, "needs 3 numbers (x, y, z), world frame");
  return v;
}

}  // namespace

std::shared_ptr<const DeviceParams> ReadToolParams(MapReader& r) {
  auto p = std::make_shared<ToolParams>();
  p->arm = r.String("arm");
  p->site = r.String("site", p->site);
  p->base_body = r.String("base_body", p->base_body);
  MapReader gains = r.Map("gains");
  p->k_position = gains.Number("position", p->k_position);
  p->k_orientation = gains.Number("orientation", p->k_orientation);
  p->k_null = gains.Number("null_space", p->k_null);
  p->damping = gains.Number("damping", p->damping);
  if (!(p->k_position > 0 && p->k_orientation > 0 && p->k_null >= 0 && p->damping >= 0)) {
    gains.Fail("position", "position and orientation must be > 0, null_space and damping >= 0");
  }
  gains.Finish();
  p->max_speed = r.Number("max_speed", p->max_speed);
  if (!(p->max_speed > 0)) r.Fail("max_speed", "must be > 0 m/s");
  p->max_angular_speed = r.Number("max_angular_speed", p->max_angular_speed);
  if (!(p->max_angular_speed > 0)) r.Fail("max_angular_speed", "must be > 0 rad/s");
  MapReader box = r.Map("workspace");
  p->workspace_min = Vector3(box, "min", p->workspace_min);
  p->workspace_max = Vector3(box, "max", p->workspace_max);
  for (int i = 0; i < 3; ++i) {
    if (!(p->workspace_min[i] < p->workspace_max[i])) box.Fail("max", "must be > min in x, y and z");
  }
  box.Finish();
  const YAML::Node reach_node = r.Raw("reach");
  if (reach_node.IsDefined() && reach_node.IsScalar()) {
    const std::string mode = reach_node.Scalar();
    if (mode != "auto" && mode != "off") r.Fail("reach", "is auto, off or {centre: [x, y, z], radius: m}");
    p->reach = mode == "auto" ? ToolParams::Reach::kAuto : ToolParams::Reach::kOff;
  } else if (reach_node.IsDefined()) {
    MapReader reach = r.Map("reach");
    p->reach = ToolParams::Reach::kFixed;
    p->reach_centre = Vector3(reach, "centre", p->reach_centre);
    p->reach_radius = reach.Number("radius");
    if (!(p->reach_radius > 0)) reach.Fail("radius", "must be > 0 m");
    reach.Finish();
  }
  MapReader tilt = r.Map("tilt");
  p->tilt_axis = Vector3(tilt, "axis", p->tilt_axis);
  if (Eigen::Vector3d(p->tilt_axis[0], p->tilt_axis[1], p->tilt_axis[2]).norm() < 1e-9) {
    tilt.Fail("axis", "must not be zero");
  }
  p->max_tilt_deg = tilt.Number("max_deg", p->max_tilt_deg);
  if (!(p->max_tilt_deg > 0 && p->max_tilt_deg <= 180)) tilt.Fail("max_deg", "must be > 0 and <= 180 deg");
  tilt.Finish();
  ReadCommandInput(r, &p->input);
  return p;
}

std::unique_ptr<Device> MakeTool(const DeviceContext& context, const DeviceConfig& config) {
  return std::make_unique<SimTool>(context, config);
}

}  // namespace vlab::lab
