#include "yoyosim/yoyosim.h"

#include <cmath>
#include <cstdio>
#include <string_view>

#include "bridge/bridge_layouts.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_yoyo.h"
#include "core/core_errors.h"

namespace vlab::yoyosim {

namespace {

constexpr const char* kHandJoints[3] = {"hand_x", "hand_y", "hand_z"};

// payload positions of the point state (bridge_layouts.h; the yoyo state's are in bridge_yoyo.h)
constexpr int Point(std::string_view field) { return bridge::StateIndex(bridge::DeviceKind::kPoint, field); }
constexpr int kPointStatus = Point("status"), kPointX = Point("x"), kPointVx = Point("vx");
static_assert(Point("y") == kPointX + 1 && Point("z") == kPointX + 2 && Point("vy") == kPointVx + 1 &&
                  Point("vz") == kPointVx + 2,
              "the point's x, y, z and vx, vy, vz are consecutive");

// coefficient of `joint` in the fixed tendon `tendon` (0 when absent)
double TendonCoef(const mjModel* m, int tendon, int joint) {
  for (int w = m->tendon_adr[tendon]; w < m->tendon_adr[tendon] + m->tendon_num[tendon]; ++w) {
    if (m->wrap_type[w] == mjWRAP_JOINT && m->wrap_objid[w] == joint) return m->wrap_prm[w];
  }
  return 0;
}

}  // namespace

std::unique_ptr<YoyoSim> YoyoSim::Create(const SimConfig& config) {
  std::unique_ptr<YoyoSim> s(new YoyoSim());
  s->scene_ = config.scene;
  s->model_ = vlab::LoadModel(config.scene);  // throws InputError "scene 'PATH': ..."
  s->data_ = vlab::MakeData(s->model_.get());
  const double h = s->model_->opt.timestep;
  const double steps = config.period_s / h;
  if (!std::isfinite(steps) || !(config.period_s > 0) || std::abs(steps - std::round(steps)) > 1e-9 * steps ||
      std::round(steps) < 1) {
    char text[160];
    std::snprintf(text, sizeof(text), "--period %g s is not a whole number (>= 1) of the scene's %g s timesteps",
                  config.period_s, h);
    throw vlab::InputError(text);
  }
  s->period_s_ = config.period_s;
  s->steps_per_period_ = static_cast<int>(std::lround(steps));
  mj_forward(s->model_.get(), s->data_.get());
  s->CheckScene();
  s->Refresh();
  return s;
}

void YoyoSim::CheckScene() {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  auto fail = [&](const std::string& what) { throw vlab::InputError("scene '" + scene_ + "': " + what); };
  auto id = [&](mjtObj type, const char* name, const char* what) {
    const int i = mj_name2id(m, type, name);
    if (i < 0) fail(std::string("no ") + what + " '" + name + "'");
    return i;
  };
  hand_body_ = id(mjOBJ_BODY, "hand", "body");
  centre_site_ = id(mjOBJ_SITE, "yoyo_centre", "site");
  const int yoyo_body = id(mjOBJ_BODY, "yoyo", "body");
  const int drop = id(mjOBJ_JOINT, "yoyo_drop", "joint");
  const int spin = id(mjOBJ_JOINT, "yoyo_spin", "joint");
  const int plus = id(mjOBJ_TENDON, "yoyo_string_plus", "tendon");
  plus_force_ = m->sensor_adr[id(mjOBJ_SENSOR, "yoyo_string_plus_force", "sensor")];
  minus_force_ = m->sensor_adr[id(mjOBJ_SENSOR, "yoyo_string_minus_force", "sensor")];
  spin_dof_ = m->jnt_dofadr[spin];

  // the hand: parallel to the world, three limited slides along its axes, one servo each
  const mjtNum* q = d->xquat + 4 * hand_body_;
  if (std::abs(q[0]) < 1 - 1e-12) fail("body 'hand' is turned: its frame must be parallel to the world's");
  for (int i = 0; i < 3; ++i) {
    const int j = id(mjOBJ_JOINT, kHandJoints[i], "joint");
    const std::string where = std::string("joint '") + kHandJoints[i] + "'";
    if (m->jnt_type[j] != mjJNT_SLIDE || m->jnt_bodyid[j] != hand_body_) fail(where + " is not a slide of body 'hand'");
    for (int k = 0; k < 3; ++k) {
      if (m->jnt_axis[3 * j + k] != (k == i ? 1.0 : 0.0)) fail(where + " must slide along the hand's axis " + "xyz"[i]);
    }
    if (!m->jnt_limited[j]) fail(where + " has no range (the range is the hand's workspace)");
    hand_qpos_[i] = m->jnt_qposadr[j];
    hand_dof_[i] = m->jnt_dofadr[j];
    hand_actuator_[i] = -1;
    for (int a = 0; a < m->nu; ++a) {
      if (m->actuator_trntype[a] != mjTRN_JOINT || m->actuator_trnid[2 * a] != j) continue;
      if (hand_actuator_[i] >= 0) fail(where + " has more than one actuator");
      hand_actuator_[i] = a;
    }
    if (hand_actuator_[i] < 0) fail(where + " has no actuator (its position servo)");
    // the start is the hand at qpos0 (slides at 0 unless qpos0 says otherwise)
    start_W_[i] = d->xpos[3 * hand_body_ + i] - d->qpos[hand_qpos_[i]];
    workspace_min_W_[i] = start_W_[i] + m->jnt_range[2 * j];
    workspace_max_W_[i] = start_W_[i] + m->jnt_range[2 * j + 1];
    target_W_[i] = from_W_[i] = d->xpos[3 * hand_body_ + i];
    data_->ctrl[hand_actuator_[i]] = d->qpos[hand_qpos_[i]];
  }

  // the yo-yo, read back from the compiled model
  yoyo_.mass = m->body_mass[yoyo_body];
  mjtNum principal_axes[9];
  mju_quat2Mat(principal_axes, m->body_iquat + 4 * yoyo_body);
  const mjtNum* axis = m->jnt_axis + 3 * spin;
  for (int k = 0; k < 3; ++k) {
    const double c = axis[0] * principal_axes[k] + axis[1] * principal_axes[3 + k] + axis[2] * principal_axes[6 + k];
    yoyo_.spin_inertia += m->body_inertia[3 * yoyo_body + k] * c * c;
  }
  const double drop_coef = TendonCoef(m, plus, drop);
  if (drop_coef == 0) fail("tendon 'yoyo_string_plus' does not hold joint 'yoyo_drop'");
  yoyo_.axle_radius = std::abs(TendonCoef(m, plus, spin) / drop_coef);
  yoyo_.string_length = m->tendon_range[2 * plus + 1];
  yoyo_.gravity = mju_norm3(m->opt.gravity);
}

// positions and velocities of the state now (the first stages of mj_forward:
// pure functions of qpos and qvel, so the next mj_step is unchanged)
void YoyoSim::Refresh() {
  mj_kinematics(model_.get(), data_.get());
  mj_comPos(model_.get(), data_.get());
  mj_comVel(model_.get(), data_.get());
}

bool YoyoSim::WithinWorkspace(const double* target_W) const {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(target_W[i])) return false;
    if (target_W[i] < workspace_min_W_[i] || target_W[i] > workspace_max_W_[i]) return false;
  }
  return true;
}

bool YoyoSim::SetTarget(const double* target_W) {
  if (!WithinWorkspace(target_W)) return false;
  for (int i = 0; i < 3; ++i) target_W_[i] = target_W[i];  // Step moves the reference there
  holding_ = false;
  return true;
}

void YoyoSim::Hold() {
  for (int i = 0; i < 3; ++i) {
    target_W_[i] = from_W_[i] = data_->xpos[3 * hand_body_ + i];
    data_->ctrl[hand_actuator_[i]] = data_->qpos[hand_qpos_[i]];
  }
  holding_ = true;
}

bool YoyoSim::Step() {
  if (diverged_) return false;
  for (int s = 0; s < steps_per_period_; ++s) {
    // the servo reference moves linearly from the old set-point to the new one
    const double f = static_cast<double>(s + 1) / steps_per_period_;
    for (int i = 0; i < 3; ++i) {
      data_->ctrl[hand_actuator_[i]] = from_W_[i] + f * (target_W_[i] - from_W_[i]) - start_W_[i];
    }
    mj_step(model_.get(), data_.get());
    for (int w = 0; w < mjNWARNING; ++w) {
      if (data_->warning[w].number > 0 && vlab::IsDivergenceWarning(w)) {
        diverged_ = true;
        divergence_warning_ = w;
        return false;
      }
    }
  }
  from_W_ = target_W_;
  ++periods_;
  Refresh();
  return true;
}

const char* YoyoSim::divergence() const {
  return divergence_warning_ >= 0 ? vlab::WarningName(divergence_warning_) : "";
}

void YoyoSim::SamplePoint(double* out) const {
  out[kPointStatus] = holding_ ? static_cast<double>(bridge::kStatusHolding) : 0.0;
  for (int i = 0; i < 3; ++i) {
    out[kPointX + i] = data_->xpos[3 * hand_body_ + i];
    out[kPointVx + i] = data_->qvel[hand_dof_[i]];  // the slides run along the world axes
  }
}

void YoyoSim::SampleYoyo(double* out) const {
  mjtNum velocity[6];  // [angular; linear] at the site, world orientation
  mj_objectVelocity(model_.get(), data_.get(), mjOBJ_SITE, centre_site_, velocity, 0);
  const mjtNum* centre = data_->site_xpos + 3 * centre_site_;
  out[bridge::kYoyoStatus] = 0;  // a simulation always sees the yo-yo
  out[bridge::kYoyoX] = centre[0];
  out[bridge::kYoyoY] = centre[1];
  out[bridge::kYoyoZ] = centre[2];
  out[bridge::kYoyoVz] = velocity[5];
  out[bridge::kYoyoStringForce] = data_->sensordata[plus_force_] + data_->sensordata[minus_force_];
  out[bridge::kYoyoSpin] = data_->qvel[spin_dof_];
}

}  // namespace vlab::yoyosim
