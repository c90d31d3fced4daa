// servoj(q): a streamed joint reference, one per control period (URScript's
// servoj): the script computes the arm's joint angles for the next period, the
// arm gets them as its position command, and the call returns a period later.
// A stream cannot be slowed down as a planned move is, so a reference beyond a
// joint's range, or one that needs more speed or acceleration than the joint's
// limits (limits(): task_rates.h) from the two references before it, is an
// error at the script's line naming the joint; the arm keeps its last one.
//
// The prelude's servoj (task_api.cc) waits for a running move first, then
// calls _servoj and waits the period.
#include <cmath>
#include <cstdio>
#include <utility>

#include <lua.hpp>

#include "task/task_api_args.h"
#include "task/task_lua.h"

namespace vlab::task {

namespace {

// why the reference q (chain order, rad) cannot be streamed, into `why` (empty: it can)
void Refusal(const Robot& r, const double* q, double period_s, char* why, std::size_t size) {
  const int n = r.model->dof();
  const JointRateLimits& limits = r.planner->rate_limits();
  const bool history = r.q_ref_before.size() == n;
  for (int i = 0; i < n && !why[0]; ++i) {
    const char* joint = r.model->joint_names()[i].c_str();
    if (q[i] > r.model->upper_limits()[i] || q[i] < r.model->lower_limits()[i]) {
      const bool upper = q[i] > r.model->upper_limits()[i];
      std::snprintf(why, size, "joint %s = %.6g deg is beyond its %s limit %.6g deg", joint, q[i] / kDeg,
                    upper ? "upper" : "lower",
                    (upper ? r.model->upper_limits()[i] : r.model->lower_limits()[i]) / kDeg);
      break;
    }
    const double v = (q[i] - r.q_ref[i]) / period_s;
    const double v_before = history ? (r.q_ref[i] - r.q_ref_before[i]) / period_s : 0.0;
    const double a = (v - v_before) / period_s;
    if (std::abs(v) > limits.v_rps[i]) {
      std::snprintf(why, size,
                    "joint %s needs %.6g deg/s (from %.6g to %.6g deg in one period); its limit is %.6g deg/s "
                    "(a streamed reference is not slowed down)",
                    joint, std::abs(v) / kDeg, r.q_ref[i] / kDeg, q[i] / kDeg, limits.v_rps[i] / kDeg);
    } else if (std::abs(a) > limits.a_rps2[i]) {
      std::snprintf(why, size,
                    "joint %s needs %.6g deg/s^2 (its speed from %.6g to %.6g deg/s in one period); its limit is "
                    "%.6g deg/s^2 (a streamed reference is not slowed down)",
                    joint, std::abs(a) / kDeg, v_before / kDeg, v / kDeg, limits.a_rps2[i] / kDeg);
    }
  }
}

int ServoJ(lua_State* L) {
  Robot& r = NeedRobot(L, "servoj");
  if (r.force.on) {
    ScriptError(L,
                "servoj: not in force mode: only movel, movel_rel, movec, movep and search follow a path there "
                "(end_force_mode() first)");
  }
  if (!lua_istable(L, 1)) ScriptError(L, "servoj: expected a table of joint angles (deg), got %s", luaL_typename(L, 1));
  if (!lua_isnone(L, 2)) ScriptError(L, "servoj: takes one argument, the joint angles (deg)");
  const int n = r.model->dof();
  const double* q = JointAngles(L, 1, n, "servoj");
  char why[400] = "";
  Refusal(r, q, ProgramOf(L)->period_s, why, sizeof why);
  if (why[0]) ScriptError(L, "servoj: %s", why);
  Plan plan;
  plan.q.emplace_back(Eigen::Map<const Eigen::VectorXd>(q, n));
  plan.duration_s = ProgramOf(L)->period_s;
  StartPlan(&r, std::move(plan));
  return 0;
}

}  // namespace

void OpenServo(lua_State* L) { lua_register(L, "_servoj", ServoJ); }

}  // namespace vlab::task
