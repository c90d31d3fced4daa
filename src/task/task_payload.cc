// The task language's payload(): the robot arm's load at its flange, set and
// read in process and over UDP alike (the Channel does the transport).
//
//   payload(mass, {com = {x, y, z}, inertia = {ixx, iyy, izz[, ixy, ixz, iyz]}})
//       kg; m; kg m^2 about the centre of mass, flange frame (com default 0,
//       inertia default 0: a point mass). In force from the next period.
//   payload() -> {mass = kg, com = {x, y, z}, inertia = {ixx, iyy, izz, ixy, ixz, iyz}}
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include <lua.hpp>

#include "bridge/bridge_payload.h"
#include "task/task_lua.h"
#include "task/task_program.h"

namespace vlab::task {

namespace {

// reads option `key` of the table at `options` into out[0..]: between `least` and `most` numbers
void ReadNumbers(lua_State* L, int options, const char* key, int least, int most, double* out, const char* form) {
  if (lua_getfield(L, options, key) == LUA_TNIL) {
    lua_pop(L, 1);
    return;  // the default: zeros
  }
  if (!lua_istable(L, -1)) ScriptError(L, "payload: %s must be a table %s, got %s", key, form, luaL_typename(L, -1));
  const int n = static_cast<int>(lua_rawlen(L, -1));
  if (n < least || n > most) ScriptError(L, "payload: %s must be %s, got %d numbers", key, form, n);
  for (int i = 0; i < n; ++i) {
    lua_rawgeti(L, -1, i + 1);
    if (!lua_isnumber(L, -1))
      ScriptError(L, "payload: %s[%d] must be a number, got %s", key, i + 1, luaL_typename(L, -1));
    out[i] = lua_tonumber(L, -1);
    if (!std::isfinite(out[i])) ScriptError(L, "payload: %s[%d] is not finite", key, i + 1);
    lua_pop(L, 1);
  }
  lua_pop(L, 1);
}

void PushNumbers(lua_State* L, const double* values, int n) {
  lua_createtable(L, n, 0);
  for (int i = 0; i < n; ++i) {
    lua_pushnumber(L, values[i]);
    lua_rawseti(L, -2, i + 1);
  }
}

int PushPayload(lua_State* L, Channel* arm) {
  bridge::ArmPayloadMsg p;
  char why[512] = "";
  {
    std::string reason;
    if (!arm->GetPayload(&p, &reason)) std::snprintf(why, sizeof why, "%s", reason.c_str());
  }
  if (why[0]) ScriptError(L, "payload: %s", why);
  lua_createtable(L, 0, 3);
  lua_pushnumber(L, p.mass_kg);
  lua_setfield(L, -2, "mass");
  PushNumbers(L, p.com_m.data(), 3);
  lua_setfield(L, -2, "com");
  PushNumbers(L, p.inertia_kgm2.data(), 6);
  lua_setfield(L, -2, "inertia");
  return 1;
}

int Payload(lua_State* L) {
  Program* program = ProgramOf(L);
  if (!program->robot) ScriptError(L, "payload: this program has no robot (scenario: programs[].robot)");
  Channel* arm = program->robot->arm;
  if (lua_gettop(L) == 0) return PushPayload(L, arm);

  // the mass, then the options com and inertia
  bridge::ArmPayloadMsg p;
  if (lua_type(L, 1) != LUA_TNUMBER) {
    ScriptError(L, "payload: argument 1 (mass) must be a number (kg), got %s", luaL_typename(L, 1));
  }
  p.mass_kg = lua_tonumber(L, 1);
  if (!std::isfinite(p.mass_kg) || p.mass_kg < 0) {
    ScriptError(L, "payload: argument 1 (mass) must be a finite number >= 0 kg, got %g", p.mass_kg);
  }
  if (!lua_isnoneornil(L, 2)) {
    if (!lua_istable(L, 2)) {
      ScriptError(L, "payload: argument 2 must be a table {com = {x, y, z}, inertia = {...}}, got %s",
                  luaL_typename(L, 2));
    }
    lua_pushnil(L);
    while (lua_next(L, 2)) {
      lua_pop(L, 1);
      const char* key = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "?";
      if (std::strcmp(key, "com") != 0 && std::strcmp(key, "inertia") != 0) {
        ScriptError(L, "payload: unknown option '%s' (com, inertia)", key);
      }
    }
    ReadNumbers(L, 2, "com", 3, 3, p.com_m.data(), "{x, y, z} (m, flange frame)");
    ReadNumbers(L, 2, "inertia", 3, 6, p.inertia_kgm2.data(), "{ixx, iyy, izz[, ixy, ixz, iyz]} (kg m^2)");
  }
  const char* field = nullptr;
  const char* reason = nullptr;
  if (!bridge::CheckArmPayload(p, &field, &reason)) ScriptError(L, "payload: %s %s", field, reason);

  // the arm takes it (over UDP: waits for the device's answer); refused: a script error with the reason
  char why[512] = "";
  {
    std::string reason_text;
    if (!arm->SetPayload(p, &reason_text)) std::snprintf(why, sizeof why, "%s", reason_text.c_str());
  }
  if (why[0]) ScriptError(L, "payload: %s", why);
  return 0;
}

}  // namespace

void OpenPayload(lua_State* L) { lua_register(L, "payload", Payload); }

}  // namespace vlab::task
