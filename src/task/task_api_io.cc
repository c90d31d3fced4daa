// The task language's devices, markers and blackboard (the Lua side of
// task_channel.h and task_program.h's Blackboard):
//   device(NAME) -> {get, read, send}   a served or in-process device by name
//   markers(NAME)                       a markers device (kind 5, task_markers.h);
//                                       the prelude's markers() wraps _markers_*
//   shared.KEY, signal(), wait_signal() the blackboard every program shares
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <lua.hpp>

#include "task/task_lua.h"
#include "task/task_markers.h"
#include "task/task_program.h"

namespace vlab::task {

namespace {

// ---- devices by name: device(NAME) -> {get, read, send}
Channel* DeviceArg(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  lua_getfield(L, 1, "name");
  Channel* c = ProgramOf(L)->devices->Find(lua_tostring(L, -1) ? lua_tostring(L, -1) : "");
  lua_pop(L, 1);
  if (!c) ScriptError(L, "device: not a device object (use d:get(...), not d.get(...))");
  return c;
}
int DeviceGet(lua_State* L) {
  Channel* c = DeviceArg(L);
  const char* field = luaL_checkstring(L, 2);
  double value = 0;
  int found = -2;
  {
    std::vector<double> v;
    if (c->Read(&v)) {
      found = IndexOf(c->state_names(), field);
      if (found >= 0) value = v[found];
    }
  }
  if (found == -2) ScriptError(L, "device '%s' has sent no state yet (reading '%s')", c->name().c_str(), field);
  if (found < 0) ScriptError(L, "device '%s' has no state field '%s'", c->name().c_str(), field);
  lua_pushnumber(L, value);
  return 1;
}
int DeviceRead(lua_State* L) {
  Channel* c = DeviceArg(L);
  // (the Lua calls below raise only on memory exhaustion)
  std::vector<double> v;
  const bool ok = c->Read(&v);
  lua_createtable(L, 0, static_cast<int>(c->state_names().size()));
  for (std::size_t i = 0; ok && i < v.size() && i < c->state_names().size(); ++i) {
    lua_pushnumber(L, v[i]);
    lua_setfield(L, -2, c->state_names()[i].c_str());
  }
  return 1;
}
int DeviceSend(lua_State* L) {
  Channel* c = DeviceArg(L);
  luaL_checktype(L, 2, LUA_TTABLE);
  const std::vector<std::string>& names = c->command_names();
  if (names.empty()) ScriptError(L, "device '%s' takes no commands", c->name().c_str());
  Program* p = ProgramOf(L);
  std::vector<double>& command = p->device_commands[c->name()];
  command.assign(names.size(), 0.0);
  for (std::size_t i = 0; i < names.size(); ++i) {
    lua_getfield(L, 2, names[i].c_str());
    if (!lua_isnumber(L, -1)) {
      p->device_commands.erase(c->name());
      ScriptError(L, "device '%s': command field '%s' must be a number", c->name().c_str(), names[i].c_str());
    }
    command[i] = lua_tonumber(L, -1);
    lua_pop(L, 1);
  }
  return 0;
}
int Device(lua_State* L) {
  const char* name = luaL_checkstring(L, 1);
  Channel* c = ProgramOf(L)->devices->Find(name);
  if (!c) ScriptError(L, "device: no device named '%s'", name);
  if (c->kind() == bridge::DeviceKind::kArm && ProgramOf(L)->robot && c == ProgramOf(L)->robot->arm) {
    ScriptError(L, "device: '%s' is this program's robot: use movej/movel and joints()", name);
  }
  lua_createtable(L, 0, 4);
  lua_pushstring(L, name);
  lua_setfield(L, -2, "name");
  static const luaL_Reg methods[] = {
      {"get", DeviceGet}, {"read", DeviceRead}, {"send", DeviceSend}, {nullptr, nullptr}};
  luaL_setfuncs(L, methods, 0);
  return 1;
}

// ---- markers(NAME): a markers device (kind 5), through task_markers.h
MarkerChannel* MarkersArg(lua_State* L) {
  const char* name = luaL_checkstring(L, 1);
  MarkerChannel* m = ProgramOf(L)->devices->FindMarkers(name);
  if (!m) ScriptError(L, "markers: no markers device named '%s'", name);
  return m;
}
int MarkersOpen(lua_State* L) {
  MarkerChannel* m = MarkersArg(L);
  char why[512] = "";
  try {
    m->Open();
  } catch (const std::exception& e) {
    std::snprintf(why, sizeof why, "%s", e.what());
  }
  if (why[0]) ScriptError(L, "markers '%s': %s", lua_tostring(L, 1), why);
  return 0;
}
void PushMarkerFrame(lua_State* L, const Eigen::Matrix4d& T) {
  Frame f;
  f.p = T.block<3, 1>(0, 3);
  f.q = Eigen::Quaterniond(Eigen::Matrix3d(T.block<3, 3>(0, 0))).normalized();
  PushFrame(L, f);
}
// {seq, time, described, unknown, markers = {{dictionary, id, valid, error, camera, world}, ...}}
void PushMarkersState(lua_State* L, const bridge::MarkersClient::State& s) {
  lua_createtable(L, 0, 5);
  lua_pushinteger(L, static_cast<lua_Integer>(s.seq));
  lua_setfield(L, -2, "seq");
  lua_pushnumber(L, s.time);
  lua_setfield(L, -2, "time");
  lua_pushinteger(L, s.described);
  lua_setfield(L, -2, "described");
  lua_pushinteger(L, s.unknown);
  lua_setfield(L, -2, "unknown");
  lua_createtable(L, static_cast<int>(s.markers.size()), 0);
  for (std::size_t i = 0; i < s.markers.size(); ++i) {
    const bridge::MarkersClient::Marker& m = s.markers[i];
    lua_createtable(L, 0, 6);
    const bridge::MarkerDictionary* d = bridge::FindMarkerDictionary(m.dictionary);
    lua_pushstring(L, d ? d->name : "?");
    lua_setfield(L, -2, "dictionary");
    lua_pushinteger(L, m.id);
    lua_setfield(L, -2, "id");
    lua_pushboolean(L, m.valid);
    lua_setfield(L, -2, "valid");
    lua_pushnumber(L, m.reprojection_error_px);
    lua_setfield(L, -2, "error");
    PushMarkerFrame(L, m.T_camera_marker);
    lua_setfield(L, -2, "camera");
    if (m.world_valid) {
      PushMarkerFrame(L, m.T_world_marker);
      lua_setfield(L, -2, "world");
    }
    lua_rawseti(L, -2, static_cast<lua_Integer>(i + 1));
  }
  lua_setfield(L, -2, "markers");
}
// (due, frame_time): the period that delivers the wanted frame; nothing when not holding
int MarkersDue(lua_State* L) {
  MarkerChannel* m = MarkersArg(L);
  const double t0 = NumberArg(L, 2, "markers:next");
  char why[512] = "";
  try {
    m->Renew();  // the frame wanted is exposed from now on: subscribed by then, however long the script was away
  } catch (const std::exception& e) {
    std::snprintf(why, sizeof why, "%s", e.what());
  }
  if (why[0]) ScriptError(L, "markers '%s': %s", lua_tostring(L, 1), why);
  const CameraTiming timing = m->timing();
  if (!ProgramOf(L)->markers_hold || !(timing.fps > 0)) return 0;
  double frame_time = 0;
  const double due = MarkersFrameDue(timing, ProgramOf(L)->period_s, t0, &frame_time);
  lua_pushnumber(L, due);
  lua_pushnumber(L, frame_time);
  return 2;
}
// the markers state of the frame stamped frame_time: waits (wall time) while the period is held
int MarkersTake(lua_State* L) {
  MarkerChannel* m = MarkersArg(L);
  const double frame_time = NumberArg(L, 2, "markers:next");
  const double wait_s = ProgramOf(L)->markers_wait_s;
  auto s = std::make_unique<bridge::MarkersClient::State>();
  char why[512] = "";
  try {
    if (!m->WaitFor(frame_time, wait_s, s.get())) {
      std::snprintf(why, sizeof why,
                    "no markers state of the camera frame stamped %.6g s within %g s of waiting (is the vision "
                    "program running, and its camera served?)",
                    frame_time, wait_s);
    } else if (std::fabs(s->time - frame_time) > 1e-6) {
      std::snprintf(why, sizeof why,
                    "waited for the camera frame stamped %.6g s and got the one stamped %.6g s: the camera's schedule "
                    "is not the one its describe reply gives (fps, exposure_s, latency_s)",
                    frame_time, s->time);
    }
  } catch (const std::exception& e) {
    std::snprintf(why, sizeof why, "%s", e.what());
  }
  if (why[0]) {
    s.reset();
    ScriptError(L, "markers '%s': %s", lua_tostring(L, 1), why);
  }
  PushMarkersState(L, *s);
  return 1;
}
// calls read(state), a markers channel's read that does not wait, and pushes the state it
// got (1 result) or nothing (0). An exception is a script error, raised once every C++
// object here is gone (lua_error does not unwind C++ frames).
template <typename Read>
int PushMarkersRead(lua_State* L, Read read) {
  auto s = std::make_unique<bridge::MarkersClient::State>();
  char why[512] = "";
  bool got = false;
  try {
    got = read(s.get());
  } catch (const std::exception& e) {
    std::snprintf(why, sizeof why, "%s", e.what());
  }
  if (why[0]) {
    s.reset();
    ScriptError(L, "markers '%s': %s", lua_tostring(L, 1), why);
  }
  if (!got) return 0;
  PushMarkersState(L, *s);
  return 1;
}
int MarkersPoll(lua_State* L) {
  MarkerChannel* m = MarkersArg(L);
  const double t0 = NumberArg(L, 2, "markers:next");
  return PushMarkersRead(L, [m, t0](bridge::MarkersClient::State* s) { return m->Poll(t0, s); });
}
int MarkersLatest(lua_State* L) {
  MarkerChannel* m = MarkersArg(L);
  return PushMarkersRead(L, [m](bridge::MarkersClient::State* s) { return m->Latest(s); });
}

// ---- blackboard
int SharedIndex(lua_State* L) {
  const char* key = luaL_checkstring(L, 2);
  Blackboard* b = ProgramOf(L)->board;
  const auto it = b->values.find(key);
  if (it == b->values.end()) {
    lua_pushnil(L);
    return 1;
  }
  const SharedValue& v = it->second;
  switch (v.type) {
    case SharedValue::kNumber:
      lua_pushnumber(L, v.number);
      break;
    case SharedValue::kString:
      lua_pushlstring(L, v.text.data(), v.text.size());
      break;
    case SharedValue::kBoolean:
      lua_pushboolean(L, v.number != 0);
      break;
    case SharedValue::kVec3:
      PushVec3(L, v.frame.p);
      break;
    case SharedValue::kQuat:
      PushQuat(L, v.frame.q);
      break;
    case SharedValue::kFrame:
      PushFrame(L, v.frame);
      break;
  }
  return 1;
}
int SharedNewIndex(lua_State* L) {
  const char* key = luaL_checkstring(L, 2);
  Blackboard* b = ProgramOf(L)->board;
  if (lua_isnil(L, 3)) {
    b->values.erase(key);
    return 0;
  }
  SharedValue v;
  if (lua_type(L, 3) == LUA_TNUMBER) {
    v.type = SharedValue::kNumber;
    v.number = lua_tonumber(L, 3);
  } else if (lua_type(L, 3) == LUA_TSTRING) {
    v.type = SharedValue::kString;
    v.text = lua_tostring(L, 3);
  } else if (lua_type(L, 3) == LUA_TBOOLEAN) {
    v.type = SharedValue::kBoolean;
    v.number = lua_toboolean(L, 3);
  } else if (const Eigen::Vector3d* p = ToVec3(L, 3)) {
    v.type = SharedValue::kVec3;
    v.frame.p = *p;
  } else if (const Eigen::Quaterniond* q = ToQuat(L, 3)) {
    v.type = SharedValue::kQuat;
    v.frame.q = *q;
  } else if (const Frame* f = ToFrame(L, 3)) {
    v.type = SharedValue::kFrame;
    v.frame = *f;
  } else {
    const char* type = luaL_typename(L, 3);
    v = SharedValue();
    ScriptError(L, "shared.%s: a %s cannot be shared (numbers, strings, booleans, vec3, quat, frame)", key, type);
  }
  b->values[key] = std::move(v);
  return 0;
}
int Signal(lua_State* L) {
  const char* name = luaL_checkstring(L, 1);
  ++ProgramOf(L)->board->signals[name];
  return 0;
}
int TakeSignal(lua_State* L) {  // true (and one signal taken) when `name` was raised
  const char* name = luaL_checkstring(L, 1);
  auto& signals = ProgramOf(L)->board->signals;
  const auto it = signals.find(name);
  const bool raised = it != signals.end() && it->second > 0;
  if (raised) --it->second;
  lua_pushboolean(L, raised);
  return 1;
}

}  // namespace

void OpenIo(lua_State* L) {
  static const luaL_Reg functions[] = {{"_signal", Signal},
                                       {"_take_signal", TakeSignal},
                                       {"device", Device},
                                       {"_markers_open", MarkersOpen},
                                       {"_markers_due", MarkersDue},
                                       {"_markers_take", MarkersTake},
                                       {"_markers_poll", MarkersPoll},
                                       {"_markers_latest", MarkersLatest},
                                       {nullptr, nullptr}};
  lua_pushglobaltable(L);
  luaL_setfuncs(L, functions, 0);
  lua_pop(L, 1);
  // shared: a proxy of the blackboard
  lua_newtable(L);
  lua_newtable(L);
  lua_pushcfunction(L, SharedIndex);
  lua_setfield(L, -2, "__index");
  lua_pushcfunction(L, SharedNewIndex);
  lua_setfield(L, -2, "__newindex");
  lua_setmetatable(L, -2);
  lua_setglobal(L, "shared");
}

}  // namespace vlab::task
