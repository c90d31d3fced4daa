#include "lab/run/lab_run_watch.h"

#include "core/core_mujoco.h"
#include "lab/outputs/lab_log.h"

namespace vlab::lab {

namespace {

// a controller's commands (the sim device's are the run's own)
bool ControllerRole(CommandRole role) {
  return role == CommandRole::kWaited || role == CommandRole::kWaitedFromStart || role == CommandRole::kDriven;
}

const Device* DeviceNamed(const std::vector<Device*>& devices, const std::string& name) {
  for (const Device* d : devices) {
    if (d->name() == name) return d;
  }
  return nullptr;
}

// "pa10 127.0.0.1:50010, jr3 ..."
std::string Endpoints(const std::vector<const ServedDevice*>& served) {
  std::string text;
  for (const ServedDevice* d : served) {
    text += (text.empty() ? "" : ", ") + d->name + " " + d->address + ":" + std::to_string(d->port);
  }
  return text;
}

}  // namespace

std::string WaitingLine(const std::vector<ServedDevice>& served, const std::vector<Device*>& devices,
                        const std::string& clock, double start_timeout_s) {
  std::vector<const ServedDevice*> from_start, any;
  for (const ServedDevice& d : served) {
    const Device* device = DeviceNamed(devices, d.name);
    if (device && device->command_role() == CommandRole::kWaitedFromStart) from_start.push_back(&d);
    if (device && device->command_role() == CommandRole::kWaited) any.push_back(&d);
  }
  if (from_start.empty() && any.empty()) return "";
  const std::string whom = from_start.size() > 1 ? "controllers on " + Endpoints(from_start)
                           : !from_start.empty() ? "a controller on " + Endpoints(from_start)
                           : any.size() > 1      ? "a controller on any of " + Endpoints(any)
                                                 : "a controller on " + Endpoints(any);
  return "waiting for " + whom + " (" + clock + ", start timeout " + FormatDouble(start_timeout_s) + " s)";
}

std::string NoControllerReason(const std::vector<ServedDevice>& served, const std::vector<Device*>& devices) {
  std::vector<const ServedDevice*> commanded;
  long accepted = 0;
  for (const ServedDevice& d : served) {
    const Device* device = DeviceNamed(devices, d.name);
    if (!device || !ControllerRole(device->command_role())) continue;
    commanded.push_back(&d);
    accepted += d.counters.accepted;
  }
  if (commanded.empty() || accepted > 0) return "";
  return "no controller connected: no command arrived in the run (lockstep; commanded devices: " +
         Endpoints(commanded) + ")";
}

std::string Verdict(const RunResult& r, bool diverged, const std::string& no_controller) {
  if (r.periods == 0 && !diverged) return "no control period was simulated: nothing was checked";
  for (const auto& w : r.warnings) {
    if (diverged && IsDivergenceWarning(WarningIndex(w.name))) {
      return "diverged at t = " + FormatDouble(w.first_time_s) + " s: " + w.message;
    }
  }
  for (const auto& w : r.warnings) {
    if (!w.allowed) {
      return "MuJoCo warning '" + w.name + "' (" + std::to_string(w.count) +
             "x, first at t = " + FormatDouble(w.first_time_s) + " s): " + w.message;
    }
  }
  if (!no_controller.empty()) return no_controller;
  for (const auto& c : r.checks) {
    if (!c.pass) {
      return "check '" + c.config.name + "' failed: " + ReduceName(c.config.reduce) + std::string("(") +
             c.config.signal + ") = " + FormatDouble(c.value);
    }
  }
  return "";
}

}  // namespace vlab::lab
