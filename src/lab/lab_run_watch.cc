#include "lab/lab_run_watch.h"

#include "lab/lab_log.h"
#include "core/core_mujoco.h"

namespace vlab::lab {

std::string Verdict(const RunResult& r, bool diverged, const std::string& no_controller) {
  if (r.periods == 0 && !diverged) return "no control period was simulated: nothing was checked";
  for (const auto& w : r.warnings) {
    if (diverged && IsDivergenceWarning(WarningIndex(w.name))) {
      return "diverged at t = " + FormatDouble(w.first_time_s) + " s: " + w.message;
    }
  }
  for (const auto& w : r.warnings) {
    if (!w.allowed) {
      return "MuJoCo warning '" + w.name + "' (" + std::to_string(w.count) + "x, first at t = " +
             FormatDouble(w.first_time_s) + " s): " + w.message;
    }
  }
  if (!no_controller.empty()) return no_controller;
  for (const auto& c : r.checks) {
    if (!c.pass) {
      return "check '" + c.config.name + "' failed: " + ReduceName(c.config.reduce) + std::string("(") + c.config.signal +
             ") = " + FormatDouble(c.value);
    }
  }
  return "";
}

}  // namespace vlab::lab
