// The task-language runtime: one Lua state per robot program, each program a
// coroutine resumed once per control period, in a fixed order, with a shared
// blackboard (`shared`) and signals between them.
//
// Each period (Step):
//   for every program, in the order given:
//     1. resume its coroutine: it runs until its next wait (every blocking
//        command waits by yielding once per period) or its end
//     2. its motion generator hands out the next joint reference; a guarded
//        move whose force threshold is exceeded stops here
//     3. the arm gets a position command [1, q_1..q_n] (arm order)
// A program that has ended keeps its arm at the last reference. The first
// error (a Lua error, a refused command, an exceeded instruction budget)
// stops the runtime: error() gives "FILE:LINE: message" and a traceback.
//
// Determinism: no wall clock, no addresses, sorted pairs/next, math.random
// seeded from `seed` mixed with the program's index; the programs run in a
// fixed order. Same devices, same seed: the same commands.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

#include "task/task_channel.h"

namespace vlab::task {

/// One robot program.
struct ProgramConfig {
  std::string script;               ///< path of the .lua file
  std::string robot;                ///< arm device it commands ("": none, a supervisor program)
  std::string base_body = "world";  ///< kinematic chain from this body ...
  std::string tip_site;             ///< ... to this site (required with a robot)
  std::string wrench;               ///< default wrench device of guarded moves ("": the only one, if any)
  std::string where;                ///< "FILE:LINE" of its scenario entry, for messages
  /// The program's parameters, the global table PARAMS: NAME -> text as given. A text
  /// that reads whole as a number becomes a number, "true" and "false" booleans, any
  /// other text a string (ParseParam).
  std::map<std::string, std::string> params;
};

/// Checks a parameter's name (a Lua identifier: letters, digits, '_', not first a
/// digit); InputError "`where`: parameter 'NAME': ..." otherwise.
void CheckParamName(const std::string& name, const std::string& where);

/// Splits "NAME=VALUE" (the first '='), checking NAME; InputError naming `text`.
std::pair<std::string, std::string> ParseParam(const std::string& text);

struct RuntimeConfig {
  std::vector<ProgramConfig> programs;
  double period_s = 0.002;
  std::uint64_t seed = 1;
  long instruction_budget = 10'000'000;  ///< VM instructions per resume
  /// markers:next() under a lockstep or fast clock: advance to the period
  /// that delivers the wanted camera frame, then hold the period (wall time)
  /// until its markers state arrives, so that the run is reproducible. False
  /// under a realtime clock: next() yields until a state of the frame or a
  /// later one arrives.
  bool markers_hold = true;
  double markers_wait_s = 10.0;  ///< the longest hold (wall time): then a runtime error
  /// print() output of the programs: (robot or script name, simulated time, text).
  std::function<void(const std::string&, double, const std::string&)> print;
};

/// Compiles `script` without running it: InputError "FILE:LINE: message
/// (syntax error: nothing has run)" on a syntax error, or naming a missing file.
void CheckSyntax(const std::string& script);

class Runtime {
 public:
  /// Loads every script (a syntax error: InputError "FILE:LINE: message",
  /// nothing has run), binds every robot to its arm channel and chain in
  /// `model` (InputError naming the program's `where`). `devices` and
  /// `model` must outlive the runtime.
  static std::unique_ptr<Runtime> Create(const RuntimeConfig& config, const mjModel* model, Devices* devices);
  ~Runtime();

  /// Log columns: per program with a robot, "task.ROBOT.line" (the script line
  /// it waits at, 0 once it returned, the line of its error once it failed) and "task.ROBOT.tool.x|y|z" (the planned tool
  /// position, world, m).
  std::vector<std::string> Columns() const;
  /// One control period at simulated time t_s; writes Columns().size()
  /// values into `columns` (may be null). False once a program failed (see
  /// error()); the commands of the period are not sent then, its columns are
  /// written (the failed program's line is that of its error).
  bool Step(double t_s, double* columns);
  /// True when every program has ended.
  bool finished() const;
  /// The first failure: "FILE:LINE: message\nstack traceback: ...".
  const std::string& error() const;

 private:
  struct Impl;
  explicit Runtime(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::task
