// Ground truth of a PowerBall (powerball_truth.h).
#include "lab/devices/powerball_truth.h"

#include <algorithm>
#include <cmath>

#include "core/core_errors.h"

namespace vlab::lab {
namespace {

int Find(const mjModel& model, mjtObj type, const char* name, const std::string& where) {
  const int id = mj_name2id(&model, type, name);
  if (id < 0) {
    throw InputError(where + ": no " +
                     (type == mjOBJ_BODY    ? "body"
                      : type == mjOBJ_JOINT ? "joint"
                                            : "geom") +
                     " '" + name + "' (a PowerBall needs mjcf/powerball/powerball.xml)");
  }
  return id;
}

int HingeDof(const mjModel& model, const char* name, const std::string& where) {
  const int joint = Find(model, mjOBJ_JOINT, name, where);
  if (model.jnt_type[joint] != mjJNT_HINGE) throw InputError(where + ": joint '" + name + "' is not a hinge");
  return model.jnt_dofadr[joint];
}

}  // namespace

PowerballBinding PowerballBinding::Bind(const mjModel& model, const std::string& where) {
  PowerballBinding b;
  b.shell_body = Find(model, mjOBJ_BODY, "pb_shell", where);
  b.ring_body = Find(model, mjOBJ_BODY, "pb_ring", where);
  b.rotor_body = Find(model, mjOBJ_BODY, "pb_rotor", where);
  b.precess_dof = HingeDof(model, "pb_precess", where);
  b.tilt_dof = HingeDof(model, "pb_tilt", where);
  b.spin_dof = HingeDof(model, "pb_spin", where);
  b.tip_plus = Find(model, mjOBJ_GEOM, "pb_tip_plus", where);
  b.tip_minus = Find(model, mjOBJ_GEOM, "pb_tip_minus", where);
  const double* p = model.geom_pos + 3 * b.tip_plus;
  b.groove_radius_m = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  b.tip_radius_m = model.geom_size[3 * b.tip_plus];
  // the rotor's principal axes are its body axes (diaginertia): y is the axle
  b.spin_inertia = model.body_inertia[3 * b.rotor_body + 1];
  if (!(b.groove_radius_m > 0.0) || !(b.tip_radius_m > 0.0) || !(b.spin_inertia > 0.0)) {
    throw InputError(where + ": PowerBall geometry is degenerate (tip at the centre, zero tip radius or spin inertia)");
  }
  return b;
}

double PowerballTruth::CoupleNorm() const {
  return std::sqrt(couple[0] * couple[0] + couple[1] * couple[1] + couple[2] * couple[2]);
}

PowerballTruth MeasurePowerball(const mjModel& model, const mjData& data, const PowerballBinding& ball) {
  PowerballTruth t;
  const double* shell_R = data.xmat + 9 * ball.shell_body;
  const double* rotor_R = data.xmat + 9 * ball.rotor_body;
  for (int i = 0; i < 3; ++i) {
    t.normal[i] = shell_R[3 * i + 2];
    t.axle[i] = rotor_R[3 * i + 1];
  }
  // spin relative to the shell: (w_rotor - w_shell) . a, world-frame angular velocities
  mjtNum v_rotor[6], v_shell[6];
  mj_objectVelocity(&model, &data, mjOBJ_BODY, ball.rotor_body, v_rotor, 0);
  mj_objectVelocity(&model, &data, mjOBJ_BODY, ball.shell_body, v_shell, 0);
  for (int i = 0; i < 3; ++i) t.omega += (v_rotor[i] - v_shell[i]) * t.axle[i];
  t.nu = data.qvel[ball.precess_dof];
  const double rolled = std::abs(t.omega) * ball.tip_radius_m;
  t.slip = std::abs(rolled - std::abs(t.nu) * ball.groove_radius_m) / std::max(rolled, 1e-9);

  // couple of the tip contacts about the rotor's centre; mj_contactForce gives the force
  // geom1 exerts on geom2 in the contact frame (rows of frame: normal, tangents)
  const double* centre = data.xpos + 3 * ball.rotor_body;
  for (int k = 0; k < data.ncon; ++k) {
    const mjContact& contact = data.contact[k];
    double sign = 0.0;
    if (contact.geom2 == ball.tip_plus || contact.geom2 == ball.tip_minus) sign = 1.0;
    if (contact.geom1 == ball.tip_plus || contact.geom1 == ball.tip_minus) sign = -1.0;
    if (sign == 0.0 || contact.efc_address < 0) continue;
    ++t.contacts;
    mjtNum f_contact[6];
    mj_contactForce(&model, &data, k, f_contact);
    double f[3], arm[3];
    for (int i = 0; i < 3; ++i) {
      f[i] = sign * (f_contact[0] * contact.frame[i] + f_contact[1] * contact.frame[3 + i] +
                     f_contact[2] * contact.frame[6 + i]);
      arm[i] = contact.pos[i] - centre[i];
    }
    t.couple[0] += arm[1] * f[2] - arm[2] * f[1];
    t.couple[1] += arm[2] * f[0] - arm[0] * f[2];
    t.couple[2] += arm[0] * f[1] - arm[1] * f[0];
  }
  return t;
}

}  // namespace vlab::lab
