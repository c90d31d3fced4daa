#include "task/task_lua.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include <lua.hpp>

namespace vlab::task {

void ScriptWhere(lua_State* L, char* out, int size) {
  lua_Debug ar;
  for (int level = 0; lua_getstack(L, level, &ar); ++level) {
    if (!lua_getinfo(L, "Sl", &ar)) continue;
    // a script file: chunk names "@PATH"; the runtime's own code is "=..."
    if (ar.source && ar.source[0] == '@' && ar.currentline > 0) {
      std::snprintf(out, size, "%s:%d", ar.source + 1, ar.currentline);
      return;
    }
  }
  std::snprintf(out, size, "?");
}

void ScriptError(lua_State* L, const char* format, ...) {
  char where[256];
  ScriptWhere(L, where, sizeof where);
  char text[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  lua_pushfstring(L, "%s: %s", where, text);
  lua_error(L);
  for (;;) {
  }  // lua_error does not return
}

double NumberArg(lua_State* L, int i, const char* what) {
  if (!lua_isnumber(L, i)) ScriptError(L, "%s: argument %d must be a number, got %s", what, i, luaL_typename(L, i));
  const double v = lua_tonumber(L, i);
  if (!std::isfinite(v)) ScriptError(L, "%s: argument %d is not finite", what, i);
  return v;
}

}  // namespace vlab::task
