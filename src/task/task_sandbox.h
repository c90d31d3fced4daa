// The sandbox a task program runs in: one Lua state with the safe standard
// libraries and nothing that reaches the machine.
//
//   kept      base functions (less dofile, loadfile; load takes text only and
//             runs in the program's globals), coroutine, math, string (less
//             string.dump), table, utf8
//   removed   io, os, debug, package, dofile, loadfile, collectgarbage's
//             tuning options
//   replaced  require(NAME): NAME.lua from the script's folder (or a folder
//             below it), text only, loaded once; pairs and next: keys in a
//             fixed order (numbers ascending, then strings by bytes, then
//             false, true), so iteration never depends on Lua's per-run
//             string-hash seed; a key of another type (a table, a function)
//             is an error naming the type; print: to the runtime's sink
//   seeded    math.random from the scenario seed (math.randomseed(seed))
//   budget    an instruction-count hook: more than `instruction_budget` VM
//             instructions between two waits is an error at the line reached
#pragma once

#include <cstdint>
#include <functional>
#include <string>

struct lua_State;

namespace vlab::task {

struct SandboxConfig {
  std::string script_dir = ".";                   ///< folder require() may load from
  std::uint64_t seed = 1;                         ///< math.randomseed
  long instruction_budget = 10'000'000;           ///< VM instructions per resume (> 0)
  std::function<void(const std::string&)> print;  ///< print() output, one line (no newline)
};

/// Opens the libraries and installs the replacements into a fresh state.
/// The config must outlive the state (require and print refer to it).
void OpenSandbox(lua_State* L, const SandboxConfig* config);

/// Starts a new instruction budget for the coroutine `co` (before a resume).
void ArmBudget(lua_State* co, long instruction_budget);

}  // namespace vlab::task
