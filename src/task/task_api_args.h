// The argument and frame helpers the task language's binding files share
// (task_api.cc, task_api_query.cc): each raises a script error (ScriptError,
// task_lua.h: the script's FILE:LINE, then what is wrong) on a bad argument.
// They longjmp on error: call them with no C++ object alive that needs its
// destructor.
#pragma once

#include "task/task_program.h"
#include "task/task_units.h"
#include "task/task_values.h"

struct lua_State;

namespace vlab::task {

/// The program's robot; an error naming `what` when the program has none.
Robot& NeedRobot(lua_State* L, const char* what);

/// Field `key` of the options table at stack index `options` as a finite
/// number, or `fallback` when the table or the field is absent.
double Option(lua_State* L, int options, const char* key, double fallback, const char* what);

/// An option a call does not take, and why (named in its error).
struct Refused {
  const char* key;
  const char* why;
};

/// Every key of the options table at `options` must be in `known` (null
/// ended): a key in `refused` (ended by a null key) is an error saying why,
/// any other an error listing the known ones. No table: nothing to check.
void CheckOptions(lua_State* L, int options, const char* what, const char* const* known,
                  const Refused* refused = nullptr);

/// Whether the options table at `options` has `key` (false without a table).
bool HasOption(lua_State* L, int options, const char* key);

/// An error naming `what` and `which` ("target") unless every number of `f`
/// is finite.
void CheckFinite(lua_State* L, const Frame& f, const char* what, const char* which);

/// The world frame of a frame given in the script's base frame (r.base_W).
Frame ToWorld(const Robot& r, const Frame& f);
/// A world frame in the script's base frame (the inverse of ToWorld).
Frame ToBase(const Robot& r, const Frame& w);

}  // namespace vlab::task
