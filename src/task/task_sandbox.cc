#include "task/task_sandbox.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include <lua.hpp>

#include "task/task_lua.h"

namespace vlab::task {

namespace {

constexpr const char* kConfigKey = "vlab.sandbox";
constexpr int kHookEvery = 1000;  // instructions between two hook calls

const SandboxConfig& Config(lua_State* L) {
  lua_getfield(L, LUA_REGISTRYINDEX, kConfigKey);
  const auto* c = static_cast<const SandboxConfig*>(lua_touserdata(L, -1));
  lua_pop(L, 1);
  return *c;
}

// ---- deterministic iteration
// rank of a key type in the fixed order; -1: no deterministic order
int Rank(lua_State* L, int i) {
  switch (lua_type(L, i)) {
    case LUA_TNUMBER:
      return 0;
    case LUA_TSTRING:
      return 1;
    case LUA_TBOOLEAN:
      return 2;
    default:
      return -1;
  }
}

// a < b in the fixed order (both of ranked types)
bool KeyLess(lua_State* L, int a, int b) {
  const int ra = Rank(L, a), rb = Rank(L, b);
  if (ra != rb) return ra < rb;
  if (ra == 0) return lua_compare(L, a, b, LUA_OPLT) != 0;
  if (ra == 1) {
    std::size_t na, nb;
    const char* sa = lua_tolstring(L, a, &na);
    const char* sb = lua_tolstring(L, b, &nb);
    const int c = std::memcmp(sa, sb, std::min(na, nb));
    return c < 0 || (c == 0 && na < nb);
  }
  return !lua_toboolean(L, a) && lua_toboolean(L, b);
}

// pushes a new array of the table's keys (table at t) in the fixed order
void SortedKeys(lua_State* L, int t) {
  t = lua_absindex(L, t);
  lua_newtable(L);
  const int keys = lua_gettop(L);
  lua_Integer n = 0;
  lua_pushnil(L);
  while (lua_next(L, t)) {
    lua_pop(L, 1);
    if (Rank(L, -1) < 0) {
      ScriptError(L,
                  "pairs/next: a table key of type %s has no reproducible order (use numbers, strings or "
                  "booleans as keys)",
                  luaL_typename(L, -1));
    }
    lua_pushvalue(L, -1);
    lua_rawseti(L, keys, ++n);
  }
  // insertion sort on the Lua stack: tables a student iterates are small
  for (lua_Integer i = 2; i <= n; ++i) {
    lua_rawgeti(L, keys, i);  // x
    lua_Integer j = i - 1;
    while (j >= 1) {
      lua_rawgeti(L, keys, j);
      const bool greater = KeyLess(L, -2, -1);
      if (!greater) {
        lua_pop(L, 1);
        break;
      }
      lua_rawseti(L, keys, j + 1);
      --j;
    }
    lua_rawseti(L, keys, j + 1);
  }
}

// iterator of pairs: upvalue 1 the sorted keys, upvalue 2 the position
int SortedIterator(lua_State* L) {
  lua_Integer i = lua_tointeger(L, lua_upvalueindex(2));
  for (;;) {
    ++i;
    if (lua_rawgeti(L, lua_upvalueindex(1), i) == LUA_TNIL) return 0;
    lua_pushvalue(L, -1);
    lua_gettable(L, 1);  // the value, now (a key removed meanwhile is skipped)
    if (!lua_isnil(L, -1)) {
      lua_pushinteger(L, i);
      lua_replace(L, lua_upvalueindex(2));
      return 2;
    }
    lua_pop(L, 2);
  }
}

int SortedPairs(lua_State* L) {
  if (luaL_getmetafield(L, 1, "__pairs") != LUA_TNIL) {  // the table's own iteration
    lua_pushvalue(L, 1);
    lua_call(L, 1, 3);
    return 3;
  }
  luaL_checktype(L, 1, LUA_TTABLE);
  SortedKeys(L, 1);
  lua_pushinteger(L, 0);
  lua_pushcclosure(L, SortedIterator, 2);
  lua_pushvalue(L, 1);
  lua_pushnil(L);
  return 3;
}

int SortedNext(lua_State* L) {
  luaL_checktype(L, 1, LUA_TTABLE);
  lua_settop(L, 2);
  SortedKeys(L, 1);
  const int keys = 3;
  const lua_Integer n = static_cast<lua_Integer>(lua_rawlen(L, keys));
  lua_Integer i = 0;  // index of the key given
  if (!lua_isnil(L, 2)) {
    for (i = 1; i <= n; ++i) {
      lua_rawgeti(L, keys, i);
      const bool same = lua_rawequal(L, -1, 2);
      lua_pop(L, 1);
      if (same) break;
    }
    if (i > n) ScriptError(L, "next: the key given is not in the table");
  }
  if (i + 1 > n) {
    lua_pushnil(L);
    return 1;
  }
  lua_rawgeti(L, keys, i + 1);
  lua_pushvalue(L, -1);
  lua_rawget(L, 1);
  return 2;
}

// ---- require from the script's folder only
int Require(lua_State* L) {
  const char* name = luaL_checkstring(L, 1);
  const std::size_t len = std::strlen(name);
  bool ok = len > 0 && len < 200 && name[0] != '/' && name[0] != '.';
  for (std::size_t i = 0; i < len && ok; ++i) {
    const char c = name[i];
    ok = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
    if (c == '.' && i + 1 < len && name[i + 1] == '.') ok = false;
  }
  if (!ok) {
    ScriptError(L,
                "require: '%s' is not a module name of the script's folder (letters, digits, _ and -; dots for "
                "subfolders; no paths)",
                name);
  }
  lua_getfield(L, LUA_REGISTRYINDEX, "vlab.loaded");
  if (lua_getfield(L, -1, name) != LUA_TNIL) return 1;
  lua_pop(L, 1);
  char path[512];
  {
    std::string file(name);
    std::replace(file.begin(), file.end(), '.', '/');
    std::snprintf(path, sizeof path, "%s/%s.lua", Config(L).script_dir.c_str(), file.c_str());
  }
  if (luaL_loadfilex(L, path, "t") != LUA_OK) {
    const char* why = lua_tostring(L, -1);
    ScriptError(L, "require '%s': %s", name, why ? why : "cannot load");
  }
  lua_call(L, 0, 1);
  if (lua_isnil(L, -1)) {
    lua_pop(L, 1);
    lua_pushboolean(L, 1);
  }
  lua_pushvalue(L, -1);
  lua_setfield(L, -3, name);
  return 1;
}

// ---- load: text chunks only, in the program's globals
int Load(lua_State* L) {
  std::size_t n;
  const char* text = luaL_checklstring(L, 1, &n);
  const char* name = luaL_optstring(L, 2, "=(load)");
  if (luaL_loadbufferx(L, text, n, name, "t") != LUA_OK) {
    lua_pushnil(L);
    lua_insert(L, -2);
    return 2;
  }
  return 1;
}

int Print(lua_State* L) {
  const int n = lua_gettop(L);
  luaL_Buffer b;
  luaL_buffinit(L, &b);
  for (int i = 1; i <= n; ++i) {
    if (i > 1) luaL_addchar(&b, '\t');
    luaL_tolstring(L, i, nullptr);
    luaL_addvalue(&b);
  }
  luaL_pushresult(&b);
  const SandboxConfig& c = Config(L);
  if (c.print) c.print(lua_tostring(L, -1));
  return 0;
}

void Hook(lua_State* L, lua_Debug* ar) {
  (void)ar;
  lua_getfield(L, LUA_REGISTRYINDEX, "vlab.budget");
  const lua_Integer left = lua_tointeger(L, -1) - kHookEvery;
  lua_pop(L, 1);
  lua_pushinteger(L, left);
  lua_setfield(L, LUA_REGISTRYINDEX, "vlab.budget");
  if (left < 0) {
    lua_getfield(L, LUA_REGISTRYINDEX, "vlab.budget_total");
    const lua_Integer total = lua_tointeger(L, -1);
    lua_pop(L, 1);
    ScriptError(L,
                "instruction budget exceeded: %lld instructions without a wait (a loop that never waits? call "
                "wait() or sync() in it)",
                static_cast<long long>(total));
  }
}

void Remove(lua_State* L, const char* table, const char* field) {
  lua_getglobal(L, table);
  lua_pushnil(L);
  lua_setfield(L, -2, field);
  lua_pop(L, 1);
}

}  // namespace

void OpenSandbox(lua_State* L, const SandboxConfig* config) {
  lua_pushlightuserdata(L, const_cast<SandboxConfig*>(config));
  lua_setfield(L, LUA_REGISTRYINDEX, kConfigKey);
  lua_newtable(L);
  lua_setfield(L, LUA_REGISTRYINDEX, "vlab.loaded");
  static const luaL_Reg libs[] = {{LUA_GNAME, luaopen_base},       {LUA_COLIBNAME, luaopen_coroutine},
                                  {LUA_MATHLIBNAME, luaopen_math}, {LUA_STRLIBNAME, luaopen_string},
                                  {LUA_TABLIBNAME, luaopen_table}, {LUA_UTF8LIBNAME, luaopen_utf8}};
  for (const luaL_Reg& lib : libs) {
    luaL_requiref(L, lib.name, lib.func, 1);
    lua_pop(L, 1);
  }
  for (const char* name : {"dofile", "loadfile", "collectgarbage"}) {
    lua_pushnil(L);
    lua_setglobal(L, name);
  }
  Remove(L, "string", "dump");
  static const luaL_Reg replaced[] = {{"pairs", SortedPairs}, {"next", SortedNext}, {"require", Require},
                                      {"load", Load},         {"print", Print},     {nullptr, nullptr}};
  lua_pushglobaltable(L);
  luaL_setfuncs(L, replaced, 0);
  lua_pop(L, 1);
  // math.randomseed(seed): Lua seeds from the time and an address otherwise
  lua_getglobal(L, "math");
  lua_getfield(L, -1, "randomseed");
  lua_pushinteger(L, static_cast<lua_Integer>(config->seed & 0x7fffffffffffffffULL));
  lua_call(L, 1, 0);
  lua_pop(L, 1);
}

void ArmBudget(lua_State* co, long instruction_budget) {
  lua_pushinteger(co, instruction_budget);
  lua_setfield(co, LUA_REGISTRYINDEX, "vlab.budget");
  lua_pushinteger(co, instruction_budget);
  lua_setfield(co, LUA_REGISTRYINDEX, "vlab.budget_total");
  lua_sethook(co, Hook, LUA_MASKCOUNT, kHookEvery);
}

}  // namespace vlab::task
