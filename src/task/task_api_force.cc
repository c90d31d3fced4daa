// The task language's force functions: force_mode(target [, opts]),
// end_force_mode(), and the guard options of moves (force, dir, torque,
// wrench, stop_if). What they do each period: task_force.cc.
#include <cmath>
#include <cstring>

#include <lua.hpp>

#include "task/task_api_args.h"
#include "task/task_lua.h"
#include "task/task_program.h"

namespace vlab::task {

namespace {

// The admittance's gain k (m/s per N of force error). The loop: an integrator k/s from the
// force error to the commanded position, then the arm's position servo and the contact
// (together a stiffness K from the commanded position to the force, with the servo's
// dynamics), then the JR3's filter (filter 4: four 2-pole stages, the last at 7.8 Hz, about
// 40 ms of delay) and a period or two of transport delay. Its crossover is w_c = k K.
// Measured on the PA10 pressing the table of scenes/pa10.xml (servo 10 Hz, JR3 filter 4;
// tests/task/task_force_mode_test.cc): K = 1.1e4 N/m (0.44 mm of command for 4.8 N), and
// the loop oscillates from k = 4e-3 (w_c = 44 rad/s, where the filter's and the servo's
// lags reach 180 deg). k = 2e-3 keeps a gain margin of 2 (6 dB) with w_c = 22 rad/s: the
// force settles in about 3 / w_c = 0.15 s and rejects the friction's push when the tool
// starts sliding (within 0.45 N at 10 N, measured). A softer contact lowers K (slower, not
// less stable); a stiffer servo raises it.
constexpr double kForceGain_mps_per_N = 2e-3;
constexpr double kForceSpeed_mps = 0.02;  // the admittance's default speed limit along a held axis

// the wrench device of option `wrench` at `options` (a name), else the program's default;
// an error naming `what` when there is none
Channel* WrenchOf(lua_State* L, Robot& r, int options, const char* what) {
  Channel* w = r.default_wrench;
  if (HasOption(L, options, "wrench")) {
    lua_getfield(L, options, "wrench");
    if (lua_type(L, -1) != LUA_TSTRING) {
      ScriptError(L, "%s: option wrench must be a wrench device's name, got %s", what, luaL_typename(L, -1));
    }
    w = ProgramOf(L)->devices->Find(lua_tostring(L, -1));
    if (!w || w->kind() != bridge::DeviceKind::kWrench) {
      ScriptError(L, "%s: option wrench: no wrench device named '%s'", what, lua_tostring(L, -1));
    }
    lua_pop(L, 1);
  }
  if (!w) {
    ScriptError(L, "%s: needs a wrench device: the program has no default one (option wrench = NAME)", what);
  }
  return w;
}

// ---- force_mode(target [, opts]): {fx = N, fy = N, fz = N}; opts frame, v, wrench
int ForceModeStart(lua_State* L) {
  Robot& r = NeedRobot(L, "force_mode");
  ForceMode& f = r.force;
  if (!lua_istable(L, 1) || ToFrame(L, 1) || ToVec3(L, 1)) {
    ScriptError(L, "force_mode: argument 1 must be a table of the forces to hold, e.g. {fz = 10} (N), got %s",
                ToFrame(L, 1) ? "a frame" : (ToVec3(L, 1) ? "a vec3" : luaL_typename(L, 1)));
  }
  static const char* const axes[] = {"fx", "fy", "fz", nullptr};
  static const Refused torques[] = {
      {"tx", "force mode holds forces only (fx, fy, fz); a torque about a task axis is not held"},
      {"ty", "force mode holds forces only (fx, fy, fz); a torque about a task axis is not held"},
      {"tz", "force mode holds forces only (fx, fy, fz); a torque about a task axis is not held"},
      {nullptr, nullptr}};
  CheckOptions(L, 1, "force_mode: target", axes, torques);
  bool held[3] = {false, false, false};
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    held[i] = HasOption(L, 1, axes[i]);
    target[i] = Option(L, 1, axes[i], 0, "force_mode: target");
  }
  if (!held[0] && !held[1] && !held[2]) ScriptError(L, "force_mode: the target holds no axis: give fx, fy or fz (N)");
  static const char* const known[] = {"frame", "v", "wrench", nullptr};
  CheckOptions(L, 2, "force_mode", known);
  const double v_max = Option(L, 2, "v", kForceSpeed_mps, "force_mode");
  if (!(v_max > 0)) ScriptError(L, "force_mode: option v (the speed limit along a held axis) must be > 0 m/s");
  // the task frame's axes: the planned tool's, the base's or a user frame's, fixed while the mode lasts
  const Frame here_W = r.planner->ToolPose(r.q_ref);
  Eigen::Quaterniond task_W = here_W.q;
  if (HasOption(L, 2, "frame")) {
    lua_getfield(L, 2, "frame");
    if (lua_type(L, -1) != LUA_TSTRING) {
      ScriptError(L, "force_mode: option frame must be \"tool\", \"base\" or a user frame's name, got %s",
                  luaL_typename(L, -1));
    }
    const char* name = lua_tostring(L, -1);
    if (!std::strcmp(name, "base")) {
      task_W = r.base_W.q;
    } else if (std::strcmp(name, "tool") != 0) {
      task_W = ToWorld(r, *UserFrame(L, name, "force_mode: option frame")).q;
    }
    lua_pop(L, 1);
  }
  Channel* wrench = WrenchOf(L, r, 2, "force_mode");
  if (f.on && wrench != f.wrench) {
    ScriptError(L, "force_mode: force mode is on with the wrench device '%s': end_force_mode() before changing it",
                f.wrench->name().c_str());
  }
  if (!f.on) {
    if (r.zero_wrench == wrench) {
      f.bias_N = r.zero_N;  // force_zero()'s
    } else {
      // zeroed here (as UR's zero_ftsensor): the tool's weight, as the sensor sees it now, taken out
      if (!wrench->Read(&r.reading) || r.reading.size() < 3) {
        ScriptError(L, "force_mode: the wrench device '%s' has sent no reading yet", wrench->name().c_str());
      }
      f.bias_N = Eigen::Vector3d(r.reading[0], r.reading[1], r.reading[2]);
    }
    f.nominal_W = here_W;
  }
  // a second call replaces the targets, keeping the zero and the pose reached
  f.wrench = wrench;
  f.R_WT = task_W.toRotationMatrix();
  for (int i = 0; i < 3; ++i) {
    f.held[i] = held[i];
    f.target_N[i] = target[i];
    f.c_m[i] = f.R_WT.col(i).dot(here_W.p);
  }
  f.v_mps.setZero();
  f.force_T.setZero();
  f.v_max_mps = v_max;
  f.a_max_mps2 = r.limits.accel_mps2;
  f.gain_mps_per_N = kForceGain_mps_per_N;
  f.period_s = ProgramOf(L)->period_s;
  f.fault.clear();
  f.on = true;
  return 0;
}

// force_zero([name]): the wrench's reading now is force mode's zero (UR's zero_ftsensor)
int ForceZero(lua_State* L) {
  Robot& r = NeedRobot(L, "force_zero");
  Channel* w = r.default_wrench;
  if (!lua_isnoneornil(L, 1)) {
    if (lua_type(L, 1) != LUA_TSTRING) {
      ScriptError(L, "force_zero: argument 1 must be a wrench device's name, got %s", luaL_typename(L, 1));
    }
    w = ProgramOf(L)->devices->Find(lua_tostring(L, 1));
    if (!w || w->kind() != bridge::DeviceKind::kWrench) {
      ScriptError(L, "force_zero: no wrench device named '%s'", lua_tostring(L, 1));
    }
  }
  if (!w) ScriptError(L, "force_zero: the program has no default wrench device: name one, force_zero(\"jr3\")");
  if (r.force.on) ScriptError(L, "force_zero: force mode is on: its zero stays until end_force_mode()");
  if (!w->Read(&r.reading) || r.reading.size() < 3) {
    ScriptError(L, "force_zero: the wrench device '%s' has sent no reading yet", w->name().c_str());
  }
  r.zero_wrench = w;
  r.zero_N = Eigen::Vector3d(r.reading[0], r.reading[1], r.reading[2]);
  return 0;
}

int ForceModeEnd(lua_State* L) {
  Robot& r = NeedRobot(L, "end_force_mode");
  r.force.on = false;
  r.force.v_mps.setZero();
  return 0;
}

// _fault(in_condition): raises the force mode's fault (a period's pose out of reach), or,
// called from a stop_if condition that waits, that error
int Fault(lua_State* L) {
  if (lua_toboolean(L, 1)) {
    ScriptError(L, "stop_if: the condition must not wait: it is called once per period while its move runs");
  }
  Robot* r = ProgramOf(L)->robot.get();
  if (!r || r->force.fault.empty()) return 0;
  char message[512];
  std::snprintf(message, sizeof message, "%s", r->force.fault.c_str());
  r->force.fault.clear();
  ScriptError(L, "force mode: %s; force mode has ended, the arm holds its last command", message);
}

// _halt(): a move's stop_if condition came true: it stops where it is
int Halt(lua_State* L) {
  Robot* r = ProgramOf(L)->robot.get();
  if (r && r->moving) {
    r->moving = false;
    r->outcome = "condition";
  }
  return 0;
}

}  // namespace

void CheckGuards(lua_State* L, Robot& r, int options, const char* what) {
  const double force = Option(L, options, "force", 0, what);
  if (HasOption(L, options, "force") && !(force > 0)) ScriptError(L, "%s: option force must be > 0 N", what);
  const double torque = Option(L, options, "torque", 0, what);
  if (HasOption(L, options, "torque") && !(torque > 0)) ScriptError(L, "%s: option torque must be > 0 N m", what);
  if (HasOption(L, options, "dir")) {
    if (!HasOption(L, options, "force")) {
      ScriptError(L, "%s: option dir is the direction of the force guard: give force (N) too", what);
    }
    lua_getfield(L, options, "dir");
    const Eigen::Vector3d* d = ToVec3(L, -1);
    if (!d)
      ScriptError(L, "%s: option dir must be a vec3 (a direction in the base frame), got %s", what,
                  luaL_typename(L, -1));
    if (!d->allFinite() || d->norm() < 1e-9) {
      ScriptError(L, "%s: option dir must be a finite, non-zero direction, got (%g, %g, %g)", what, d->x(), d->y(),
                  d->z());
    }
    lua_pop(L, 1);
  }
  if (HasOption(L, options, "stop_if")) {
    lua_getfield(L, options, "stop_if");
    if (!lua_isfunction(L, -1)) {
      ScriptError(L, "%s: option stop_if must be a function (called once per period), got %s", what,
                  luaL_typename(L, -1));
    }
    lua_pop(L, 1);
  }
  if (force > 0 || torque > 0) WrenchOf(L, r, options, what);
}

void SetGuards(lua_State* L, Robot& r, int options, const char* what) {
  const double force = Option(L, options, "force", 0, what), torque = Option(L, options, "torque", 0, what);
  if (!(force > 0) && !(torque > 0)) return;
  Channel* w = WrenchOf(L, r, options, what);
  r.guard_bias_N.setZero();
  r.guard_torque_bias_Nm.setZero();
  if (w->Read(&r.reading) && r.reading.size() >= 6) {
    r.guard_bias_N = Eigen::Vector3d(r.reading[0], r.reading[1], r.reading[2]);
    r.guard_torque_bias_Nm = Eigen::Vector3d(r.reading[3], r.reading[4], r.reading[5]);
  }
  r.guard_dir_W.setZero();
  if (HasOption(L, options, "dir")) {
    lua_getfield(L, options, "dir");
    r.guard_dir_W = (r.base_W.q * ToVec3(L, -1)->normalized()).normalized();
    lua_pop(L, 1);
  }
  r.guard = w;
  r.guard_force_N = force;
  r.guard_torque_Nm = torque;
}

void OpenForce(lua_State* L) {
  static const luaL_Reg functions[] = {{"_force_mode", ForceModeStart},
                                       {"_end_force_mode", ForceModeEnd},
                                       {"force_zero", ForceZero},
                                       {"_fault", Fault},
                                       {"_halt", Halt},
                                       {nullptr, nullptr}};
  lua_pushglobaltable(L);
  luaL_setfuncs(L, functions, 0);
  lua_pop(L, 1);
}

}  // namespace vlab::task
