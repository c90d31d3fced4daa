// What decides a run's verdict besides its checks: MuJoCo's warnings, watched
// after every step, whether a served run had a controller, and the order in
// which failures are reported.
#pragma once

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "lab/run/lab_runner.h"

namespace vlab::lab {

// MuJoCo's warning counters, watched after every step. A divergence resets
// mjData (its counters and time included), so the watch keeps its own.
class WarningWatch {
 public:
  /// Records new warnings of the step that started at t_step; true on divergence.
  bool Update(const mjData& d, double t_step) {
    bool diverged = false;
    for (int w = 0; w < mjNWARNING; ++w) {
      if (d.warning[w].number > count_[w]) {
        if (count_[w] == 0) first_[w] = t_step;
        count_[w] = d.warning[w].number;
        last_info_[w] = d.warning[w].lastinfo;
        diverged = diverged || IsDivergenceWarning(w);
      }
    }
    return diverged;
  }

  /// One report per kind that occurred, with MuJoCo's text.
  std::vector<WarningReport> Reports(const std::vector<std::string>& allowed) const {
    std::vector<WarningReport> reports;
    for (int w = 0; w < mjNWARNING; ++w) {
      if (count_[w] == 0) continue;
      WarningReport r;
      r.name = WarningName(w);
      r.count = count_[w];
      r.first_time_s = first_[w];
      r.message = mju_warningText(w, last_info_[w]);
      r.allowed = std::find(allowed.begin(), allowed.end(), r.name) != allowed.end();
      reports.push_back(r);
    }
    return reports;
  }

 private:
  int count_[mjNWARNING] = {0};
  int last_info_[mjNWARNING] = {0};
  double first_[mjNWARNING] = {0};
};

// vlab serve: the line that says whom period 0 waits for, by LabBridge::Answered's rule (an
// owner of every served arm, else of any served commanded device): "waiting for a controller
// on pa10 127.0.0.1:50010 (lockstep, start timeout 30 s)"; "" when it waits for nobody.
std::string WaitingLine(const std::vector<ServedDevice>& served, const std::vector<Device*>& devices,
                        const std::string& clock, double start_timeout_s);

// vlab serve in lockstep: why the run had no controller when no served commanded device
// accepted a command ("no controller connected: ..."); "" when one did, or none is served.
std::string NoControllerReason(const std::vector<ServedDevice>& served, const std::vector<Device*>& devices);

// The first reason a run fails, in order: no period simulated, divergence, a
// warning the scenario does not allow, `no_controller` (why a served run had no
// controller; "" when it had one or needed none), a failed check; "" when it passes.
std::string Verdict(const RunResult& r, bool diverged, const std::string& no_controller);

}  // namespace vlab::lab
