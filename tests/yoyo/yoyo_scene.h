// The fixed-hand yo-yo scene (mjcf/yoyo/yoyo_fixed_hand.xml) for tests: a fixture on the
// MuJoCo fixture (any undeclared MuJoCo warning fails the test), the yo-yo's parameters
// read back from the compiled model, and the closed forms of DATASHEET §6.3 computed from them.
#pragma once

#include <cmath>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mujoco_fixture.h"

namespace vlab::yoyo::testing {

/// The yo-yo as the compiled model has it (SI units), with the closed forms of DS §6.3.
struct Yoyo {
  int drop_qpos = -1, spin_qpos = -1;     // qpos addresses of d and theta
  int drop_dof = -1, spin_dof = -1;       // their qvel addresses
  int plus_force = -1, minus_force = -1;  // sensordata addresses of the tendon limit forces
  double mass = 0;                        // m, kg
  double spin_inertia = 0;                // J about the spin axis, kg m^2
  double axle_radius = 0;                 // r, m: the spin coefficient of the string tendons
  double length = 0;                      // L, m: the string tendons' limit
  double gravity = 0;                     // g along the descent direction, m/s^2
  double timestep = 0;                    // h, s
  double steady_stretch = 0;              // string stretch under the yo-yo's weight, m (ReadYoyo)

  /// Descent acceleration on a taut string, a = g m r^2 / (m r^2 + J), m/s^2.
  double Descent() const { return gravity * MassR2() / (MassR2() + spin_inertia); }
  /// String tension during the descent (or climb), T = m g J / (J + m r^2), N.
  double Tension() const { return mass * gravity * spin_inertia / (spin_inertia + MassR2()); }
  /// Equivalent restitution of the bottom, e = (J - m r^2) / (J + m r^2).
  double Restitution() const { return (spin_inertia - MassR2()) / (spin_inertia + MassR2()); }
  /// Kinetic energy (m + J/r^2) v^2 / 2 of a yo-yo descending at v on a taut string, J.
  double RollingEnergy(double v) const { return 0.5 * (mass + spin_inertia / (axle_radius * axle_radius)) * v * v; }
  /// m r^2, kg m^2: the mass's share of the inertia about the string's contact point.
  double MassR2() const { return mass * axle_radius * axle_radius; }
};

/// Fixed tendon coefficient of `joint` in `tendon` (0 when absent).
inline double TendonCoef(const mjModel* m, int tendon, int joint) {
  for (int w = m->tendon_adr[tendon]; w < m->tendon_adr[tendon] + m->tendon_num[tendon]; ++w) {
    if (m->wrap_type[w] == mjWRAP_JOINT && m->wrap_objid[w] == joint) return m->wrap_prm[w];
  }
  return 0;
}

/// Reads the yo-yo's parameters from the model (fails the test on a missing part).
/// `d` must have been through mj_forward (for the slide axis in the world frame).
inline Yoyo ReadYoyo(const mjModel* m, const mjData* d) {
  Yoyo y;
  const int body = mj_name2id(m, mjOBJ_BODY, "yoyo");
  const int drop = mj_name2id(m, mjOBJ_JOINT, "yoyo_drop");
  const int spin = mj_name2id(m, mjOBJ_JOINT, "yoyo_spin");
  const int plus = mj_name2id(m, mjOBJ_TENDON, "yoyo_string_plus");
  const int plus_force = mj_name2id(m, mjOBJ_SENSOR, "yoyo_string_plus_force");
  const int minus_force = mj_name2id(m, mjOBJ_SENSOR, "yoyo_string_minus_force");
  if (body < 0 || drop < 0 || spin < 0 || plus < 0 || plus_force < 0 || minus_force < 0) {
    ADD_FAILURE() << "yo-yo body, joints, tendon or force sensors missing";
    return y;
  }
  y.drop_qpos = m->jnt_qposadr[drop];
  y.spin_qpos = m->jnt_qposadr[spin];
  y.drop_dof = m->jnt_dofadr[drop];
  y.spin_dof = m->jnt_dofadr[spin];
  y.plus_force = m->sensor_adr[plus_force];
  y.minus_force = m->sensor_adr[minus_force];
  y.mass = m->body_mass[body];
  // inertia about the hinge axis (body frame) from the principal inertia and its frame
  mjtNum principal_axes[9];
  mju_quat2Mat(principal_axes, m->body_iquat + 4 * body);
  const mjtNum* axis = m->jnt_axis + 3 * spin;
  for (int k = 0; k < 3; ++k) {
    const double c = axis[0] * principal_axes[k] + axis[1] * principal_axes[3 + k] + axis[2] * principal_axes[6 + k];
    y.spin_inertia += m->body_inertia[3 * body + k] * c * c;
  }
  y.axle_radius = TendonCoef(m, plus, spin) / TendonCoef(m, plus, drop);
  y.length = m->tendon_range[2 * plus + 1];
  y.gravity = mju_dot3(m->opt.gravity, d->xaxis + 3 * drop);
  y.timestep = m->opt.timestep;
  // steady stretch of a soft limit under a constant load g: d k x = (1 - d) g with
  // k = d / (dmax tc dampratio)^2 (MuJoCo's solref/solimp), i.e. x = (1 - d) g (dmax tc dr / d)^2
  const double tc = m->tendon_solref_lim[2 * plus], dr = m->tendon_solref_lim[2 * plus + 1];
  const double imp = m->tendon_solimp_lim[5 * plus + 1];  // dmax
  if (m->tendon_solimp_lim[5 * plus] != imp) ADD_FAILURE() << "the stretch formula assumes solimp dmin = dmax";
  y.steady_stretch = (1 - imp) * y.gravity * tc * tc * dr * dr;
  return y;
}

/// String tension, N: the sum of the two tendon limit forces (each >= 0, 0 when slack).
inline double Tension(const Yoyo& y, const mjData* d) {
  return d->sensordata[y.plus_force] + d->sensordata[y.minus_force];
}

/// String excess |d| + r |theta| - L, m: <= 0 when the string holds, > 0 stretched.
inline double Stretch(const Yoyo& y, const mjData* d) {
  return std::abs(d->qpos[y.drop_qpos]) + y.axle_radius * std::abs(d->qpos[y.spin_qpos]) - y.length;
}

/// Mechanical energy (kinetic + gravity, zero at the hand), J. MuJoCo's semi-implicit Euler
/// sets v(n+1) = v(n) + h a, q(n+1) = q(n) + h v(n+1); under a constant force q(n) then runs
/// ahead of the exact parabola by h v(n) / 2, so the height is taken half a step back: with
/// that, the energy of a constant-force phase is conserved to round-off.
inline double Energy(const Yoyo& y, const mjData* d) {
  const double v = d->qvel[y.drop_dof], w = d->qvel[y.spin_dof];
  const double height = -(d->qpos[y.drop_qpos] - 0.5 * y.timestep * v);
  return 0.5 * y.mass * v * v + 0.5 * y.spin_inertia * w * w + y.mass * y.gravity * height;
}

/// Steps `d` until `duration` s have passed since the call or MuJoCo warns (on divergence
/// MuJoCo also resets the data, time included, so loops stop on the warning rather than on
/// d->time); `observe(d)` runs after every step. Returns the number of steps taken.
template <typename Observe>
long StepFor(const mjModel* m, mjData* d, double duration, Observe observe) {
  const long steps = std::lround(duration / m->opt.timestep);
  long step = 0;
  for (; step < steps && !vlab::test::AnyWarning(*d); ++step) {
    mj_step(m, d);
    observe(d);
  }
  return step;
}

/// Test fixture: the scene loaded, data at qpos0 after mj_forward, the yo-yo read back.
class YoyoTest : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("mjcf/yoyo/yoyo_fixed_hand.xml");
    data_ = MakeData(model_);
    mj_forward(model_, data_);
    yoyo_ = ReadYoyo(model_, data_);
  }
  /// Sets d, theta and their rates and runs mj_forward.
  void SetState(double drop, double spin, double drop_rate, double spin_rate) {
    mj_resetData(model_, data_);
    data_->qpos[yoyo_.drop_qpos] = drop;
    data_->qpos[yoyo_.spin_qpos] = spin;
    data_->qvel[yoyo_.drop_dof] = drop_rate;
    data_->qvel[yoyo_.spin_dof] = spin_rate;
    mj_forward(model_, data_);
  }

  const mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  Yoyo yoyo_;
};

}  // namespace vlab::yoyo::testing
