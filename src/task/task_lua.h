// Small helpers shared by the task language's Lua bindings.
#pragma once

struct lua_State;

namespace vlab::task {

/// Raises a Lua error whose message starts with the script position of the
/// innermost call from a script file ("pick.lua:12: "), skipping the C
/// functions and the runtime's own Lua code, then the printf-formatted text.
/// Never returns (longjmp): call it with no C++ object alive that needs its
/// destructor.
[[noreturn]] void ScriptError(lua_State* L, const char* format, ...);

/// "FILE:LINE" of the innermost call from a script file, or "?" when none.
/// Writes into `out` (at least 256 bytes).
void ScriptWhere(lua_State* L, char* out, int size);

/// Argument `i` of a Lua call as a finite number; otherwise a ScriptError
/// naming `what` ("speed: argument 1 must be a number, got string", "... is
/// not finite").
double NumberArg(lua_State* L, int i, const char* what);

}  // namespace vlab::task
