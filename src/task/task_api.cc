// The task language's robot functions: moves, poses, user frames, settings,
// and the prelude (the Lua side of task_program.h). Blocking commands are Lua
// functions of the prelude below: they start something here, then yield once
// per period until it is done. Devices, markers and the blackboard:
// task_api_io.cc; fk, ik, reachable: task_api_query.cc; payload():
// task_payload.cc; the argument helpers they share: task_api_args.h.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <lua.hpp>

#include "task/task_api_args.h"
#include "task/task_lua.h"
#include "task/task_program.h"

namespace vlab::task {

namespace {

constexpr const char* kProgramKey = "vlab.program";

// the runtime's own Lua code: blocking commands and waits
constexpr const char* kPrelude = R"lua(
local co_yield, moving, outcome, clock, periods, take = coroutine.yield, _moving, _outcome, _now, _periods, _take_signal
_moving, _outcome, _now, _periods, _take_signal = nil, nil, nil, nil, nil
local raise, sent = _signal, _sent
_signal, _sent = nil, nil
local fault, halt, fm, efm, srch = _fault, _halt, _force_mode, _end_force_mode, _search
_fault, _halt, _force_mode, _end_force_mode, _search = nil, nil, nil, nil, nil
local planned_pose = planned
local in_condition = false  -- a move's stop_if condition runs: it must not wait
-- a move's triggers (option at): each fires once the sample it names has been commanded
local function fire(triggers)
  if not triggers then return end
  local n = sent()
  for _, tr in ipairs(triggers) do
    if not tr.fired and tr.sample < n then
      tr.fired = true
      if tr.signal then raise(tr.signal) else tr.call() end
    end
  end
end
-- the running asynchronous move (option async), whose triggers fire at every wait of the program
local async_move
local function yield()
  if in_condition then fault(true) end
  if async_move then fire(async_move.triggers) end
  co_yield()
  fault()  -- force mode's pose out of reach: an error here, at the script's wait
end
function sync() yield() end
local function await(triggers, condition)
  while moving() do
    fire(triggers)
    if condition then
      in_condition = true
      local hit = condition()
      in_condition = false
      if hit then halt() break end
    end
    yield()
  end
  fire(triggers)
  return outcome()
end
-- an asynchronous move's handle: m:done(), m:wait() (or wait(m)): its outcome
local Move = {}
Move.__index = Move
function Move:done() return self.result ~= nil or not (async_move == self and moving()) end
function Move:wait()
  while not self.result and async_move == self and moving() do yield() end
  if not self.result then
    fire(self.triggers)
    self.result = outcome()
    if async_move == self then async_move = nil end
  end
  return self.result
end
local function finish_async() if async_move then async_move:wait() end end
local function run(triggers, options)
  if options and options.async then
    async_move = setmetatable({triggers = triggers}, Move)
    return async_move
  end
  return await(triggers, options and options.stop_if)
end
function wait(a, timeout)
  if type(a) == "number" then
    for _ = 1, periods(a) do yield() end
    return true
  elseif type(a) == "function" then
    local t_end = timeout and (clock() + periods(timeout) * PERIOD - PERIOD / 2)
    while true do
      local v = a()
      if v then return v end
      if t_end and clock() >= t_end then return nil end
      yield()
    end
  elseif getmetatable(a) == Move then
    if timeout ~= nil then error("wait: a move takes no timeout (m:done() polls it)", 2) end
    return a:wait()
  end
  error("wait: expected seconds, a condition function or a move, got " .. type(a), 2)
end
local function settle() while moving(true) do yield() end end  -- a blended move's end: at rest
local mj, ml, mlr, mc, mp, sm = _movej, _movel, _movel_rel, _movec, _movep, _selfmove
_movej, _movel, _movel_rel, _movec, _movep, _selfmove = nil, nil, nil, nil, nil, nil
function movej(target, options) finish_async() settle() return run(mj(target, options), options) end
function movel(target, options) finish_async() return run(ml(target, options), options) end
function movel_rel(delta, options) finish_async() return run(mlr(delta, options), options) end
function movec(via, target, options) finish_async() settle() return run(mc(via, target, options), options) end
function movep(points, options) finish_async() settle() return run(mp(points, options), options) end
function selfmove(options) finish_async() settle() sm(options) return await() end
function search(target, options)
  finish_async() settle()
  srch(target, options)
  local outcome = await(nil, options and options.stop_if)
  if outcome == "done" then return "done", nil end
  return outcome, planned_pose()
end
function force_mode(target, options) finish_async() settle() fm(target, options) end
function end_force_mode() finish_async() settle() efm() end
local sj = _servoj
_servoj = nil
function servoj(q) finish_async() settle() sj(q) await() end
function signal(name) raise(name) end
function wait_signal(name, timeout)
  return wait(function() return take(name) end, timeout)
end
local m_open, m_due, m_take, m_poll, m_latest = _markers_open, _markers_due, _markers_take, _markers_poll, _markers_latest
_markers_open, _markers_due, _markers_take, _markers_poll, _markers_latest = nil, nil, nil, nil, nil
function markers(name)
  m_open(name)
  -- one period on: the camera renders only while someone listens, so frames queued before
  -- the vision program was there are not rendered; from here on every frame is
  yield()
  local vis = {name = name}
  function vis:next(timeout)
    if timeout ~= nil and (type(timeout) ~= "number" or timeout < 0) then
      error("markers:next: the timeout must be a number of seconds >= 0", 2)
    end
    local t0 = clock()
    local t_end = timeout and (t0 + periods(timeout) * PERIOD - PERIOD / 2)
    local due, frame_time = m_due(name, t0)
    if due then  -- lockstep: to the period that delivers the frame, then hold for its markers
      if t_end and due > t_end then
        while clock() < t_end do yield() end
        return nil
      end
      while clock() < due - PERIOD / 2 do yield() end
      return m_take(name, frame_time)
    end
    while true do  -- realtime: the first state of a frame exposed at or after t0
      local s = m_poll(name, t0)
      if s then return s end
      if t_end and clock() >= t_end then return nil end
      yield()
    end
  end
  function vis:latest() return m_latest(name) end
  return vis
end
function gripper(name)
  local d = device(name)
  local g = {}
  function g:open(width) d:send{mode = 0, value = width} end
  function g:close(force) d:send{mode = 1, value = force} end
  function g:grasped() return d:get("grasped") > 0.5 end
  function g:opening() return d:get("opening") end
  function g:force() return d:get("force") end
  return g
end
)lua";

Program* P(lua_State* L) { return ProgramOf(L); }

// a duration (t) replaces the speed limits: an option that would then be ignored is an error
void CheckDurationAlone(lua_State* L, int options, const char* what, const char* const* speed_keys) {
  if (!HasOption(L, options, "t")) return;
  for (const char* const* k = speed_keys; *k; ++k) {
    if (HasOption(L, options, *k)) {
      ScriptError(L, "%s: options 't' and '%s' together: t sets the move's duration, so '%s' would be ignored", what,
                  *k, *k);
    }
  }
}

// the wrench option names the sensor of a guarded move: without force or torque it would be ignored
void CheckWrenchNeedsForce(lua_State* L, int options, const char* what) {
  if (HasOption(L, options, "wrench") && !HasOption(L, options, "force") && !HasOption(L, options, "torque")) {
    ScriptError(L, "%s: option 'wrench' names the sensor of a guarded move: give 'force' (N) or 'torque' (N m) too",
                what);
  }
}

// whether a move has a guard (force, torque, stop_if): it stops where it is, so it cannot blend
bool Guarded(lua_State* L, int options) {
  return HasOption(L, options, "force") || HasOption(L, options, "torque") || HasOption(L, options, "stop_if");
}

// in force mode a move's path is followed along the free axes with its samples' tool poses:
// joint moves have none (radius < 0 says the move is one), and a blend (radius > 0) would
// leave the move before its end
void CheckForceModeMove(lua_State* L, const Robot& r, const char* what, double radius = 0) {
  if (!r.force.on) return;
  if (radius < 0) {
    ScriptError(L,
                "%s: not in force mode: only movel, movel_rel, movec, movep and search follow a path there "
                "(end_force_mode() first)",
                what);
  }
  if (radius > 0) {
    ScriptError(L, "%s: a move in force mode cannot blend (r = %g m): give r = 0 (or blend(0))", what, radius);
  }
}

// the limits of one move: the settings, overridden by its options (movej: v and jv in deg/s,
// a in deg/s^2, of the fastest joint; movel, movec: v in m/s, a in m/s^2, w in deg/s)
MotionLimits MoveLimits(lua_State* L, const Robot& r, int options, const char* what, bool joint_move = false) {
  MotionLimits l = r.limits;
  struct Given {
    const char* key;
    double value;
  };
  if (joint_move) {
    l.joint_speed_rps = Option(L, options, "jv", l.joint_speed_rps / kDeg, what) * kDeg;
    l.joint_speed_rps = Option(L, options, "v", l.joint_speed_rps / kDeg, what) * kDeg;
    l.joint_accel_rps2 = Option(L, options, "a", l.joint_accel_rps2 / kDeg, what) * kDeg;
    for (const Given& g : {Given{"v", l.joint_speed_rps}, Given{"a", l.joint_accel_rps2}}) {
      if (!(g.value > 0)) ScriptError(L, "%s: option %s must be > 0", what, g.key);
    }
    if (HasOption(L, options, "v") && HasOption(L, options, "jv")) {
      ScriptError(L, "%s: options 'v' and 'jv' together: they are the same (deg/s), give one", what);
    }
    return l;
  }
  l.speed_mps = Option(L, options, "v", l.speed_mps, what);
  l.accel_mps2 = Option(L, options, "a", l.accel_mps2, what);
  l.rot_speed_rps = Option(L, options, "w", l.rot_speed_rps / kDeg, what) * kDeg;
  for (const Given& g : {Given{"v", l.speed_mps}, Given{"a", l.accel_mps2}, Given{"w", l.rot_speed_rps}}) {
    if (!(g.value > 0)) ScriptError(L, "%s: option %s must be > 0", what, g.key);
  }
  return l;
}

// the option t (s): 0 when absent (the speed limits set the duration), else > 0
double Duration(lua_State* L, int options, const char* what) {
  const double t = Option(L, options, "t", 0, what);
  if (HasOption(L, options, "t") && !(t > 0)) ScriptError(L, "%s: option t must be > 0 s, got %g", what, t);
  return t;
}

// the planned tool pose (world) at the planned joints q_ref: the plan's own sample (the
// target, at a Cartesian move's end) where q_ref is that sample, else forward kinematics
Frame PlannedTool(const Robot& r) {
  if (r.next > 0 && r.next <= r.plan.tool_W.size() && r.plan.q[r.next - 1] == r.q_ref) return r.plan.tool_W[r.next - 1];
  return r.planner->ToolPose(r.q_ref);
}

// the planned pose (world) a relative move starts from: where the running move ends (its
// target: it is being blended into the next one), else the planned pose
Frame PlannedEnd(const Robot& r) {
  if (!r.moving) return PlannedTool(r);
  return r.plan.tool_W.empty() ? r.planner->ToolPose(r.plan.q.back()) : r.plan.tool_W.back();
}

void Start(Robot& r, Plan&& plan) {
  r.plan = std::move(plan);
  r.next = 0;
  r.moving = !r.plan.q.empty();
  r.outcome = "done";
  r.guard = nullptr;
  r.blend_at = -1;
  r.sent_cap = -1;
}

// whether the running move was left for a blend: its entry sample has been handed out
bool BlendReady(const Robot& r) { return r.moving && r.blend_at >= 0 && static_cast<long>(r.next) - 1 >= r.blend_at; }

// runs a planner call; its std::invalid_argument becomes a script error
constexpr int kMaxTriggers = 1000;  // triggers of one move

// Option async of a move: true returns a handle at once (the prelude's Move), false or absent blocks
void CheckAsync(lua_State* L, int options, const char* what) {
  if (!HasOption(L, options, "async")) return;
  lua_getfield(L, options, "async");
  if (!lua_isboolean(L, -1))
    ScriptError(L, "%s: option async must be true or false, got %s", what, luaL_typename(L, -1));
  if (lua_toboolean(L, -1) && HasOption(L, options, "stop_if")) {
    ScriptError(L, "%s: option stop_if is called while the move's call waits: not with async = true", what);
  }
  lua_pop(L, 1);
}

// Option at of a move: a list of triggers, each {d = M or t = S, signal = NAME or call = FN}:
// d the path length from the move's start (m; Cartesian moves), t the time from it (s). Checked
// before the move is planned; ResolveTriggers, after, names the sample each fires at.
void CheckTriggers(lua_State* L, int options, const char* what, bool cartesian) {
  if (!HasOption(L, options, "at")) return;
  lua_getfield(L, options, "at");
  const int at = lua_gettop(L);
  if (!lua_istable(L, at) || ToFrame(L, at)) {
    ScriptError(L, "%s: option at must be a list of triggers {d = M or t = S, signal = NAME or call = FN}, got %s",
                what, luaL_typename(L, at));
  }
  const int n = static_cast<int>(lua_rawlen(L, at));
  if (n > kMaxTriggers) ScriptError(L, "%s: %d triggers, at most %d", what, n, kMaxTriggers);
  for (int i = 1; i <= n; ++i) {
    lua_rawgeti(L, at, i);
    const int tr = lua_gettop(L);
    if (!lua_istable(L, tr)) ScriptError(L, "%s: trigger %d must be a table, got %s", what, i, luaL_typename(L, tr));
    static const char* const keys[] = {"d", "t", "signal", "call", nullptr};
    char name[64];
    std::snprintf(name, sizeof name, "%s: trigger %d", what, i);
    CheckOptions(L, tr, name, keys);
    const bool d = HasOption(L, tr, "d"), t = HasOption(L, tr, "t");
    if (d == t) ScriptError(L, "%s: give d (m along the path) or t (s from the start), one of them", name);
    if (d && !cartesian) ScriptError(L, "%s: d is a length along the tool's path: a joint move takes t", name);
    const double value = Option(L, tr, d ? "d" : "t", 0, name);
    if (value < 0) ScriptError(L, "%s: %s must be >= 0, got %g", name, d ? "d" : "t", value);
    lua_getfield(L, tr, "signal");
    const bool is_signal = !lua_isnil(L, -1);
    if (is_signal && lua_type(L, -1) != LUA_TSTRING) {
      ScriptError(L, "%s: signal must be a name (a string), got %s", name, luaL_typename(L, -1));
    }
    lua_getfield(L, tr, "call");
    const bool is_call = !lua_isnil(L, -1);
    if (is_call && !lua_isfunction(L, -1))
      ScriptError(L, "%s: call must be a function, got %s", name, luaL_typename(L, -1));
    if (is_signal == is_call) ScriptError(L, "%s: give signal (a name) or call (a function), one of them", name);
    lua_pop(L, 3);
  }
  lua_pop(L, 1);
}

// the running move's triggers as the prelude fires them: pushes a list of {sample = I,
// signal = NAME or call = FN} (nil without option at); a trigger beyond the move (d past its
// length, t past its duration) cancels the move, which has not begun, and is an error
void ResolveTriggers(lua_State* L, Robot& r, int options, const char* what) {
  if (!HasOption(L, options, "at")) {
    lua_pushnil(L);
    return;
  }
  lua_getfield(L, options, "at");
  const int at = lua_gettop(L);
  const int n = static_cast<int>(lua_rawlen(L, at));
  const std::size_t samples = r.plan.q.size();
  // the path length up to each sample (Cartesian moves), summed as it is needed: no C++
  // object that owns memory is alive here, since a script error below unwinds by longjmp
  const Eigen::Vector3d start = r.planner->ToolPose(r.q_ref).p;
  const auto first_at = [&r, &start](double d, double* length) {  // the first sample at >= d along
    double along = 0;
    Eigen::Vector3d from = start;
    std::size_t i = 0;
    for (; i < r.plan.tool_W.size(); ++i) {
      along += (r.plan.tool_W[i].p - from).norm();
      from = r.plan.tool_W[i].p;
      if (along >= d - 1e-12) break;
    }
    *length = along;
    return std::min(i, r.plan.tool_W.empty() ? std::size_t{0} : r.plan.tool_W.size() - 1);
  };
  double length = 0;
  first_at(1e300, &length);
  const double duration = samples * P(L)->period_s;
  lua_createtable(L, n, 0);
  const int out = lua_gettop(L);
  char error[160] = "";
  for (int i = 1; i <= n && !error[0]; ++i) {
    lua_rawgeti(L, at, i);
    const int tr = lua_gettop(L);
    const bool by_length = HasOption(L, tr, "d");
    const double value = Option(L, tr, by_length ? "d" : "t", 0, what);
    std::size_t sample = 0;
    if (by_length) {
      if (value > length + 1e-9) {
        std::snprintf(error, sizeof error, "trigger %d: d = %g m is beyond the move's path (%.6g m)", i, value, length);
      }
      double reached = 0;
      sample = first_at(value, &reached);
    } else {
      if (value > duration + 1e-9) {
        std::snprintf(error, sizeof error, "trigger %d: t = %g s is beyond the move's duration (%.6g s)", i, value,
                      duration);
      }
      const double k = std::ceil(value / P(L)->period_s - 1e-9);
      sample = static_cast<std::size_t>(std::clamp(k - 1, 0.0, static_cast<double>(samples ? samples - 1 : 0)));
    }
    lua_createtable(L, 0, 2);
    lua_pushinteger(L, static_cast<lua_Integer>(sample));
    lua_setfield(L, -2, "sample");
    for (const char* key : {"signal", "call"}) {
      lua_getfield(L, tr, key);
      lua_setfield(L, -2, key);
    }
    lua_rawseti(L, out, i);
    lua_pop(L, 1);
  }
  if (error[0]) {
    r.moving = false;  // (not one sample of it was sent)
    r.plan = Plan();
    ScriptError(L, "%s: %s", what, error);
  }
  lua_remove(L, at);
}

// a trigger fires once its sample has been handed out: a blended move is left before its end
void CheckTriggersNotBlended(lua_State* L, int options, double radius, const char* what) {
  if (radius > 0 && HasOption(L, options, "at")) {
    ScriptError(L, "%s: a move with triggers (at) cannot blend (r = %g m): give r = 0 (or blend(0))", what, radius);
  }
}

template <class F>
void PlanOrFail(lua_State* L, Robot& r, const char* what, F plan_fn) {
  char error[512] = "";
  try {
    Start(r, plan_fn());
  } catch (const std::exception& e) {
    std::snprintf(error, sizeof error, "%s", e.what());
  }
  if (error[0]) ScriptError(L, "%s: %s", what, error);
}

int MoveJ(lua_State* L) {
  Robot& r = NeedRobot(L, "movej");
  static const char* const known[] = {"v", "a", "jv", "t", "ref", "at", "async", nullptr};
  static const Refused refused[] = {
      {"w", "movej interpolates the joints; its speed is v (deg/s, the fastest joint) or its duration t (s)"},
      {"r", "only movel and movec blend"},
      {"rel", "only movel_rel moves relative to the planned pose"},
      {"force", "only movel, movel_rel, movec and search are guarded moves"},
      {"wrench", "only movel, movel_rel, movec and search are guarded moves"},
      {"dir", "only movel, movel_rel, movec and search are guarded moves"},
      {"torque", "only movel, movel_rel, movec and search are guarded moves"},
      {"stop_if", "only movel, movel_rel, movec and search are guarded moves"},
      {nullptr, nullptr}};
  static const char* const speeds[] = {"v", "a", "jv", nullptr};
  CheckOptions(L, 2, "movej", known, refused);
  CheckDurationAlone(L, 2, "movej", speeds);
  CheckTriggers(L, 2, "movej", false);
  CheckAsync(L, 2, "movej");
  CheckForceModeMove(L, r, "movej", -1);
  const MotionLimits limits = MoveLimits(L, r, 2, "movej", true);
  const double t = Duration(L, 2, "movej");
  if (ToFrame(L, 1)) {
    const Frame goal = ToWorld(r, Target(L, 1, 2, "movej"));
    PlanOrFail(L, r, "movej", [&] { return r.planner->Joint(r.q_ref, r.planner->Ik(r.q_ref, goal), limits, t); });
    ResolveTriggers(L, r, 2, "movej");
    return 1;
  }
  if (!lua_istable(L, 1))
    ScriptError(L, "movej: expected a table of joint angles (deg) or a frame, got %s", luaL_typename(L, 1));
  if (HasOption(L, 2, "ref"))
    ScriptError(L, "movej: option ref is for a target frame: joint angles (deg) have no frame");
  const int n = r.model->dof();
  const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(JointAngles(L, 1, n, "movej"), n);
  PlanOrFail(L, r, "movej", [&] { return r.planner->Joint(r.q_ref, q, limits, t); });
  ResolveTriggers(L, r, 2, "movej");
  return 1;
}

// a move with a blend radius: it may be left at the first sample within the radius of its
// target (not the last: that one is at rest); `segment` is the move's length (movec: its chord)
void SetBlend(lua_State* L, Robot& r, const Eigen::Vector3d& target, double radius, double segment, const char* what) {
  if (radius > segment / 2 + 1e-12) {
    r.moving = false;  // (not one sample of it was sent)
    r.plan = Plan();
    ScriptError(L, "%s: the blend radius r = %g m is larger than half of this move (%g m): at most %g m", what, radius,
                segment, segment / 2);
  }
  for (std::size_t i = 0; i + 1 < r.plan.tool_W.size(); ++i) {
    if ((r.plan.tool_W[i].p - target).norm() <= radius) {
      r.blend_at = static_cast<long>(i);
      break;
    }
  }
  r.blend_radius_m = radius;
  r.blend_corner_W = target;
  r.segment_m = segment;
}

// plans a straight move to `goal` (world) with the options at `options` (checked by the
// caller), from the blend of the move before when there is one (movel, movel_rel)
void PlanLinear(lua_State* L, Robot& r, const Frame& goal, int options, const char* what, bool may_blend = true) {
  CheckGuards(L, r, options, what);
  const MotionLimits limits = MoveLimits(L, r, options, what);
  const double t = Duration(L, options, what);
  const double radius = may_blend ? Option(L, options, "r", r.blend_setting_m, what) : 0.0;
  if (radius < 0) ScriptError(L, "%s: the blend radius r must be >= 0 m, got %g", what, radius);
  if (radius > 0 && Guarded(L, options)) {
    ScriptError(L, "%s: a guarded move (force, torque, stop_if) stops where it is: it cannot blend (r = %g m)", what,
                radius);
  }
  CheckForceModeMove(L, r, what, radius);
  CheckTriggersNotBlended(L, options, radius, what);
  if (BlendReady(r)) {
    // entered from the previous move's blend: its radius must fit in this segment too
    const double seg = (goal.p - r.blend_corner_W).norm();
    if (r.blend_radius_m > seg / 2 + 1e-12) {
      ScriptError(L,
                  "%s: the blend radius r = %g m of the move before is larger than half of this move "
                  "(%g m from the corner): at most %g m",
                  what, r.blend_radius_m, seg, seg / 2);
    }
    if (t > 0) ScriptError(L, "%s: a move entered from a blend takes its speed (v), not a duration (t)", what);
    BlendStart b;
    b.q = r.q_ref;
    b.entry = r.plan.tool_W[r.next - 1];
    b.corner = r.blend_corner_W;
    b.speed_mps = r.plan.speed_mps[r.next - 1];
    if (r.next >= 2) b.q_before = r.plan.q[r.next - 2];  // (the entry at the plan's first sample: from rest)
    // direction of motion at the entry: the central difference of the samples around it
    const std::size_t i = r.next - 1;
    const Eigen::Vector3d after = r.plan.tool_W[std::min(i + 1, r.plan.tool_W.size() - 1)].p;
    const Eigen::Vector3d before = i > 0 ? r.plan.tool_W[i - 1].p : r.planner->ToolPose(r.q_ref).p;
    if ((after - before).norm() > 1e-12) b.tangent = (after - before).normalized();
    PlanOrFail(L, r, what, [&] { return r.planner->FromBlend(b, goal, limits); });
    r.segment_m = seg;
  } else {
    const double seg = (goal.p - r.planner->ToolPose(r.q_ref).p).norm();
    PlanOrFail(L, r, what, [&] { return r.planner->Linear(r.q_ref, goal, limits, t); });
    r.segment_m = seg;
  }
  if (radius > 0) SetBlend(L, r, goal.p, radius, r.segment_m, what);
  SetGuards(L, r, options, what);
}

int MoveL(lua_State* L) {
  Robot& r = NeedRobot(L, "movel");
  static const char* const known[] = {"v",      "a",       "w", "t",   "force", "wrench", "dir",
                                      "torque", "stop_if", "r", "ref", "at",    "async",  nullptr};
  static const Refused refused[] = {
      {"jv", "movel moves the tool: its speeds are v (m/s) and w (deg/s); the joints keep their limits"},
      {"rel", "movel's target is absolute; movel_rel(delta, {rel = ...}) moves relative to the planned pose"},
      {nullptr, nullptr}};
  static const char* const speeds[] = {"v", "a", "w", nullptr};
  CheckOptions(L, 2, "movel", known, refused);
  CheckDurationAlone(L, 2, "movel", speeds);
  CheckWrenchNeedsForce(L, 2, "movel");
  CheckTriggers(L, 2, "movel", true);
  CheckAsync(L, 2, "movel");
  PlanLinear(L, r, ToWorld(r, Target(L, 1, 2, "movel")), 2, "movel");
  ResolveTriggers(L, r, 2, "movel");
  return 1;
}

// movel_rel(delta [, opts]): movel to the planned pose moved by delta, along the tool's
// axes (rel = "tool", default: planned * delta) or the base's (rel = "base": the position
// offset by delta.pos in base axes, the rotation turned by delta.rot about base axes)
int MoveLRel(lua_State* L) {
  Robot& r = NeedRobot(L, "movel_rel");
  static const char* const known[] = {"v",      "a",       "w", "t",   "force", "wrench", "dir",
                                      "torque", "stop_if", "r", "rel", "at",    "async",  nullptr};
  static const Refused refused[] = {
      {"jv", "movel_rel moves the tool: its speeds are v (m/s) and w (deg/s); the joints keep their limits"},
      {"ref", "movel_rel's delta is relative to the planned pose; rel = \"tool\" (default) or \"base\" names its axes"},
      {nullptr, nullptr}};
  static const char* const speeds[] = {"v", "a", "w", nullptr};
  CheckOptions(L, 2, "movel_rel", known, refused);
  CheckDurationAlone(L, 2, "movel_rel", speeds);
  CheckWrenchNeedsForce(L, 2, "movel_rel");
  CheckTriggers(L, 2, "movel_rel", true);
  CheckAsync(L, 2, "movel_rel");
  const Frame& delta = CheckFrame(L, 1, "movel_rel");
  CheckFinite(L, delta, "movel_rel", "offset");
  bool in_base = false;
  if (HasOption(L, 2, "rel")) {
    lua_getfield(L, 2, "rel");
    const char* rel = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : nullptr;
    in_base = rel && !std::strcmp(rel, "base");
    if (!in_base && !(rel && !std::strcmp(rel, "tool"))) {
      ScriptError(L, "movel_rel: option rel must be \"tool\" or \"base\", got %s", luaL_tolstring(L, -1, nullptr));
    }
    lua_pop(L, 1);
  }
  const Frame from = AsValue(ToBase(r, PlannedEnd(r)));
  Frame goal = Compose(from, delta);
  if (in_base) {
    goal.p = from.p + delta.p;
    goal.q = (delta.q * from.q).normalized();
  }
  CheckFinite(L, goal, "movel_rel", "target");
  PlanLinear(L, r, ToWorld(r, goal), 2, "movel_rel");
  ResolveTriggers(L, r, 2, "movel_rel");
  return 1;
}

int MoveC(lua_State* L) {
  Robot& r = NeedRobot(L, "movec");
  static const char* const known[] = {"v",      "a",       "w", "t",   "force", "wrench", "dir",
                                      "torque", "stop_if", "r", "ref", "at",    "async",  nullptr};
  static const Refused refused[] = {
      {"jv", "movec moves the tool: its speeds are v (m/s) and w (deg/s); the joints keep their limits"},
      {"rel", "only movel_rel moves relative to the planned pose"},
      {nullptr, nullptr}};
  static const char* const speeds[] = {"v", "a", "w", nullptr};
  CheckOptions(L, 3, "movec", known, refused);
  CheckDurationAlone(L, 3, "movec", speeds);
  CheckWrenchNeedsForce(L, 3, "movec");
  CheckTriggers(L, 3, "movec", true);
  CheckAsync(L, 3, "movec");
  const double radius = Option(L, 3, "r", r.blend_setting_m, "movec");
  CheckTriggersNotBlended(L, 3, radius, "movec");
  if (radius < 0) ScriptError(L, "movec: the blend radius r must be >= 0 m, got %g", radius);
  if (radius > 0 && Guarded(L, 3)) {
    ScriptError(L, "movec: a guarded move (force, torque, stop_if) stops where it is: it cannot blend (r = %g m)",
                radius);
  }
  CheckForceModeMove(L, r, "movec", radius);
  CheckGuards(L, r, 3, "movec");
  // the via point and the target: in the user frame of option ref when there is one
  const Frame* user = RefFrame(L, 3, "movec");
  Frame point;
  if (const Frame* f = ToFrame(L, 1)) {
    point.p = f->p;
  } else {
    point.p = CheckVec3(L, 1, "movec");
  }
  if (user) point = Compose(*user, point);
  const Eigen::Vector3d via = ToWorld(r, point).p;
  if (!via.allFinite()) ScriptError(L, "movec: the via point (%g, %g, %g) m is not finite", via.x(), via.y(), via.z());
  const Frame goal = ToWorld(r, Target(L, 2, 3, "movec"));
  const MotionLimits limits = MoveLimits(L, r, 3, "movec");
  const double t = Duration(L, 3, "movec");
  const double chord = (goal.p - r.planner->ToolPose(r.q_ref).p).norm();
  PlanOrFail(L, r, "movec", [&] { return r.planner->Arc(r.q_ref, via, goal, limits, t); });
  if (radius > 0) SetBlend(L, r, goal.p, radius, chord, "movec");
  SetGuards(L, r, 3, "movec");
  ResolveTriggers(L, r, 3, "movec");
  return 1;
}

// movep(points [, opts]): through a list of frames at constant tool speed, each corner rounded
// by an arc starting r before it (MotionPlanner::Path)
constexpr double kPathRadius_m = 0.01;  // movep's default corner radius
constexpr int kMaxPathPoints = 10000;

int MoveP(lua_State* L) {
  Robot& r = NeedRobot(L, "movep");
  static const char* const known[] = {"v", "a", "w", "r", "ref", "at", "async", "spline", nullptr};
  static const Refused refused[] = {
      {"t", "movep holds the tool speed v (m/s): its duration follows from the path's length"},
      {"jv", "movep moves the tool: its speeds are v (m/s) and w (deg/s); the joints keep their limits"},
      {"force", "only movel, movel_rel, movec and search are guarded moves"},
      {"wrench", "only movel, movel_rel, movec and search are guarded moves"},
      {"dir", "only movel, movel_rel, movec and search are guarded moves"},
      {"torque", "only movel, movel_rel, movec and search are guarded moves"},
      {"stop_if", "only movel, movel_rel, movec and search are guarded moves"},
      {"rel", "only movel_rel moves relative to the planned pose"},
      {nullptr, nullptr}};
  CheckOptions(L, 2, "movep", known, refused);
  CheckTriggers(L, 2, "movep", true);
  CheckAsync(L, 2, "movep");
  if (!lua_istable(L, 1) || ToFrame(L, 1)) {
    ScriptError(L, "movep: expected a list of frames, got %s", ToFrame(L, 1) ? "one frame" : luaL_typename(L, 1));
  }
  const int count = static_cast<int>(lua_rawlen(L, 1));
  if (count < 1) ScriptError(L, "movep: the list of points is empty");
  if (count > kMaxPathPoints) ScriptError(L, "movep: %d points, at most %d", count, kMaxPathPoints);
  bool spline = false;
  if (HasOption(L, 2, "spline")) {
    lua_getfield(L, 2, "spline");
    if (!lua_isboolean(L, -1))
      ScriptError(L, "movep: option spline must be true or false, got %s", luaL_typename(L, -1));
    spline = lua_toboolean(L, -1);
    lua_pop(L, 1);
  }
  if (spline && HasOption(L, 2, "r"))
    ScriptError(L, "movep: a spline passes through every point: it has no corner radius r");
  const double radius = Option(L, 2, "r", kPathRadius_m, "movep");
  if (!(radius > 0)) ScriptError(L, "movep: the corner radius r must be > 0 m, got %g", radius);
  const MotionLimits limits = MoveLimits(L, r, 2, "movep");
  // the points (world), in a Lua-owned buffer: a script error below leaves no C++ object behind
  auto* points = static_cast<Frame*>(lua_newuserdatauv(L, sizeof(Frame) * static_cast<std::size_t>(count), 0));
  const int buffer = lua_gettop(L);
  for (int i = 0; i < count; ++i) {
    lua_rawgeti(L, 1, i + 1);
    char what[48];
    std::snprintf(what, sizeof what, "movep: point %d", i + 1);
    if (!ToFrame(L, -1)) ScriptError(L, "%s: expected a frame, got %s", what, luaL_typename(L, -1));
    new (&points[i]) Frame(ToWorld(r, Target(L, lua_gettop(L), 2, what)));
    lua_pop(L, 1);
  }
  PlanOrFail(L, r, "movep", [&] {
    return r.planner->Path(r.q_ref, std::vector<Frame>(points, points + count), radius, limits, spline);
  });
  lua_remove(L, buffer);
  ResolveTriggers(L, r, 2, "movep");
  return 1;
}

int SelfMove(lua_State* L) {
  Robot& r = NeedRobot(L, "selfmove");
  static const char* const known[] = {"joint", "by", "t", nullptr};
  static const Refused refused[] = {{"v", "selfmove's duration is t (s)"},
                                    {"a", "selfmove's profile is quintic over t (s)"},
                                    {"w", "selfmove's duration is t (s)"},
                                    {"jv", "selfmove's duration is t (s)"},
                                    {"r", "only movel and movec blend"},
                                    {"force", "only movel, movel_rel, movec and search are guarded moves"},
                                    {"wrench", "only movel, movel_rel, movec and search are guarded moves"},
                                    {"dir", "only movel, movel_rel, movec and search are guarded moves"},
                                    {"torque", "only movel, movel_rel, movec and search are guarded moves"},
                                    {"stop_if", "only movel, movel_rel, movec and search are guarded moves"},
                                    {"ref", "selfmove holds the tool where it is: it has no target"},
                                    {"rel", "selfmove holds the tool where it is: it has no target"},
                                    {nullptr, nullptr}};
  if (!lua_istable(L, 1)) ScriptError(L, "selfmove: expected {joint = N, by = DEG, t = S}");
  CheckOptions(L, 1, "selfmove", known, refused);
  CheckForceModeMove(L, r, "selfmove", -1);
  const int joint = static_cast<int>(Option(L, 1, "joint", 3, "selfmove")) - 1;
  const double by = Option(L, 1, "by", 0, "selfmove") * kDeg;
  const double t = Option(L, 1, "t", 0, "selfmove");
  if (!(t > 0)) ScriptError(L, "selfmove: t (s) must be given and > 0");
  PlanOrFail(L, r, "selfmove", [&] { return r.planner->Self(r.q_ref, joint, by, t); });
  return 0;
}

// search(direction or frame [, opts]): a guarded straight move meant to stop on its guard
// (RAPID's SearchL): along a direction (a vec3, base frame) at most `max` m, its force guard
// on the force along that direction; or to a frame. The prelude returns the outcome and,
// unless it reached its end ("done"), the planned pose where it stopped.
int Search(lua_State* L) {
  Robot& r = NeedRobot(L, "search");
  static const char* const known[] = {"v",       "a",      "w",   "force", "dir",  "torque",
                                      "stop_if", "wrench", "max", "ref",   nullptr};
  static const Refused refused[] = {
      {"t", "search moves at its speed v (m/s) until a guard stops it"},
      {"r", "search stops where its guard fires: it cannot blend"},
      {"jv", "search moves the tool: its speeds are v (m/s) and w (deg/s)"},
      {"at", "search has no triggers: it returns where it stopped"},
      {"async", "search waits for its guard: it returns the outcome and where it stopped"},
      {"rel", "search's direction is in the base frame (or give a target frame)"},
      {nullptr, nullptr}};
  CheckOptions(L, 2, "search", known, refused);
  CheckWrenchNeedsForce(L, 2, "search");
  if (!Guarded(L, 2)) {
    ScriptError(L, "search: needs a guard to stop it: force (N), torque (N m) or stop_if (a function)");
  }
  const Eigen::Vector3d* along = ToVec3(L, 1);
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  Frame goal;
  if (along) {
    d = *along;
    if (!d.allFinite() || d.norm() < 1e-9) {
      ScriptError(L, "search: the direction must be finite and non-zero, got (%g, %g, %g)", d.x(), d.y(), d.z());
    }
    if (!HasOption(L, 2, "max")) ScriptError(L, "search: a search along a direction needs max (m, how far it may go)");
    const double max = Option(L, 2, "max", 0, "search");
    if (!(max > 0)) ScriptError(L, "search: option max must be > 0 m, got %g", max);
    if (HasOption(L, 2, "ref")) {
      ScriptError(L, "search: option ref is for a target frame: a direction is in the base frame");
    }
    if (HasOption(L, 2, "dir")) {
      ScriptError(L, "search: along a direction the force guard is along it: option dir is for a search to a frame");
    }
    d.normalize();
    goal = AsValue(ToBase(r, PlannedEnd(r)));
    goal.p += max * d;
    goal = ToWorld(r, goal);
  } else if (ToFrame(L, 1)) {
    if (HasOption(L, 2, "max"))
      ScriptError(L, "search: option max is for a search along a direction: a frame is its end");
    goal = ToWorld(r, Target(L, 1, 2, "search"));
  } else {
    ScriptError(L, "search: argument 1 must be a direction (a vec3, base frame) or a target frame, got %s",
                luaL_typename(L, 1));
  }
  PlanLinear(L, r, goal, 2, "search", false);
  if (along && r.guard_force_N > 0) r.guard_dir_W = (r.base_W.q * d).normalized();
  return 0;
}

int Moving(lua_State* L) {  // moving(): until done or left for a blend; moving(true): until at rest
  const Robot* r = P(L)->robot.get();
  const bool raw = lua_toboolean(L, 1);
  lua_pushboolean(L, r && r->moving && (raw || !BlendReady(*r)));
  return 1;
}
int Sent(lua_State* L) {  // samples of the running (or last) move handed out
  const Robot* r = P(L)->robot.get();
  // (after stop(): the samples of the move that were handed out; its triggers beyond do not fire)
  lua_pushinteger(L, !r ? 0 : r->sent_cap >= 0 ? r->sent_cap : static_cast<lua_Integer>(r->next));
  return 1;
}
int Outcome(lua_State* L) {
  lua_pushstring(L, P(L)->robot ? P(L)->robot->outcome.c_str() : "done");
  return 1;
}

int Joints(lua_State* L) {
  Robot& r = NeedRobot(L, "joints");
  lua_createtable(L, static_cast<int>(r.q_meas.size()), 0);
  for (int i = 0; i < r.q_meas.size(); ++i) {
    lua_pushnumber(L, r.q_meas[i] / kDeg);
    lua_rawseti(L, -2, i + 1);
  }
  return 1;
}

int Pose(lua_State* L) {  // measured tool pose in the base frame
  Robot& r = NeedRobot(L, "pose");
  PushFrame(L, ToBase(r, r.planner->ToolPose(r.q_meas)));
  return 1;
}

int Planned(lua_State* L) {  // planned (commanded) tool pose in the base frame
  Robot& r = NeedRobot(L, "planned");
  PushFrame(L, ToBase(r, PlannedTool(r)));
  return 1;
}

int PlannedJoints(lua_State* L) {  // planned (commanded) joint angles, deg, chain order
  Robot& r = NeedRobot(L, "planned_joints");
  lua_createtable(L, static_cast<int>(r.q_ref.size()), 0);
  for (int i = 0; i < r.q_ref.size(); ++i) {
    lua_pushnumber(L, r.q_ref[i] / kDeg);
    lua_rawseti(L, -2, i + 1);
  }
  return 1;
}

// ---- user frames (work objects): frame_def(name, frame), frame_of(name)
int FrameDef(lua_State* L) {
  if (lua_type(L, 1) != LUA_TSTRING || lua_rawlen(L, 1) == 0) {
    ScriptError(L, "frame_def: argument 1 must be the frame's name (a non-empty string), got %s", luaL_typename(L, 1));
  }
  CheckFinite(L, CheckFrame(L, 2, "frame_def"), "frame_def", "frame's");
  // the value itself (frames are immutable): moves with ref use the very numbers given
  lua_getfield(L, LUA_REGISTRYINDEX, kFramesKey);
  lua_pushvalue(L, 1);
  lua_pushvalue(L, 2);
  lua_rawset(L, -3);
  lua_pop(L, 1);
  return 0;
}

int FrameOf(lua_State* L) {
  if (lua_type(L, 1) != LUA_TSTRING) {
    ScriptError(L, "frame_of: argument 1 must be a user frame's name, got %s", luaL_typename(L, 1));
  }
  UserFrame(L, lua_tostring(L, 1), "frame_of");
  lua_getfield(L, LUA_REGISTRYINDEX, kFramesKey);
  lua_getfield(L, -1, lua_tostring(L, 1));
  return 1;
}

template <bool kForce>
int WrenchPart(lua_State* L) {
  Program* p = P(L);
  Channel* w = p->robot ? p->robot->default_wrench : nullptr;
  if (lua_isstring(L, 1)) w = p->devices->Find(lua_tostring(L, 1));
  if (!w || w->kind() != bridge::DeviceKind::kWrench) {
    ScriptError(L, "%s: no wrench device%s%s", kForce ? "force" : "torque", lua_isstring(L, 1) ? " named " : "",
                lua_isstring(L, 1) ? lua_tostring(L, 1) : "");
  }
  std::vector<double> v;
  const bool ok = w->Read(&v) && v.size() >= 6;
  const Eigen::Vector3d out =
      ok ? Eigen::Vector3d(v[kForce ? 0 : 3], v[kForce ? 1 : 4], v[kForce ? 2 : 5]) : Eigen::Vector3d::Zero();
  v = std::vector<double>();
  PushVec3(L, out);
  return 1;
}

// a setting's getter form (no argument): pushes the values in force, in the setter's units
int Get(lua_State* L, std::initializer_list<double> values) {
  for (const double v : values) lua_pushnumber(L, v);
  return static_cast<int>(values.size());
}

int SetSpeed(lua_State* L) {
  Robot& r = NeedRobot(L, "speed");
  if (lua_gettop(L) == 0) return Get(L, {r.limits.speed_mps, r.limits.rot_speed_rps / kDeg});
  const double v = NumberArg(L, 1, "speed");
  if (!(v > 0)) ScriptError(L, "speed: must be > 0 m/s");
  r.limits.speed_mps = v;
  if (!lua_isnoneornil(L, 2)) r.limits.rot_speed_rps = NumberArg(L, 2, "speed") * kDeg;
  return 0;
}
int SetAccel(lua_State* L) {
  Robot& r = NeedRobot(L, "accel");
  if (lua_gettop(L) == 0) return Get(L, {r.limits.accel_mps2, r.limits.rot_accel_rps2 / kDeg});
  const double a = NumberArg(L, 1, "accel");
  if (!(a > 0)) ScriptError(L, "accel: must be > 0 m/s^2");
  r.limits.accel_mps2 = a;
  if (!lua_isnoneornil(L, 2)) r.limits.rot_accel_rps2 = NumberArg(L, 2, "accel") * kDeg;
  return 0;
}
int SetJointSpeed(lua_State* L) {
  Robot& r = NeedRobot(L, "jspeed");
  if (lua_gettop(L) == 0) return Get(L, {r.limits.joint_speed_rps / kDeg, r.limits.joint_accel_rps2 / kDeg});
  const double v = NumberArg(L, 1, "jspeed");
  if (!(v > 0)) ScriptError(L, "jspeed: must be > 0 deg/s");
  r.limits.joint_speed_rps = v * kDeg;
  if (!lua_isnoneornil(L, 2)) r.limits.joint_accel_rps2 = NumberArg(L, 2, "jspeed") * kDeg;
  return 0;
}
int SetRateLimits(lua_State* L) {  // limits("slow" | "refuse"): what a move beyond the joints' limits does
  Robot& r = NeedRobot(L, "limits");
  if (lua_gettop(L) == 0) {
    lua_pushstring(L, r.planner->rate_limits().refuse ? "refuse" : "slow");
    return 1;
  }
  const char* mode = lua_tostring(L, 1);
  const bool slow = mode && !std::strcmp(mode, "slow"), refuse = mode && !std::strcmp(mode, "refuse");
  if (!slow && !refuse)
    ScriptError(L, "limits: expected \"slow\" or \"refuse\", got %s", luaL_tolstring(L, 1, nullptr));
  JointRateLimits l = r.planner->rate_limits();
  l.refuse = refuse;
  r.planner->set_rate_limits(l);
  return 0;
}
int SetTool(lua_State* L) {
  Robot& r = NeedRobot(L, "tool");
  if (lua_gettop(L) == 0) {
    PushFrame(L, r.planner->tool());
    return 1;
  }
  r.planner->set_tool(CheckFrame(L, 1, "tool"));
  // a finished plan's tool poses are of the tool before: the planned pose is forward kinematics from here
  if (!r.moving) r.plan.tool_W.clear();
  return 0;
}
int SetBlend(lua_State* L) {
  Robot& r = NeedRobot(L, "blend");
  if (lua_gettop(L) == 0) return Get(L, {r.blend_setting_m});
  const double v = NumberArg(L, 1, "blend");
  if (v < 0) ScriptError(L, "blend: the radius must be >= 0 m (0: every move stops at its target)");
  r.blend_setting_m = v;
  return 0;
}
int SetBase(lua_State* L) {
  Robot& r = NeedRobot(L, "base");
  if (lua_gettop(L) == 0) {
    PushFrame(L, r.base_W);
    return 1;
  }
  r.base_W = CheckFrame(L, 1, "base");
  return 0;
}

int Now(lua_State* L) {
  lua_pushnumber(L, P(L)->t_s);
  return 1;
}
int Periods(lua_State* L) {  // whole periods in a duration (s)
  const double s = NumberArg(L, 1, "wait");
  if (s < 0) ScriptError(L, "wait: the time must be >= 0 s, got %g", s);
  lua_pushinteger(L, static_cast<lua_Integer>(std::llround(s / P(L)->period_s)));
  return 1;
}

}  // namespace

Program* ProgramOf(lua_State* L) {
  lua_getfield(L, LUA_REGISTRYINDEX, kProgramKey);
  auto* p = static_cast<Program*>(lua_touserdata(L, -1));
  lua_pop(L, 1);
  return p;
}

void StartPlan(Robot* r, Plan plan) { Start(*r, std::move(plan)); }

void AdvanceMotion(Robot* r) {
  r->q_ref_before = r->q_ref;  // (sized once: no allocation after the first period)
  if (r->moving) {
    if (const char* tripped = GuardTripped(r)) {
      r->moving = false;
      r->outcome = tripped;
    }
  }
  if (r->force.on) {
    AdvanceForceMode(r);
    return;
  }
  if (!r->moving) return;
  r->q_ref = r->plan.q[r->next++];
  if (r->next >= r->plan.q.size()) r->moving = false;
}

void StopMotion(Robot* r, double period_s) {
  if (!r->moving || r->next >= r->plan.q.size()) return;
  // the path left: the current reference, then the samples not yet handed out
  std::vector<Eigen::VectorXd> path;
  path.push_back(r->q_ref);
  for (std::size_t i = r->next; i < r->plan.q.size(); ++i) path.push_back(r->plan.q[i]);
  const JointRateLimits& limits = r->planner->rate_limits();
  const int dof = static_cast<int>(r->q_ref.size());
  const double T2 = period_s * period_s;
  // the rate's fall per period, delta: over the samples the stop can cover (about 1/(2 delta)
  // of them), joint j's step |dq_j| (rad per sample) must leave delta |dq_j| / T^2 within its
  // limit less the path's own acceleration there; refined over the window it gives
  double delta = 1.0;
  for (int pass = 0; pass < 4; ++pass) {
    const std::size_t window = std::min(path.size() - 1, static_cast<std::size_t>(std::ceil(0.5 / delta)) + 2);
    double need = 1e-12;
    for (std::size_t i = 1; i <= window; ++i) {
      for (int j = 0; j < dof; ++j) {
        const double step = std::abs(path[i][j] - path[i - 1][j]);
        const double own = i + 1 < path.size() ? std::abs(path[i + 1][j] - 2 * path[i][j] + path[i - 1][j]) / T2 : 0.0;
        const double room = std::max(0.98 * limits.a_rps2[j] - own, 0.05 * limits.a_rps2[j]);  // 2 %: interpolation
        need = std::max(need, step / (room * T2));
      }
    }
    delta = std::min(1.0, 1.0 / need);
  }
  // in force mode the commands come from the plan's tool poses (the admittance moves them
  // along the held axes): the stop follows those, from the pose of the last period
  const bool force = r->force.on && r->plan.tool_W.size() == r->plan.q.size();
  const auto pose_at = [r](std::size_t i) -> const Frame& {
    return i == 0 ? r->force.nominal_W : r->plan.tool_W[r->next + i - 1];
  };
  Plan stop;
  double x = 0, rate = 1;
  const double end = static_cast<double>(path.size() - 1);
  while (rate > 0 && x < end) {
    rate -= delta;
    x = std::min(end, x + std::max(rate, 0.0));
    const std::size_t i = std::min(static_cast<std::size_t>(x), path.size() - 2);
    const double f = x - static_cast<double>(i);
    stop.q.push_back(path[i] + f * (path[i + 1] - path[i]));
    if (force) {
      Frame pose;
      pose.p = pose_at(i).p + f * (pose_at(i + 1).p - pose_at(i).p);
      pose.q = pose_at(i).q.slerp(f, pose_at(i + 1).q);
      stop.tool_W.push_back(pose);
    } else {
      stop.tool_W.push_back(r->planner->ToolPose(stop.q.back()));
    }
    stop.speed_mps.push_back(0);
  }
  if (stop.q.empty()) {
    stop.q.push_back(r->q_ref);
    stop.tool_W.push_back(force ? r->force.nominal_W : r->planner->ToolPose(r->q_ref));
  }
  stop.duration_s = stop.q.size() * period_s;
  r->sent_cap = r->sent_cap >= 0 ? r->sent_cap : static_cast<long>(r->next);
  r->plan = std::move(stop);
  r->next = 0;
  r->moving = true;
  r->outcome = "stopped";
  r->guard = nullptr;
  r->blend_at = -1;
}

namespace {

// stop([name]): halts the running move of robot `name` (default: this program's) on its path
int Stop(lua_State* L) {
  Program* p = P(L);
  const char* name = nullptr;
  if (lua_isnoneornil(L, 1)) {
    if (!p->robot) ScriptError(L, "stop: this program has no robot: name the robot to stop, stop(\"pa10\")");
    name = p->config.robot.c_str();
  } else {
    if (lua_type(L, 1) != LUA_TSTRING) ScriptError(L, "stop: expected a robot's name, got %s", luaL_typename(L, 1));
    name = lua_tostring(L, 1);
    if (!p->board->robots.count(name)) {
      char list[256] = "";
      for (const std::string& robot : p->board->robots) {
        const std::size_t used = std::strlen(list);
        std::snprintf(list + used, sizeof list - used, "%s'%s'", used ? ", " : "", robot.c_str());
      }
      ScriptError(L, "stop: no robot named '%s' (%s%s)", name, list[0] ? "robots: " : "no program has a robot", list);
    }
  }
  p->board->stops.insert(name);
  return 0;
}

}  // namespace

void OpenApi(Program* p) {
  lua_State* L = p->L;
  lua_pushlightuserdata(L, p);
  lua_setfield(L, LUA_REGISTRYINDEX, kProgramKey);
  static const luaL_Reg functions[] = {{"_movej", MoveJ},
                                       {"_movel", MoveL},
                                       {"_movel_rel", MoveLRel},
                                       {"_movec", MoveC},
                                       {"_movep", MoveP},
                                       {"_selfmove", SelfMove},
                                       {"_search", Search},
                                       {"_moving", Moving},
                                       {"_outcome", Outcome},
                                       {"_sent", Sent},
                                       {"stop", Stop},
                                       {"_now", Now},
                                       {"_periods", Periods},
                                       {"now", Now},
                                       {"joints", Joints},
                                       {"pose", Pose},
                                       {"planned", Planned},
                                       {"planned_joints", PlannedJoints},
                                       {"frame_def", FrameDef},
                                       {"frame_of", FrameOf},
                                       {"force", WrenchPart<true>},
                                       {"torque", WrenchPart<false>},
                                       {"speed", SetSpeed},
                                       {"accel", SetAccel},
                                       {"jspeed", SetJointSpeed},
                                       {"limits", SetRateLimits},
                                       {"tool", SetTool},
                                       {"base", SetBase},
                                       {"blend", SetBlend},
                                       {nullptr, nullptr}};
  lua_pushglobaltable(L);
  luaL_setfuncs(L, functions, 0);
  lua_pop(L, 1);
  lua_pushnumber(L, p->period_s);
  lua_setglobal(L, "PERIOD");
  lua_pushstring(L, p->config.robot.c_str());
  lua_setglobal(L, "ROBOT");
  lua_newtable(L);
  lua_setfield(L, LUA_REGISTRYINDEX, kFramesKey);
  // PARAMS: the program's parameters, numbers and booleans where the text reads as one
  lua_newtable(L);
  for (const auto& [name, text] : p->config.params) {
    const bool plain = !text.empty() && !std::isspace(static_cast<unsigned char>(text[0]));
    char* end = nullptr;
    errno = 0;
    const long long integer = plain ? std::strtoll(text.c_str(), &end, 10) : 0;
    const bool is_integer = plain && end && *end == '\0' && errno == 0;
    end = nullptr;
    const double number = plain ? std::strtod(text.c_str(), &end) : 0.0;
    const bool is_number = plain && end && *end == '\0' && std::isfinite(number);
    if (text == "true" || text == "false") {
      lua_pushboolean(L, text == "true");
    } else if (is_integer) {
      lua_pushinteger(L, static_cast<lua_Integer>(integer));
    } else if (is_number) {
      lua_pushnumber(L, number);
    } else {
      lua_pushlstring(L, text.data(), text.size());
    }
    lua_setfield(L, -2, name.c_str());
  }
  lua_setglobal(L, "PARAMS");
  OpenIo(L);
  OpenQueries(L);
  OpenPayload(L);
  OpenForce(L);
  OpenServo(L);
  if (luaL_loadbufferx(L, kPrelude, std::strlen(kPrelude), "=vlab", "t") != LUA_OK) {
    throw std::logic_error(std::string("task prelude: ") + lua_tostring(L, -1));
  }
  lua_call(L, 0, 0);
}

}  // namespace vlab::task
