#include "lab/devices/device_arm.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bridge/bridge_describe.h"
#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"
#include "lab/scenario/lab_yaml.h"
#include "sensors/sensor_random.h"

namespace vlab::lab {

namespace {

// largest |q_ref - q| the servo keeps, rad (a drive's following-error window)
constexpr double kMaxFollowingError = 0.2;

[[noreturn]] void Fail(const DeviceConfig& c, const std::string& what) {
  throw InputError(c.where + ": device '" + c.name + "': " + what);
}

// limits for the wire: one value per joint, or none where a joint is unlimited
std::vector<double> Limits(const Eigen::VectorXd& v, bool keep_infinite) {
  std::vector<double> out;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (!keep_infinite && !std::isfinite(v[i])) return {};  // unlimited: no limit of that kind
    out.push_back(v[i]);
  }
  return out;
}

// |tau| limits: the smaller side of each motor's range
std::vector<double> TorqueMax(const Eigen::VectorXd& tau_min, const Eigen::VectorXd& tau_max) {
  std::vector<double> out;
  for (Eigen::Index i = 0; i < tau_min.size(); ++i) {
    const double m = std::min(std::abs(tau_min[i]), std::abs(tau_max[i]));
    if (!std::isfinite(m)) return {};
    out.push_back(m);
  }
  return out;
}

// the payload key: {mass: kg, com: [x, y, z] m, inertia: [ixx, iyy, izz(, ixy, ixz, iyz)] kg m^2}
void ReadPayload(MapReader& r, Payload* payload) {
  MapReader p = r.Map("payload");
  if (p.node().size() == 0) return;
  payload->mass_kg = p.Number("mass");
  const std::vector<double> com = p.Numbers("com", {0, 0, 0});
  if (com.size() != 3) p.Fail("com", "needs 3 numbers (x, y, z in the flange frame, m)");
  payload->com_m = Eigen::Vector3d(com[0], com[1], com[2]);
  const std::vector<double> inertia = p.Numbers("inertia", {0, 0, 0});
  if (inertia.size() != 3 && inertia.size() != 6) {
    p.Fail("inertia", "needs 3 or 6 numbers (ixx, iyy, izz[, ixy, ixz, iyz], kg m^2)");
  }
  std::copy(inertia.begin(), inertia.end(), payload->inertia_kgm2.begin());
  p.Finish();
  std::string field, reason;
  if (!CheckPayload(*payload, &field, &reason)) p.Fail(field, reason);
}

}  // namespace

std::shared_ptr<const DeviceParams> ReadArmParams(MapReader& r) {
  auto arm = std::make_shared<ArmParams>();
  arm->joints = r.Strings("joints", {});
  if (arm->joints.empty()) r.Fail("joints", "an arm needs at least one joint");
  arm->actuators = r.Strings("actuators", arm->joints);
  if (arm->actuators.size() != arm->joints.size()) r.Fail("actuators", "needs one actuator per joint");
  arm->initial = r.Numbers("initial", {});
  if (!arm->initial.empty() && arm->initial.size() != arm->joints.size()) {
    r.Fail("initial", "needs one value per joint (" + std::to_string(arm->joints.size()) + ")");
  }
  // initial_jitter: one value for every joint, or one per joint (rad)
  const YAML::Node jitter = r.Raw("initial_jitter");
  if (jitter.IsDefined() && !jitter.IsNull()) {
    arm->initial_jitter = jitter.IsSequence()
                              ? YamlNumbers(r.file(), jitter, r.Child("initial_jitter"))
                              : std::vector<double>{YamlNumber(r.file(), jitter, r.Child("initial_jitter"))};
    if (arm->initial_jitter.size() != 1 && arm->initial_jitter.size() != arm->joints.size()) {
      r.Fail("initial_jitter", "needs one value or one per joint (" + std::to_string(arm->joints.size()) + ")");
    }
    for (double j : arm->initial_jitter) {
      if (!(j >= 0 && j <= M_PI)) r.Fail("initial_jitter", "values must be 0 to pi rad");
    }
    if (arm->initial.empty()) r.Fail("initial_jitter", "needs initial: the joint angles it draws about (rad)");
  }
  MapReader servo = r.Map("servo");
  arm->max_velocity = r.Numbers("max_velocity", {});
  if (!arm->max_velocity.empty() && arm->max_velocity.size() != arm->joints.size()) {
    r.Fail("max_velocity", "needs one value per joint (" + std::to_string(arm->joints.size()) + ")");
  }
  for (double v : arm->max_velocity) {
    if (!(v > 0)) r.Fail("max_velocity", "values must be > 0 rad/s");
  }
  ReadCommandInput(r, &arm->input);
  arm->log_following_error = r.Bool("log_following_error", arm->log_following_error);
  arm->log_command = r.Bool("log_command", arm->log_command);
  arm->servo.bandwidth_hz = servo.Number("bandwidth_hz", arm->servo.bandwidth_hz);
  arm->servo.damping_ratio = servo.Number("damping_ratio", arm->servo.damping_ratio);
  if (!(arm->servo.bandwidth_hz > 0)) servo.Fail("bandwidth_hz", "must be > 0 Hz");
  if (!(arm->servo.damping_ratio > 0)) servo.Fail("damping_ratio", "must be > 0");
  const std::string feedforward = servo.String("feedforward", "world");
  if (feedforward == "model") {
    arm->servo.feedforward = ServoConfig::Feedforward::kModel;
  } else if (feedforward != "world") {
    servo.Fail("feedforward", "must be world or model, got '" + feedforward + "'");
  }
  arm->servo.bodies = servo.Strings("bodies", {});
  servo.Finish();
  ReadPayload(r, &arm->payload);
  arm->sensing = ReadSensing(r, static_cast<int>(arm->joints.size()));
  return arm;
}

std::unique_ptr<Device> MakeArm(const DeviceContext& context, const DeviceConfig& config) {
  return SimArm::Create(context, config);
}

std::unique_ptr<SimArm> SimArm::Create(const DeviceContext& context, const DeviceConfig& c) {
  const mjModel* m = context.model;
  const ArmParams& p = c.ParamsAs<ArmParams>();
  if (m->opt.integrator == mjINT_RK4) {
    throw InputError("scene '" + context.scene +
                     "': arm devices need the Euler or implicit integrator (RK4 "
                     "cannot split the step for the servo)");
  }
  std::unique_ptr<SimArm> arm(new SimArm(c));
  arm->model_ = m;
  arm->command_period_s_ = context.control_period_s;
  arm->joint_names_ = p.joints;
  const int n = static_cast<int>(p.joints.size());
  const double inf = std::numeric_limits<double>::infinity();
  arm->lower_.resize(n);
  arm->upper_.resize(n);
  arm->tau_min_.resize(n);
  arm->tau_max_.resize(n);
  for (int i = 0; i < n; ++i) {
    const std::string& joint = p.joints[i];
    const int j = mj_name2id(m, mjOBJ_JOINT, joint.c_str());
    if (j < 0) Fail(c, "no joint '" + joint + "' in the scene");
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) {
      Fail(c, "joint '" + joint + "' is not a hinge or slide");
    }
    arm->qpos_adr_.push_back(m->jnt_qposadr[j]);
    arm->dof_adr_.push_back(m->jnt_dofadr[j]);
    arm->lower_[i] = m->jnt_limited[j] ? m->jnt_range[2 * j] : -inf;
    arm->upper_[i] = m->jnt_limited[j] ? m->jnt_range[2 * j + 1] : inf;

    const std::string& actuator = p.actuators[i];
    const int a = mj_name2id(m, mjOBJ_ACTUATOR, actuator.c_str());
    if (a < 0) Fail(c, "no actuator '" + actuator + "' in the scene");
    // a torque motor on this very joint: direct transmission, unit-free gain, no bias
    const bool direct = m->actuator_trntype[a] == mjTRN_JOINT && m->actuator_trnid[2 * a] == j;
    const bool motor = m->actuator_dyntype[a] == mjDYN_NONE && m->actuator_gaintype[a] == mjGAIN_FIXED &&
                       m->actuator_biastype[a] == mjBIAS_NONE;
    if (!direct || !motor) Fail(c, "actuator '" + actuator + "' is not a motor on joint '" + joint + "'");
    if (m->actuator_gear[6 * a] != 1.0 || m->actuator_gainprm[mjNGAIN * a] != 1.0) {
      Fail(c, "actuator '" + actuator + "' must have gear 1 and gain 1 (torque in N·m)");
    }
    arm->actuator_ids_.push_back(a);
    arm->tau_min_[i] = m->actuator_ctrllimited[a] ? m->actuator_ctrlrange[2 * a] : -inf;
    arm->tau_max_[i] = m->actuator_ctrllimited[a] ? m->actuator_ctrlrange[2 * a + 1] : inf;
    if (m->actuator_forcelimited[a]) {
      arm->tau_min_[i] = std::max(arm->tau_min_[i], m->actuator_forcerange[2 * a]);
      arm->tau_max_[i] = std::min(arm->tau_max_[i], m->actuator_forcerange[2 * a + 1]);
    }
  }
  if (!p.initial.empty()) {
    arm->has_initial_ = true;
    arm->initial_ = Eigen::Map<const Eigen::VectorXd>(p.initial.data(), n);
    for (int i = 0; i < n; ++i) {
      if (arm->initial_[i] < arm->lower_[i] || arm->initial_[i] > arm->upper_[i]) {
        Fail(c, "initial position of joint '" + p.joints[i] + "' is outside its range");
      }
    }
    // the seeded start: uniform in initial +- jitter, from the device's own stream (the top 53
    // bits of xoshiro256++, as lab_randomize.cc), drawn once
    if (!p.initial_jitter.empty()) {
      sensors::Xoshiro256pp rng(context.seed);
      for (int i = 0; i < n; ++i) {
        const double jitter = p.initial_jitter.size() == 1 ? p.initial_jitter[0] : p.initial_jitter[i];
        if (arm->initial_[i] - jitter < arm->lower_[i] || arm->initial_[i] + jitter > arm->upper_[i]) {
          Fail(c, "initial_jitter: joint '" + p.joints[i] + "' could start outside its range (initial " +
                      FormatDouble(arm->initial_[i]) + " +- " + FormatDouble(jitter) + " rad, range " +
                      FormatDouble(arm->lower_[i]) + " .. " + FormatDouble(arm->upper_[i]) + ")");
        }
        const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0, 1)
        arm->initial_[i] += jitter * (2 * u - 1);
      }
    }
  }
  if (!p.max_velocity.empty()) {
    arm->max_velocity_ = Eigen::Map<const Eigen::VectorXd>(p.max_velocity.data(), n);
  }
  // the servo's own model, with the declared payload
  std::vector<int> joint_ids;
  for (const std::string& joint : p.joints) joint_ids.push_back(mj_name2id(m, mjOBJ_JOINT, joint.c_str()));
  arm->welds_ = ArmWelds::Find(*m, joint_ids);
  try {
    arm->servo_model_ = ArmServoModel::Create(*m, joint_ids, p.servo.bodies);
  } catch (const InputError& e) {
    Fail(c, e.what());
  }
  std::string why;
  if (!arm->servo_model_->SetPayload(p.payload, &why)) Fail(c, "payload." + why);
  arm->feedforward_kind_ = p.servo.feedforward;
  arm->feedforward_ = Eigen::VectorXd::Zero(n);
  arm->sensing_.Configure(p.sensing, n);
  arm->q_true_ = Eigen::VectorXd::Zero(n);
  arm->qd_true_ = Eigen::VectorXd::Zero(n);
  arm->watchdog_periods_ = p.input.watchdog_periods;
  arm->owner_timeout_s_ = p.input.owner_timeout_s;
  arm->log_following_error_ = p.log_following_error;
  arm->log_command_ = p.log_command;
  arm->bandwidth_hz_ = p.servo.bandwidth_hz;
  arm->damping_ratio_ = p.servo.damping_ratio;
  arm->value_ = Eigen::VectorXd::Zero(n);
  arm->q_ref_ = Eigen::VectorXd::Zero(n);
  arm->qd_ref_ = Eigen::VectorXd::Zero(n);
  arm->last_position_command_ = Eigen::VectorXd::Zero(n);
  arm->tau_ = Eigen::VectorXd::Zero(n);
  arm->state_.q = arm->state_.qd = arm->state_.tau = Eigen::VectorXd::Zero(n);
  arm->message_.q.reserve(n);
  arm->message_.qd.reserve(n);
  arm->message_.tau.reserve(n);
  arm->wire_command_.value.reserve(bridge::kMaxPacketValues);
  arm->command_.value.resize(n);
  return arm;
}

void SimArm::SetInitialState(mjData& d) const {
  if (!has_initial_) return;
  for (int i = 0; i < dof(); ++i) d.qpos[qpos_adr_[i]] = initial_[i];
  if (welds_.empty()) return;
  // a welded gripper to its weld's pose at these joints (the arm's bodies first)
  mj_kinematics(model_, &d);
  welds_.Place(*model_, d);
}

void SimArm::Start(mjData& d) {
  const mjModel* m = model_;
  // joint inertia H_ii: the world's (qM diagonal) or the servo model's at this pose
  const bool own_model = feedforward_kind_ == ServoConfig::Feedforward::kModel;
  servo_model_->Place(d);
  if (own_model) servo_model_->InertiaDiagonal(d, feedforward_.data());  // (its buffer, free until Actuate)
  const double w = 2.0 * M_PI * bandwidth_hz_;
  if (sensing_.enabled()) Sense(d, 0.0);  // the encoders' first reading: the reference holds it
  kp_.resize(dof());
  kd_.resize(dof());
  for (int i = 0; i < dof(); ++i) {
    const double inertia = own_model ? feedforward_[i] : d.qM[m->dof_Madr[dof_adr_[i]]];
    kp_[i] = inertia * w * w;
    kd_[i] = 2.0 * damping_ratio_ * inertia * w;
    q_ref_[i] = sensing_.enabled() ? sensing_.q()[i] : d.qpos[qpos_adr_[i]];
  }
  qd_ref_.setZero();
  mode_ = bridge::ArmMode::kHold;
  have_position_command_ = false;
  // the servo holds from the first instant: its torques for the forces the lab recomputes next
  Actuate(d, 0.0);
}

void SimArm::Reset(const mjData& d) { Sample(d, d.time, &state_); }

void SimArm::Resume(const mjData& d, const Eigen::VectorXd& q_ref) {
  if (sensing_.enabled()) {
    // the encoders last read the joints a physics step ago: their counts there, so that the
    // next step's difference velocity is the one over that step
    Gather(d);
    const double dt = model_->opt.timestep;
    const Eigen::VectorXd q_before = q_true_ - qd_true_ * dt;
    sensing_.Sense(q_before.data(), qd_true_.data(), 0.0);
  }
  q_ref_ = q_ref;
  qd_ref_.setZero();
  mode_ = bridge::ArmMode::kHold;
  have_position_command_ = false;
  last_refused_ = false;
}

void SimArm::Sample(const mjData& d, double t) { Sample(d, t, &state_); }

bool SimArm::Command(const bridge::ArmCommand& cmd) {
  bool ok = cmd.value.size() == dof() || cmd.mode == bridge::ArmMode::kHold;
  for (int i = 0; ok && i < cmd.value.size(); ++i) {
    const double v = cmd.value[i];
    ok = std::isfinite(v);
    if (ok && cmd.mode == bridge::ArmMode::kPosition) ok = v >= lower_[i] && v <= upper_[i];
    if (ok && cmd.mode == bridge::ArmMode::kTorque) ok = v >= tau_min_[i] && v <= tau_max_[i];
    if (ok && cmd.mode == bridge::ArmMode::kVelocity && max_velocity_.size() > 0) ok = std::abs(v) <= max_velocity_[i];
  }
  last_refused_ = !ok;
  if (!ok) {
    ++refused_;
    return false;
  }
  switch (cmd.mode) {
    case bridge::ArmMode::kHold:
      if (mode_ != bridge::ArmMode::kHold) qd_ref_.setZero();
      break;
    case bridge::ArmMode::kPosition:
      if (have_position_command_) {
        qd_ref_ = (cmd.value - last_position_command_) / command_period_s_;
      } else {
        qd_ref_.setZero();
      }
      q_ref_ = cmd.value;
      last_position_command_ = cmd.value;
      have_position_command_ = true;
      break;
    case bridge::ArmMode::kVelocity:
      qd_ref_ = cmd.value;
      break;
    case bridge::ArmMode::kTorque:
      value_ = cmd.value;
      break;
  }
  if (cmd.mode != bridge::ArmMode::kPosition) have_position_command_ = false;
  mode_ = cmd.mode;
  return true;
}

bool SimArm::SetPayload(const Payload& payload, std::string* why) { return servo_model_->SetPayload(payload, why); }

void SimArm::Actuate(mjData& d, double dt) {
  saturated_ = false;
  // what the drive knows of its joints: the encoders' reading, or the exact state
  const bool sensed = sensing_.enabled();
  if (sensed) Sense(d, dt);
  // the servo model's bias torques, once per step, when a servo mode uses them: at the joint
  // state the drive reads (the counts when it senses them), as a real controller's model runs
  const bool own_model = feedforward_kind_ == ServoConfig::Feedforward::kModel && mode_ != bridge::ArmMode::kTorque;
  if (own_model) {
    if (sensed) {
      servo_model_->Bias(sensing_.q().data(), sensing_.qd().data(), feedforward_.data());
    } else {
      servo_model_->Bias(d, feedforward_.data());
    }
  }
  for (int i = 0; i < dof(); ++i) {
    const double q = sensed ? sensing_.q()[i] : d.qpos[qpos_adr_[i]];
    const double qd = sensed ? sensing_.qd()[i] : d.qvel[dof_adr_[i]];
    double tau;
    if (mode_ == bridge::ArmMode::kTorque) {
      tau = value_[i];
      q_ref_[i] = q;  // so a later switch to a servo mode starts from here
    } else {
      if (mode_ == bridge::ArmMode::kVelocity) q_ref_[i] += qd_ref_[i] * dt;
      // following-error limit: a blocked joint (contact, limit) must not wind
      // the reference up, or it would spring away when released
      q_ref_[i] = std::min(std::max(q_ref_[i], q - kMaxFollowingError), q + kMaxFollowingError);
      const double bias = own_model ? feedforward_[i] : d.qfrc_bias[dof_adr_[i]];
      tau = kp_[i] * (q_ref_[i] - q) + kd_[i] * (qd_ref_[i] - qd) + bias;
    }
    if (tau > tau_max_[i] || tau < tau_min_[i]) {
      saturated_ = true;
      tau = std::min(std::max(tau, tau_min_[i]), tau_max_[i]);
    }
    tau_[i] = tau;
    d.ctrl[actuator_ids_[i]] = tau;
  }
}

void SimArm::Sample(const mjData& d, double time_s, bridge::ArmState* s) const {
  s->time_s = time_s;
  s->q.resize(dof());
  s->qd.resize(dof());
  s->tau.resize(dof());
  bool at_limit = false;
  if (sensing_.enabled()) Peek(d, s->q.data(), s->qd.data());
  for (int i = 0; i < dof(); ++i) {
    if (!sensing_.enabled()) {
      s->q[i] = d.qpos[qpos_adr_[i]];
      s->qd[i] = d.qvel[dof_adr_[i]];
    }
    s->tau[i] = tau_[i];
    at_limit = at_limit || s->q[i] <= lower_[i] || s->q[i] >= upper_[i];
  }
  std::uint32_t status = 0;
  if (mode_ == bridge::ArmMode::kHold) status |= bridge::kArmHolding;
  if (last_refused_) status |= bridge::kArmCommandRefused;
  if (saturated_) status |= bridge::kArmTorqueSaturated;
  if (at_limit) status |= bridge::kArmAtJointLimit;
  s->status = status;
}

std::vector<std::string> SimArm::Columns() const {
  std::vector<std::string> columns;
  for (const char* quantity : {"q", "qd", "tau"}) {
    for (const auto& joint : joint_names_) columns.push_back(name() + "." + quantity + "." + joint);
  }
  columns.push_back(name() + ".limit_violation");
  if (log_following_error_) columns.push_back(name() + ".following_error");
  if (log_command_) {
    columns.push_back(name() + ".cmd_mode");
    for (const auto& joint : joint_names_) columns.push_back(name() + ".cmd." + joint);
  }
  return columns;
}

void SimArm::Row(const mjData& d, double* out) const {
  const int n = dof();
  double violation = 0.0;
  if (sensing_.enabled()) Peek(d, out, out + n);  // the sensed q and qd
  for (int i = 0; i < n; ++i) {
    const double q = d.qpos[qpos_adr_[i]];  // the limits: of the true q
    if (!sensing_.enabled()) {
      out[i] = q;
      out[n + i] = d.qvel[dof_adr_[i]];
    }
    out[2 * n + i] = tau_[i];
    violation = std::max({violation, lower_[i] - q, q - upper_[i]});
  }
  out[3 * n] = violation;
  int next = 3 * n + 1;
  if (log_following_error_) {
    double following = 0.0;  // (torque mode: q_ref follows q, one step behind; sensed q when sensing)
    for (int i = 0; i < n; ++i) {
      following = std::max(following, std::abs(q_ref_[i] - (sensing_.enabled() ? out[i] : d.qpos[qpos_adr_[i]])));
    }
    out[next++] = following;
  }
  if (!log_command_) return;
  // the command in force: its mode and value (hold: the position the servo holds)
  out[next++] = static_cast<double>(static_cast<int>(mode_));
  const Eigen::VectorXd& value = mode_ == bridge::ArmMode::kHold       ? q_ref_
                                 : mode_ == bridge::ArmMode::kPosition ? last_position_command_
                                 : mode_ == bridge::ArmMode::kVelocity ? qd_ref_
                                                                       : value_;
  for (int i = 0; i < n; ++i) out[next + i] = value[i];
}

void SimArm::Gather(const mjData& d) const {
  for (int i = 0; i < dof(); ++i) {
    q_true_[i] = d.qpos[qpos_adr_[i]];
    qd_true_[i] = d.qvel[dof_adr_[i]];
  }
}

void SimArm::Sense(const mjData& d, double dt) {
  Gather(d);
  sensing_.Sense(q_true_.data(), qd_true_.data(), dt);
}

void SimArm::Peek(const mjData& d, double* q, double* qd) const {
  // between two steps: what the next step's servo will sense (its difference over one timestep)
  Gather(d);
  sensing_.Peek(q_true_.data(), qd_true_.data(), model_->opt.timestep, q, qd);
}

void SimArm::Hold() {
  command_.mode = bridge::ArmMode::kHold;
  Command(command_);
}

bool SimArm::TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>* scratch) {
  (void)scratch;
  // a payload the owner set: from this period on (the endpoint checked it with CheckPayload)
  bridge::ArmPayloadMsg payload;
  if (endpoint.TakePayload(&payload)) SetPayload(PayloadFromWire(payload));
  if (!endpoint.TakeArmCommand(&wire_command_)) return false;
  command_.mode = static_cast<bridge::ArmMode>(wire_command_.mode);
  command_.value = Eigen::Map<const Eigen::VectorXd>(wire_command_.value.data(),
                                                     static_cast<Eigen::Index>(wire_command_.value.size()));
  Command(command_);
  return true;
}

void SimArm::EncodeState(double seq, double t, std::uint32_t endpoint_bits, std::vector<double>* scratch,
                         std::vector<unsigned char>* out) const {
  (void)scratch;
  message_.status = state_.status | endpoint_bits;
  message_.q.assign(state_.q.data(), state_.q.data() + state_.q.size());
  message_.qd.assign(state_.qd.data(), state_.qd.data() + state_.qd.size());
  message_.tau.assign(state_.tau.data(), state_.tau.data() + state_.tau.size());
  bridge::EncodeArmState(seq, t, message_, out);
}

void SimArm::ConfigureEndpoint(double, bridge::EndpointConfig* ec) const {
  ec->kind = bridge::DeviceKind::kArm;
  ec->owner_timeout_s = owner_timeout_s_;
  ec->joints = dof();
  ec->position_min = Limits(lower_, true);
  ec->position_max = Limits(upper_, true);
  ec->velocity_max = Limits(max_velocity_, false);
  ec->torque_max = TorqueMax(tau_min_, tau_max_);
  ec->watchdog_periods = watchdog_periods_;
  // the payload in force; a new one the endpoint checks by the one rule (CheckArmPayload,
  // which CheckPayload is)
  ec->payload = PayloadToWire(payload());
}

std::string SimArm::DescribeJson(const bridge::DeviceDescription& common) const {
  bridge::ArmDescription desc;
  desc.joints = joint_names_;
  desc.position_min = Limits(lower_, false);
  desc.position_max = Limits(upper_, false);
  desc.velocity_max = Limits(max_velocity_, false);
  desc.torque_max = TorqueMax(tau_min_, tau_max_);
  desc.watchdog_periods = watchdog_periods_;
  desc.owner_timeout_s = owner_timeout_s_;
  if (sensing_.enabled()) {
    for (int i = 0; i < dof(); ++i) desc.resolution.push_back(sensing_.resolution(i));
  }
  desc.payload = PayloadToWire(payload());
  desc.feedforward = feedforward_kind_ == ServoConfig::Feedforward::kModel ? "model" : "world";
  static_cast<bridge::DeviceDescription&>(desc) = common;
  return bridge::DescribeJson(desc);
}

}  // namespace vlab::lab
