// Force mode and the guards of guarded moves: what a program's robot does
// with its wrench device each period (the Lua side: task_api_force.cc).
//
// Force mode (force_mode ... end_force_mode): along each held axis e_i of
// the task frame the commanded tool position's coordinate c_i is an
// admittance,
//     v_i <- v_i + clamp(clamp(k (F_target,i - F_i), ±v_max) - v_i, ±a_max T)
//     c_i <- c_i + v_i T
// with F the force the tool exerts on the world (the wrench reading less its
// value when the mode started, turned from the sensor's axes into the
// world's), once per control period T. The commanded pose is the running
// move's planned sample (or where the path rests) with its coordinate along
// each held axis replaced by c_i; joints by Newton steps from the last
// reference (MotionPlanner::Track).
#include <algorithm>
#include <cmath>

#include "task/task_program.h"

namespace vlab::task {

Eigen::Vector3d ExertedForce_W(Robot* r, const Eigen::Vector3d& f_sensor, const Eigen::Vector3d& bias) {
  if (r->zero_qd.size() != r->model->dof()) r->zero_qd = Eigen::VectorXd::Zero(r->model->dof());
  r->model->SetState(r->q_meas, r->zero_qd);
  // the reading is the load the tool applies to the sensor; less the tool's weight (the
  // bias) it is the world's push on the tool, so the tool exerts its opposite on the world
  return -(r->model->TipPose().R_W * (f_sensor - bias));
}

const char* GuardTripped(Robot* r) {
  if (!r->guard || !r->guard->Read(&r->reading) || r->reading.size() < 6) return nullptr;
  const std::vector<double>& w = r->reading;
  if (r->guard_force_N > 0) {
    const Eigen::Vector3d f(w[0], w[1], w[2]);
    const double value = r->guard_dir_W.isZero() ? (f - r->guard_bias_N).norm()
                                                 : ExertedForce_W(r, f, r->guard_bias_N).dot(r->guard_dir_W);
    if (value > r->guard_force_N) return "contact";
  }
  if (r->guard_torque_Nm > 0 &&
      (Eigen::Vector3d(w[3], w[4], w[5]) - r->guard_torque_bias_Nm).norm() > r->guard_torque_Nm) {
    return "torque";
  }
  return nullptr;
}

void AdvanceForceMode(Robot* r) {
  ForceMode& f = r->force;
  // the path's pose of this period: the running move's next sample, else where it rests
  if (r->moving) {
    f.nominal_W = r->plan.tool_W[r->next++];
    if (r->next >= r->plan.tool_W.size()) r->moving = false;
  }
  // the force the tool exerts on the world, in the task axes (the last one when no reading came)
  if (f.wrench->Read(&r->reading) && r->reading.size() >= 3) {
    const Eigen::Vector3d reading(r->reading[0], r->reading[1], r->reading[2]);
    f.force_T = f.R_WT.transpose() * ExertedForce_W(r, reading, f.bias_N);
  }
  Frame goal = f.nominal_W;
  const double T = f.period_s;
  for (int i = 0; i < 3; ++i) {
    if (!f.held[i]) continue;
    const double v_want = std::clamp(f.gain_mps_per_N * (f.target_N[i] - f.force_T[i]), -f.v_max_mps, f.v_max_mps);
    f.v_mps[i] += std::clamp(v_want - f.v_mps[i], -f.a_max_mps2 * T, f.a_max_mps2 * T);
    f.c_m[i] += f.v_mps[i] * T;
    const Eigen::Vector3d e = f.R_WT.col(i);
    goal.p += (f.c_m[i] - e.dot(goal.p)) * e;
  }
  Eigen::VectorXd q;
  if (!r->planner->Track(r->q_ref, goal, &q, &f.fault)) {
    f.on = false;
    r->moving = false;
    return;
  }
  r->q_ref = q;
}

}  // namespace vlab::task
