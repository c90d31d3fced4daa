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
// Ownership: as the point device: the device holds its arm's claim and drives it in every period;
// what the arm is sent on its own port is overridden.
// A target inside every limit may still be out of the arm's reach with that
// orientation: the tool then stops as near as the damped least squares gets it
// and NAME.error / .rot_error stay large (the limits are the refusal).
#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "control/task_space.h"
#include "core/core_errors.h"
#include "lab/devices/device_arm_chain.h"
#include "lab/devices/device_task_space.h"
#include "lab/devices/device_tool.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace {

constexpr double kQuaternionNormTolerance = 1e-3;
constexpr int kCommandValues = 7;

class SimTool final : public TaskSpaceDevice<ToolParams> {
 public:
  SimTool(const DeviceContext& context, const DeviceConfig& c) : TaskSpaceDevice(context, c, "tool") {
    reach_centre_ = Eigen::Vector3d(config_.reach_centre[0], config_.reach_centre[1], config_.reach_centre[2]);
    reach_radius_ = config_.reach == ToolParams::Reach::kFixed ? config_.reach_radius : INFINITY;
    if (config_.reach == ToolParams::Reach::kAuto) ChainLength();
    tilt_axis_ = Eigen::Vector3d(config_.tilt_axis[0], config_.tilt_axis[1], config_.tilt_axis[2]).normalized();
    cos_max_tilt_ = std::cos(config_.max_tilt_deg * M_PI / 180);
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
      if (p[i] < config_.workspace_min[i] || p[i] > config_.workspace_max[i]) return bridge::CommandCheck::kLimits;
    }
    if ((p - reach_centre_).norm() > reach_radius_) return bridge::CommandCheck::kLimits;
    const Eigen::Vector3d tool_z = q.normalized() * Eigen::Vector3d::UnitZ();
    if (tool_z.dot(tilt_axis_) < cos_max_tilt_) return bridge::CommandCheck::kLimits;
    return bridge::CommandCheck::kAccept;
  }
  void Command(const std::vector<double>& c) override {
    p_cmd_ = Eigen::Vector3d(c[0], c[1], c[2]);
    R_cmd_ = Eigen::Quaterniond(c[3], c[4], c[5], c[6]).normalized().toRotationMatrix();
    Commanded();
  }

  void Sample(const mjData& d, double) override {
    if (config_.reach == ToolParams::Reach::kAuto) {
      reach_centre_ = Eigen::Map<const Eigen::Vector3d>(d.xanchor + 3 * chain_.model->joint_ids().front());
    }
    const SiteMotion site = ReadSiteMotion(model_, d, chain_);
    p_ = site.p_W;
    q_WS_ = Eigen::Quaterniond(site.R_WS);
    if (q_WS_.w() < 0) q_WS_.coeffs() *= -1;
    w_ = site.w_W;
    v_ = site.v_W;
    rot_error_ = control::OrientationError(R_set_, site.R_WS).norm();
  }

  void State(std::vector<double>* p) const override {
    p->assign({StatusValue(), p_.x(), p_.y(), p_.z(), q_WS_.w(), q_WS_.x(), q_WS_.y(), q_WS_.z(), v_.x(), v_.y(),
               v_.z(), w_.x(), w_.y(), w_.z()});
  }
  std::vector<std::string> Columns() const override {
    return NamedColumns(
        {"x", "y", "z", "qw", "qx", "qy", "qz", "setpoint.x", "setpoint.y", "setpoint.z", "error", "rot_error"});
  }
  int ColumnCount() const override { return 12; }
  void Row(const mjData&, double* out) const override {
    for (double v : {p_.x(), p_.y(), p_.z(), q_WS_.w(), q_WS_.x(), q_WS_.y(), q_WS_.z(), p_set_.x(), p_set_.y(),
                     p_set_.z(), (p_set_ - p_).norm(), rot_error_}) {
      *out++ = v;
    }
  }

  std::string DescribeFacts() const override {
    nlohmann::json j = ArmChainFacts(chain_, config_, kind());
    j["units"] = {{"x", "m"}, {"qw", ""}, {"vx", "m/s"}, {"wx", "rad/s"}};
    // an unbounded side or reach reads null
    j["limits"] = {{"workspace_min", config_.workspace_min},
                   {"workspace_max", config_.workspace_max},
                   {"reach_centre", {reach_centre_.x(), reach_centre_.y(), reach_centre_.z()}},
                   {"reach", reach_radius_},
                   {"tilt_axis", config_.tilt_axis},
                   {"max_tilt_deg", config_.max_tilt_deg},
                   {"speed_max", config_.max_speed},
                   {"angular_speed_max", config_.max_angular_speed},
                   {"quaternion_norm_tolerance", kQuaternionNormTolerance}};
    j["limits"]["reach_mode"] = config_.reach == ToolParams::Reach::kAuto    ? "auto"
                                : config_.reach == ToolParams::Reach::kFixed ? "fixed"
                                                                             : "off";
    return j.dump();
  }

 private:
  void Start(const control::Pose& tip) override {
    p_set_ = p_cmd_ = tip.p_W;
    R_set_ = R_cmd_ = tip.R_W;
  }
  void Resume(const control::Pose& tip) override {
    p_set_ = tip.p_W;
    R_set_ = tip.R_W;
  }
  // rate limits: the set-point moves toward the command at most max_speed, turns at most max_angular_speed
  control::TaskSpaceTarget Advance() override {
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
    p_set_ += step;
    if (turn.norm() > 0) R_set_ = Eigen::AngleAxisd(turn.norm(), turn / turn.norm()).toRotationMatrix() * R_set_;
    return target;
  }

  // the reach sphere of kAuto: the anchors of the chain's joints and the site
  // at the model's reference posture; the distances between them are those of
  // every posture (each lies on one rigid link)
  void ChainLength() {
    std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(model_), mj_deleteData);
    if (!d) throw InputError(who() + ": cannot allocate MuJoCo data");
    mj_kinematics(model_, d.get());
    const std::vector<int>& joints = chain_.model->joint_ids();
    reach_radius_ = 0;
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const Eigen::Map<const Eigen::Vector3d> a(d->xanchor + 3 * joints[i]);
      const Eigen::Map<const Eigen::Vector3d> b(i + 1 < joints.size() ? d->xanchor + 3 * joints[i + 1]
                                                                      : d->site_xpos + 3 * chain_.site);
      reach_radius_ += (b - a).norm();
    }
    reach_centre_ = Eigen::Map<const Eigen::Vector3d>(d->xanchor + 3 * joints.front());
  }

  Eigen::Vector3d reach_centre_ = Eigen::Vector3d::Zero(), tilt_axis_ = -Eigen::Vector3d::UnitZ();
  double cos_max_tilt_ = -1;
  double reach_radius_ = INFINITY;  // m
  Eigen::Vector3d p_cmd_ = Eigen::Vector3d::Zero(), p_set_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_cmd_ = Eigen::Matrix3d::Identity(), R_set_ = Eigen::Matrix3d::Identity();
  // last sample
  Eigen::Vector3d p_ = Eigen::Vector3d::Zero(), v_ = Eigen::Vector3d::Zero(), w_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WS_ = Eigen::Quaterniond::Identity();
  double rot_error_ = 0;
};

std::vector<double> Vector3(MapReader& r, const std::string& key, std::vector<double> fallback) {
  std::vector<double> v = r.Numbers(key, std::move(fallback));
  if (v.size() != 3) r.Fail(key, "needs 3 numbers (x, y, z), world frame");
  return v;
}

}  // namespace

std::shared_ptr<const DeviceParams> ReadToolParams(MapReader& r) {
  auto p = std::make_shared<ToolParams>();
  MapReader gains = ReadArmChainParams(r, p.get());
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
