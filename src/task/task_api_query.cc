// The task language's kinematics queries, which never move the robot (no
// period passes, the commanded joints stay): fk(q), ik(frame [, opts]),
// reachable(frame [, opts]) on task_kinematics.h. Angles in degrees, frames
// in the script's base frame with its tool, as pose() gives them, or in a
// user frame (option ref: frame_def's name). The Lua
// errors are raised by the callers, once the workers' C++ objects are gone.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <lua.hpp>

#include "task/task_api_args.h"
#include "task/task_kinematics.h"
#include "task/task_lua.h"
#include "task/task_program.h"

namespace vlab::task {

namespace {

constexpr int kErrorSize = 512;

// the joint angles (deg, one per chain joint) of the table at `index`, in rad; false with
// `error` set ("expected 7 joint angles (deg), got 6", "joint E1 is nan, ...")
bool JointTable(lua_State* L, int index, const Robot& r, const char* which, Eigen::VectorXd* q, char* error) {
  const int n = r.model->dof();
  if (!lua_istable(L, index)) {
    std::snprintf(error, kErrorSize, "%sexpected a table of %d joint angles (deg), got %s", which, n,
                  luaL_typename(L, index));
    return false;
  }
  const int got = static_cast<int>(lua_rawlen(L, index));
  if (got != n) {
    std::snprintf(error, kErrorSize, "%sexpected %d joint angles (deg), got %d", which, n, got);
    return false;
  }
  q->resize(n);
  for (int i = 0; i < n; ++i) {
    lua_rawgeti(L, index, i + 1);
    const bool number = lua_isnumber(L, -1);
    const double deg = number ? lua_tonumber(L, -1) : 0.0;
    const char* type = luaL_typename(L, -1);
    lua_pop(L, 1);
    const char* name = r.model->joint_names()[i].c_str();
    if (!number) {
      std::snprintf(error, kErrorSize, "%sjoint %s must be a number (deg), got %s", which, name, type);
      return false;
    }
    if (!std::isfinite(deg)) {
      std::snprintf(error, kErrorSize, "%sjoint %s is %g, not a finite angle (deg)", which, name, deg);
      return false;
    }
    (*q)[i] = deg * kDeg;
  }
  return true;
}

void PushDegrees(lua_State* L, const Eigen::VectorXd& q) {
  lua_createtable(L, static_cast<int>(q.size()), 0);
  for (int i = 0; i < q.size(); ++i) {
    lua_pushnumber(L, q[i] / kDeg);
    lua_rawseti(L, -2, i + 1);
  }
}

// `user`: the user frame of option ref (the result is given in it), or null
void FkWork(lua_State* L, const Robot& r, const Frame* user, char* error) {
  Eigen::VectorXd q;
  if (!JointTable(L, 1, r, "", &q, error)) return;
  try {
    const Kinematics k(r.model.get(), r.planner.get());
    const Frame base = ToBase(r, k.Fk(q));
    PushFrame(L, user ? Relative(*user, base) : base);
  } catch (const std::exception& e) {
    std::snprintf(error, kErrorSize, "%s", e.what());
  }
}

int Fk(lua_State* L) {  // fk(q [, {ref = name}]): the tool frame (base or user frame) at joints q (deg)
  const Robot& r = NeedRobot(L, "fk");
  static const char* const known[] = {"ref", nullptr};
  CheckOptions(L, 2, "fk", known);
  const Frame* user = RefFrame(L, 2, "fk");
  char error[kErrorSize] = "";
  FkWork(L, r, user, error);
  if (error[0]) ScriptError(L, "fk: %s", error);
  return 1;
}

// ik's and reachable's options: {seed = {...}, ref = name} (ik: and all = true|false); they
// move nothing. Returns the target in the base frame (given in the user frame of ref).
Frame CheckQueryOptions(lua_State* L, const char* what, bool takes_all) {
  static const char* const with_all[] = {"seed", "all", "ref", nullptr};
  static const char* const seed_only[] = {"seed", "ref", nullptr};
  static const Refused refused[] = {
      {"all", "reachable tries every branch already (ik(frame, {all = true}) lists them)"},
      {"v", "it moves nothing"},
      {"a", "it moves nothing"},
      {"w", "it moves nothing"},
      {"jv", "it moves nothing"},
      {"t", "it moves nothing"},
      {"r", "it moves nothing"},
      {"force", "it moves nothing"},
      {"wrench", "it moves nothing"},
      {nullptr, nullptr}};
  CheckOptions(L, 2, what, takes_all ? with_all : seed_only, takes_all ? refused + 1 : refused);
  if (HasOption(L, 2, "all")) {
    lua_getfield(L, 2, "all");
    const bool boolean = lua_isboolean(L, -1);
    const char* type = luaL_typename(L, -1);
    lua_pop(L, 1);
    if (!boolean) ScriptError(L, "%s: option all must be true or false, got %s", what, type);
  }
  return Target(L, 1, 2, what);
}

// the seed of ik/reachable: option seed (deg), else the planned joints
bool Seed(lua_State* L, const Robot& r, Eigen::VectorXd* seed, char* error) {
  if (!HasOption(L, 2, "seed")) {
    *seed = r.q_ref;
    return true;
  }
  lua_getfield(L, 2, "seed");
  const bool ok = JointTable(L, lua_gettop(L), r, "option seed: ", seed, error);
  lua_pop(L, 1);
  return ok;
}

// ik (query 0: nearest, 1: all) or reachable (2) of `target` (base frame): pushes the result
void IkWork(lua_State* L, const Robot& r, const Frame& target, int query, char* error) {
  Eigen::VectorXd seed;
  if (!Seed(L, r, &seed, error)) return;
  try {
    const Kinematics k(r.model.get(), r.planner.get());
    const Frame goal = ToWorld(r, target);
    if (query == 2) {
      lua_pushboolean(L, k.Reachable(goal, seed));
    } else if (query == 1) {
      const std::vector<Eigen::VectorXd> all = k.All(goal, seed);
      lua_createtable(L, static_cast<int>(all.size()), 0);
      for (std::size_t i = 0; i < all.size(); ++i) {
        PushDegrees(L, all[i]);
        lua_rawseti(L, -2, static_cast<lua_Integer>(i + 1));
      }
    } else {
      PushDegrees(L, k.Nearest(goal, seed));
    }
  } catch (const std::exception& e) {
    std::snprintf(error, kErrorSize, "%s", e.what());
  }
}

int Ik(lua_State* L) {  // ik(frame [, {seed = q, all = true, ref = name}]): joints (deg), or a list of them
  const Robot& r = NeedRobot(L, "ik");
  const Frame target = CheckQueryOptions(L, "ik", true);
  bool all = false;
  if (!lua_isnoneornil(L, 2)) {
    lua_getfield(L, 2, "all");
    all = lua_toboolean(L, -1);
    lua_pop(L, 1);
  }
  char error[kErrorSize] = "";
  IkWork(L, r, target, all ? 1 : 0, error);
  if (error[0]) ScriptError(L, "ik: %s", error);
  return 1;
}

int Reachable(lua_State* L) {  // reachable(frame [, {seed = q, ref = name}]): whether ik finds joints
  const Robot& r = NeedRobot(L, "reachable");
  const Frame target = CheckQueryOptions(L, "reachable", false);
  char error[kErrorSize] = "";
  IkWork(L, r, target, 2, error);
  if (error[0]) ScriptError(L, "reachable: %s", error);
  return 1;
}

}  // namespace

void OpenQueries(lua_State* L) {
  static const luaL_Reg functions[] = {{"fk", Fk}, {"ik", Ik}, {"reachable", Reachable}, {nullptr, nullptr}};
  lua_pushglobaltable(L);
  luaL_setfuncs(L, functions, 0);
  lua_pop(L, 1);
}

}  // namespace vlab::task
