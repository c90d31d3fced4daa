// summary.json: a run's verdict, checks, warnings, versions and timings.
#include <cmath>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "lab/lab_runner.h"

#ifndef VLAB_VERSION
#define VLAB_VERSION "0.0.0"
#endif

namespace vlab::lab {

nlohmann::json SummaryJson(const Scenario& sc, const mjModel* m, const RunResult& r) {
  using nlohmann::json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json checks = json::array();
  for (const auto& c : r.checks) {
    json bound = json::object();
    if (std::isfinite(c.config.min)) bound["min"] = c.config.min;
    if (std::isfinite(c.config.max)) bound["max"] = c.config.max;
    json window = {{"from", c.config.from_s}, {"to", number(c.config.to_s)}};
    checks.push_back({{"name", c.config.name}, {"signal", c.config.signal}, {"reduce", c.config.reduce},
                      {"value", number(c.value)}, {"bound", bound}, {"window_s", window},
                      {"samples", c.samples}, {"pass", c.pass}});
  }
  json warnings = json::array();
  for (const auto& w : r.warnings) {
    warnings.push_back({{"name", w.name}, {"count", w.count}, {"first_time_s", w.first_time_s},
                        {"message", w.message}, {"allowed", w.allowed}});
  }
  const double rtf = r.loop_wall_s > 0 ? r.sim_time_s / r.loop_wall_s : 0.0;
  return {
      {"scenario", sc.name},
      {"file", sc.file},
      {"description", sc.description},
      {"scene", sc.scene},
      {"result", r.exit_code == 0 ? "pass" : "fail"},
      {"exit_code", r.exit_code},
      {"failure", r.failure},
      {"seed", sc.seed},
      {"clock", sc.clock},
      {"duration_s", sc.duration_s},
      {"control_period_s", sc.control_period_s},
      {"timestep_s", m->opt.timestep},
      {"checks", checks},
      {"warnings", warnings},
      {"versions",
       {{"vlab", VLAB_VERSION}, {"mujoco", MujocoVersion()}, {"compiler", __VERSION__},
        {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                      std::to_string(EIGEN_MINOR_VERSION)}}},
      {"timings",
       {{"sim_time_s", r.sim_time_s}, {"steps", r.steps}, {"control_periods", r.periods},
        {"loop_wall_s", r.loop_wall_s}, {"total_wall_s", r.total_wall_s},
        {"steps_per_s", r.loop_wall_s > 0 ? r.steps / r.loop_wall_s : 0.0}, {"realtime_factor", rtf}}},
  };
}

}  // namespace vlab::lab
