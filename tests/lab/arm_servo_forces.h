// Closed forms for the arm servo tests: the joint torques J^T F of a force at a
// body's centre of mass, written from the joint axes and anchors alone (no
// MuJoCo Jacobian, no inverse dynamics).
#pragma once

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

namespace vlab::lab {

/// J^T F: the generalized force of `force_N` (world frame) applied at the centre
/// of mass of `body`, at each joint of `joints` (ids): axis . ((p - anchor) x F)
/// for a hinge, axis . F for a slide, 0 for a joint that does not move the body.
/// Needs positions computed (mj_kinematics).
inline std::vector<double> JointForces(const mjModel* m, const mjData* d, const std::vector<int>& joints, int body,
                                       const double force_N[3]) {
  std::vector<double> out;
  for (int j : joints) {
    bool moves = false;
    for (int b = body; b > 0 && !moves; b = m->body_parentid[b]) moves = b == m->jnt_bodyid[j];
    double value = 0.0;
    if (moves && m->jnt_type[j] == mjJNT_HINGE) {
      double arm[3], moment[3];
      mju_sub3(arm, d->xipos + 3 * body, d->xanchor + 3 * j);
      mju_cross(moment, arm, force_N);
      value = mju_dot3(d->xaxis + 3 * j, moment);
    } else if (moves) {
      value = mju_dot3(d->xaxis + 3 * j, force_N);
    }
    out.push_back(value);
  }
  return out;
}

/// The bias torque the weight of `bodies` (names) adds at `joints`: -J^T (m g)
/// summed over the bodies, i.e. what a servo must add to hold them.
inline std::vector<double> WeightBias(const mjModel* m, const mjData* d, const std::vector<int>& joints,
                                      const std::vector<std::string>& bodies) {
  std::vector<double> out(joints.size(), 0.0);
  for (const std::string& name : bodies) {
    const int b = mj_name2id(m, mjOBJ_BODY, name.c_str());
    double weight[3];
    mju_scl3(weight, m->opt.gravity, m->body_mass[b]);
    const std::vector<double> torques = JointForces(m, d, joints, b, weight);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] -= torques[i];
  }
  return out;
}

}  // namespace vlab::lab
