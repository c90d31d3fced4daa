#include "task/task_api_args.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <lua.hpp>

#include "task/task_lua.h"

namespace vlab::task {

namespace {

// the names of the user frames, sorted, as "a, b" (or a hint when there are none) into `out`
void DefinedFrames(lua_State* L, char* out, std::size_t size) {
  std::vector<std::string> names;
  lua_getfield(L, LUA_REGISTRYINDEX, kFramesKey);
  lua_pushnil(L);
  while (lua_next(L, -2)) {
    lua_pop(L, 1);
    names.emplace_back(lua_tostring(L, -1));  // (every key is a string: frame_def)
  }
  lua_pop(L, 1);
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "'" : ", '") + n + "'";
  std::snprintf(out, size, "%s",
                names.empty() ? "none is defined: frame_def(name, frame)" : ("defined: " + list).c_str());
}

}  // namespace

Robot& NeedRobot(lua_State* L, const char* what) {
  Program* p = ProgramOf(L);
  if (!p->robot) ScriptError(L, "%s: this program has no robot (scenario: programs[].robot)", what);
  return *p->robot;
}

// options table field as a number (or `fallback` when absent)
double Option(lua_State* L, int options, const char* key, double fallback, const char* what) {
  if (lua_isnoneornil(L, options)) return fallback;
  lua_getfield(L, options, key);
  double v = fallback;
  if (!lua_isnil(L, -1)) {
    if (!lua_isnumber(L, -1)) ScriptError(L, "%s: option %s must be a number, got %s", what, key, luaL_typename(L, -1));
    v = lua_tonumber(L, -1);
    if (!std::isfinite(v)) ScriptError(L, "%s: option %s is not finite", what, key);
  }
  lua_pop(L, 1);
  return v;
}

// every key of an options table must be one the move honours: a refused one says why, an
// unknown one lists the known ones
void CheckOptions(lua_State* L, int options, const char* what, const char* const* known, const Refused* refused) {
  if (lua_isnoneornil(L, options)) return;
  if (!lua_istable(L, options)) ScriptError(L, "%s: options must be a table, got %s", what, luaL_typename(L, options));
  lua_pushnil(L);
  while (lua_next(L, options)) {
    lua_pop(L, 1);
    if (lua_type(L, -1) != LUA_TSTRING) {
      ScriptError(L, "%s: option keys are names (v = ..., t = ...), got a %s key", what, luaL_typename(L, -1));
    }
    const char* key = lua_tostring(L, -1);
    bool found = false;
    for (const char* const* k = known; *k; ++k) found = found || !std::strcmp(*k, key);
    if (found) continue;
    for (const Refused* r = refused; r && r->key; ++r) {
      if (!std::strcmp(r->key, key)) ScriptError(L, "%s: option '%s' is not supported: %s", what, key, r->why);
    }
    char list[256] = "";
    for (const char* const* k = known; *k; ++k) {
      std::strncat(list, k == known ? "" : ", ", sizeof list - std::strlen(list) - 1);
      std::strncat(list, *k, sizeof list - std::strlen(list) - 1);
    }
    ScriptError(L, "%s: unknown option '%s' (options: %s)", what, key, list);
  }
}

const double* JointAngles(lua_State* L, int index, int n, const char* what) {
  if (static_cast<int>(lua_rawlen(L, index)) != n) {
    ScriptError(L, "%s: expected %d joint angles (deg), got %d", what, n, static_cast<int>(lua_rawlen(L, index)));
  }
  auto* q = static_cast<double*>(lua_newuserdatauv(L, sizeof(double) * n, 0));
  for (int i = 0; i < n; ++i) {
    lua_rawgeti(L, index, i + 1);
    if (!lua_isnumber(L, -1)) ScriptError(L, "%s: joint %d must be a number (deg)", what, i + 1);
    const double deg = lua_tonumber(L, -1);
    if (!std::isfinite(deg)) ScriptError(L, "%s: joint %d is %g, not a finite angle (deg)", what, i + 1, deg);
    q[i] = deg * kDeg;
    lua_pop(L, 1);
  }
  return q;
}

// whether the options table has `key`
bool HasOption(lua_State* L, int options, const char* key) {
  if (lua_isnoneornil(L, options)) return false;
  lua_getfield(L, options, key);
  const bool has = !lua_isnil(L, -1);
  lua_pop(L, 1);
  return has;
}

// a move's target frame: every number finite (a NaN or inf would reach the inverse kinematics)
void CheckFinite(lua_State* L, const Frame& f, const char* what, const char* which) {
  if (!f.p.allFinite()) {
    ScriptError(L, "%s: the %s position (%g, %g, %g) m is not finite", what, which, f.p.x(), f.p.y(), f.p.z());
  }
  if (!f.q.coeffs().allFinite()) ScriptError(L, "%s: the %s rotation is not finite (a NaN or inf)", what, which);
}

// the world frame of a target given in the script's base frame
Frame ToWorld(const Robot& r, const Frame& f) {
  Frame w;
  w.p = r.base_W.p + r.base_W.q * f.p;
  w.q = (r.base_W.q * f.q).normalized();
  return w;
}

// a world frame in the script's base frame (the inverse of ToWorld)
Frame ToBase(const Robot& r, const Frame& w) {
  Frame b;
  b.q = (r.base_W.q.conjugate() * w.q).normalized();
  b.p = r.base_W.q.conjugate() * (w.p - r.base_W.p);
  return b;
}

Frame AsValue(Frame f) {
  f.q.normalize();
  return f;
}

Frame Compose(const Frame& a, const Frame& b) {
  Frame c;
  c.p = a.p + a.q * b.p;
  c.q = (a.q * b.q).normalized();
  return AsValue(c);
}

Frame Relative(const Frame& a, const Frame& b) {
  Frame inverse;  // as frame:inv computes it, then pushed (AsValue)
  inverse.q = a.q.conjugate();
  inverse.p = -(inverse.q * a.p);
  return Compose(AsValue(inverse), b);
}

const Frame* UserFrame(lua_State* L, const char* name, const char* what) {
  lua_getfield(L, LUA_REGISTRYINDEX, kFramesKey);
  lua_getfield(L, -1, name);
  const Frame* f = ToFrame(L, -1);
  lua_pop(L, 2);
  if (!f) {
    char list[512];
    DefinedFrames(L, list, sizeof list);
    ScriptError(L, "%s: no user frame '%s' (%s)", what, name, list);
  }
  return f;
}

const Frame* RefFrame(lua_State* L, int options, const char* what) {
  if (!HasOption(L, options, "ref")) return nullptr;
  lua_getfield(L, options, "ref");
  if (lua_type(L, -1) != LUA_TSTRING) {
    ScriptError(L, "%s: option ref must be the name of a user frame (frame_def), got %s", what, luaL_typename(L, -1));
  }
  const Frame* f = UserFrame(L, lua_tostring(L, -1), what);
  lua_pop(L, 1);
  return f;
}

Frame Target(lua_State* L, int index, int options, const char* what) {
  const Frame& given = CheckFrame(L, index, what);
  CheckFinite(L, given, what, "target");
  const Frame* user = RefFrame(L, options, what);
  if (!user) return given;
  const Frame target = Compose(*user, given);
  CheckFinite(L, target, what, "target");
  return target;
}

}  // namespace vlab::task
