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

/// The table of joint angles at `index` (deg, `n` of them, each a finite number) in radians,
/// in memory Lua owns (a userdata pushed on the stack: nothing to free when a later check
/// raises its error). An error naming `what` for a count other than `n`, a value that is not a
/// number or not finite. The caller has checked that the value is a table.
const double* JointAngles(lua_State* L, int index, int n, const char* what);

/// The registry key of the program's user frames (frame_def): a table, name -> frame.
inline constexpr const char* kFramesKey = "vlab.frames";

/// A frame as a script's frame value holds it (its rotation normalised once
/// more, as PushFrame does): computed here or by the script, equal to the bit.
Frame AsValue(Frame f);
/// a * b as the script's `a * b` gives it (the frame type's product, then AsValue).
Frame Compose(const Frame& a, const Frame& b);
/// inverse(a) * b: the frame b seen from frame a (the script's `a:inv() * b`).
Frame Relative(const Frame& a, const Frame& b);

/// The user frame `name`; an error naming it and the defined ones when there
/// is none. The registry's table keeps it, so the pointer outlives the stack slot.
const Frame* UserFrame(lua_State* L, const char* name, const char* what);
/// The user frame that option `ref` of the options table at `options` names,
/// or null without the option; an error for a value that is not a defined name.
const Frame* RefFrame(lua_State* L, int options, const char* what);
/// The frame at `index` (a target) in the base frame: given in the user frame
/// of option `ref` when there is one (user * target); checked finite.
Frame Target(lua_State* L, int index, int options, const char* what);

/// The world frame of a frame given in the script's base frame (r.base_W).
Frame ToWorld(const Robot& r, const Frame& f);
/// A world frame in the script's base frame (the inverse of ToWorld).
Frame ToBase(const Robot& r, const Frame& w);

}  // namespace vlab::task
