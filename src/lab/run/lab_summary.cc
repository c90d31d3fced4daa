// summary.json: a run's verdict, checks, warnings, versions and timings.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <unistd.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "bridge/bridge_signals.h"
#include "lab/outputs/lab_run_record.h"
#include "lab/outputs/lab_stats.h"
#include "lab/run/lab_runner.h"

#ifndef VLAB_VERSION
#define VLAB_VERSION "0.0.0"
#endif

namespace vlab::lab {

namespace {

nlohmann::json Distribution(const std::vector<double>& v) {
  auto number = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); };
  return {{"count", v.size()},
          {"p50", number(Percentile(v, 50))},
          {"p99", number(Percentile(v, 99))},
          {"max", number(v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end()))}};
}

// a time the kernel may not give (-1) as null
nlohmann::json Known(double s) { return s >= 0 ? nlohmann::json(s) : nlohmann::json(nullptr); }

// the control thread's counters and the machine's steal over a realtime run, and its worst period
nlohmann::json StallJson(const StallReport& r) {
  const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
  const StallRecord& w = r.worst;
  nlohmann::json worst = {{"period", w.period},
                          {"lateness_s", w.lateness_s},
                          {"cause", w.Cause()},
                          {"run_delay_s", Known(w.run_delay_s)},
                          {"on_cpu_s", Known(w.on_cpu_s)},
                          {"window_s", w.window_s},
                          {"steal_s", Known(w.steal_s)},
                          {"steal_window_s", w.steal_window_s},
                          {"involuntary_switches", w.involuntary_switches},
                          {"voluntary_switches", w.voluntary_switches},
                          {"minor_faults", w.minor_faults},
                          {"major_faults", w.major_faults}};
  return {{"steal_s", Known(r.steal_s)},
          {"steal_fraction", r.steal_s >= 0 && r.wall_s > 0 && cpus > 0
                                 ? nlohmann::json(r.steal_s / (r.wall_s * static_cast<double>(cpus)))
                                 : nlohmann::json(nullptr)},
          {"control_thread",
           {{"run_delay_s", Known(r.run_delay_s)},
            {"involuntary_switches", r.involuntary_switches},
            {"voluntary_switches", r.voluntary_switches},
            {"minor_faults", r.minor_faults},
            {"major_faults", r.major_faults}}},
          {"worst_period", worst}};
}

}  // namespace

nlohmann::json SummaryJson(const Scenario& sc, const mjModel* m, const RunResult& r) {
  using nlohmann::json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json checks = json::array();
  for (const auto& c : r.checks) {
    json bound = json::object();
    if (std::isfinite(c.config.min)) bound["min"] = c.config.min;
    if (std::isfinite(c.config.max)) bound["max"] = c.config.max;
    json window = {{"from", c.config.from_s}, {"to", number(c.config.to_s)}};
    checks.push_back({{"name", c.config.name},
                      {"signal", c.config.signal},
                      {"reduce", ReduceName(c.config.reduce)},
                      {"value", number(c.value)},
                      {"bound", bound},
                      {"window_s", window},
                      {"samples", c.samples},
                      {"pass", c.pass}});
    if (c.skipped) checks.back()["skipped"] = "its window starts after the run's end";
  }
  json warnings = json::array();
  for (const auto& w : r.warnings) {
    warnings.push_back({{"name", w.name},
                        {"count", w.count},
                        {"first_time_s", w.first_time_s},
                        {"message", w.message},
                        {"allowed", w.allowed}});
  }
  const double rtf = r.loop_wall_s > 0 ? r.sim_time_s / r.loop_wall_s : 0.0;
  json clock = {{"name", ClockModeName(r.clock)}, {"periods", r.clock_stats.periods}};
  if (r.clock == ClockMode::kRealtime) {
    clock["missed_deadlines"] = r.clock_stats.missed_deadlines;
    clock["missed_fraction"] = r.clock_stats.periods ? static_cast<double>(r.clock_stats.missed_deadlines) /
                                                           static_cast<double>(r.clock_stats.periods)
                                                     : 0.0;
    clock["lateness_s"] = Distribution(r.clock_stats.lateness_s);
    clock["stall"] = StallJson(r.clock_stats.stall);
  }
  if (r.clock == ClockMode::kLockstep) clock["timeouts"] = r.clock_stats.timeouts;
  json served = json::array();
  for (const auto& d : r.served) {
    const auto& c = d.counters;
    served.push_back({{"name", d.name},
                      {"kind", d.kind},
                      {"address", d.address},
                      {"port", d.port},
                      {"received", c.received},
                      {"requests", c.requests},
                      {"accepted", c.accepted},
                      {"describes", c.describes},
                      {"payloads", c.payloads},
                      {"refused", c.refused},
                      {"refused_malformed", c.refused_malformed},
                      {"refused_limits", c.refused_limits},
                      {"refused_not_owner", c.refused_not_owner},
                      {"refused_not_subscribed", c.refused_not_subscribed},
                      {"stale", c.stale},
                      {"stale_window", c.stale_window},
                      {"duplicate", c.duplicate},
                      {"future", c.future},
                      {"watchdog_holds", c.watchdog_holds},
                      {"owners_released", c.owners_released},
                      {"sessions",
                       {{"challenges", c.sessions.challenges},
                        {"subscribed", c.sessions.subscribed},
                        {"unsubscribed", c.sessions.unsubscribed},
                        {"expired", c.sessions.expired},
                        {"refused_full", c.sessions.refused_full},
                        {"evicted", c.sessions.evicted},
                        {"describes_limited", c.sessions.describes_limited}}}});
    if (d.kind == "camera") {
      served.back()["frames"] = {{"sent", d.frames.sent}, {"late", d.frames.late}, {"dropped", d.frames.dropped}};
    }
  }
  const auto grant = [](const RealtimeGrant& g) {
    return json{{"requested", g.requested},
                {"granted", g.granted},
                {"memory_locked", g.memory_locked},
                {"reason", g.reason},
                {"slice_ns", g.slice_ns},
                {"loop_cpu", g.loop_cpu},
                {"device_cpus", g.device_cpus},
                {"deadline_runtime_ns", g.deadline_runtime_ns},
                {"deadline_period_ns", g.deadline_period_ns},
                {"deadline_refused", g.deadline_refused},
                {"wake_latency_held", g.wake_latency_held},
                {"wake_latency_refused", g.wake_latency_refused}};
  };
  json overrides = json::object();
  for (const auto& [key, value] : sc.overrides) overrides[key] = value;
  json summary = {
      {"scenario", sc.name},
      {"file", sc.file},
      {"description", sc.description},
      {"scene", sc.scene},
      {"result", r.interrupted_by   ? "interrupted"
                 : r.exit_code == 0 ? "pass"
                                    : "fail"},
      {"exit_code", r.exit_code},
      {"failure", r.failure},
      {"seed", sc.seed},
      {"overrides", overrides},
      {"record", RecordJson(RecordOf(sc))},
      {"clock", ClockModeName(r.clock)},
      {"duration_s", sc.duration_s},
      {"control_period_s", sc.control_period_s},
      {"timestep_s", m->opt.timestep},
      {"checks", checks},
      {"clock_stats", clock},
      {"realtime_priority", {{"lab", grant(r.realtime)}, {"controller", grant(r.controller.realtime)}}},
      {"bridge",
       {{"devices", served},
        {"command_latency_s", Distribution(r.latencies_s)},
        {"command_age_s", Distribution(r.command_ages_s)}}},
      {"controller",
       {{"type", ControllerTypeName(sc.controller.type)},
        {"program", r.controller.program},
        {"outcome", r.controller.outcome},
        {"ended_run", r.controller.ended_run},
        {"ports", r.controller.ports}}},
      {"warnings", warnings},
      {"plots_skipped", r.plots_skipped},
      {"versions",
       {{"vlab", VLAB_VERSION},
        {"mujoco", MujocoVersion()},
        {"compiler", __VERSION__},
        {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                      std::to_string(EIGEN_MINOR_VERSION)}}},
      {"timings",
       {{"sim_time_s", r.sim_time_s},
        {"steps", r.steps},
        {"control_periods", r.periods},
        {"loop_wall_s", r.loop_wall_s},
        {"total_wall_s", r.total_wall_s},
        {"steps_per_s", r.loop_wall_s > 0 ? r.steps / r.loop_wall_s : 0.0},
        {"realtime_factor", rtf},
        {"log_writer_waits", r.log_waits},
        {"log_writer_wait_s", r.log_wait_s}}},
  };
  // which signal stopped the run, and where: the log holds the periods up to sim_time_s
  if (r.interrupted_by) {
    summary["interrupted"] = {
        {"signal", StopSignalName(r.interrupted_by)}, {"sim_time_s", r.sim_time_s}, {"periods", r.periods}};
  }
  return summary;
}

}  // namespace vlab::lab
