// The files vlab excite writes (cli_excite.cc): the task, the scenario that runs it in the
// lab, and the record of the trajectory.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "cli/cli_excite.h"
#include "core/core_output_file.h"

namespace vlab::cli::excite {

namespace {

std::string Num(double x) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", x);
  return s;
}

std::string Script(const ExciteArgs& a, const std::string& arm, const control::FourierExcitation& t,
                   double control_period_s, double cond) {
  const Eigen::VectorXd q0 = t.Offsets();
  std::string s;
  s += "-- An excitation trajectory for identifying " + arm + "'s dynamics, written by vlab excite\n";
  s += "-- (docs/identify.md): a finite Fourier series per joint (Swevers et al. 1997),\n";
  s += "--   q_i(t) = q0_i + sum_l a_il/(w l) sin(w l t) - b_il/(w l) cos(w l t),  w = 2 pi / T,\n";
  s += "-- at rest at the start pose at t = 0, T, 2T, ...; condition number of the regressor " + Num(cond) + ".\n";
  s += "-- It moves to the start pose (movej), then streams one reference per control period\n";
  s += "-- (servoj, which refuses any beyond a joint's limits) for " + std::to_string(a.cycles) +
       " periods. Angles in deg, a and b in deg/s.\n";
  s += "local T, cycles = " + Num(t.period_s) + ", " + std::to_string(a.cycles) + "\n";
  s += "assert(math.abs(PERIOD - " + Num(control_period_s) + ") < 1e-9, \"excite.lua was planned for a " +
       Num(control_period_s) + " s control period, this arm's is \" .. PERIOD .. \" s: run vlab excite on a " +
       "scenario with its control_period\")\n";
  const auto list = [](const Eigen::VectorXd& v, double unit) {
    std::string out = "{";
    for (int i = 0; i < v.size(); ++i) out += (i ? ", " : "") + Num(v[i] / unit);
    return out + "}";
  };
  s += "local start = " + list(t.q_start, kDeg) + "\n";
  s += "local q0 = " + list(q0, kDeg) + "\n";
  for (const char* which : {"a", "b"}) {
    const Eigen::MatrixXd& c = which[0] == 'a' ? t.a : t.b;
    s += std::string("local ") + which + " = {\n";
    for (int i = 0; i < c.rows(); ++i) s += "  " + list(c.row(i).transpose(), kDeg) + ",\n";
    s += "}\n";
  }
  s += R"(local w = 2 * math.pi / T
movej(start)
print(string.format("excitation: %d periods of %g s", cycles, T))
local q = {}
for k = 1, math.floor(cycles * T / PERIOD + 0.5) do
  local t = k * PERIOD
  for i = 1, #q0 do
    local v = q0[i]
    for l = 1, #a[i] do
      local wl = w * l
      v = v + (a[i][l] * math.sin(wl * t) - b[i][l] * math.cos(wl * t)) / wl
    end
    q[i] = v
  end
  servoj(q)
end
print("excitation: done")
)";
  return s;
}

std::vector<double> Values(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

nlohmann::ordered_json Matrix(const Eigen::MatrixXd& m) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int i = 0; i < m.rows(); ++i) rows.push_back(Values(m.row(i).transpose()));
  return rows;
}

// excite.yaml: the scenario's scene, keyframe, control period and arm, a task controller running
// excite.lua, and checks that the arm's logged joints keep their limits
std::string ScenarioYaml(const ExciteArgs& a, const lab::Scenario& s, const lab::DeviceConfig& arm,
                         const std::string& tip, const std::string& base, const control::DynamicsRegressor& r,
                         const control::JointLimits& limits, const std::string& out_dir, double duration_s) {
  const YAML::Node resolved = YAML::Load(s.resolved_yaml);
  YAML::Node arm_node;
  for (const YAML::Node& d : resolved["devices"]) {
    if (d["name"] && d["name"].as<std::string>() == arm.name) arm_node = d;
  }
  namespace fs = std::filesystem;
  const std::string scene =
      fs::relative(fs::weakly_canonical(fs::absolute(s.scene)), fs::weakly_canonical(fs::absolute(out_dir))).string();
  YAML::Emitter y;
  y << YAML::Comment("Excitation of arm " + arm.name + " for identification, written by vlab excite from " + s.file +
                     " (docs/identify.md): excite.lua streams the trajectory of excite.json");
  y << YAML::BeginMap;
  y << YAML::Key << "name" << YAML::Value << "excite-" + arm.name;
  y << YAML::Key << "description" << YAML::Value
    << "Excitation trajectory of " + arm.name + " (" + std::to_string(a.harmonics) + " harmonics, period " +
           Num(a.period_s) + " s, " + std::to_string(a.cycles) + " periods)";
  y << YAML::Key << "scene" << YAML::Value << scene;
  if (!s.keyframe.empty()) y << YAML::Key << "keyframe" << YAML::Value << s.keyframe;
  y << YAML::Key << "duration" << YAML::Value << duration_s;
  y << YAML::Key << "control_period" << YAML::Value << s.control_period_s;
  y << YAML::Key << "seed" << YAML::Value << s.seed;
  y << YAML::Key << "clock" << YAML::Value << "fast";
  if (resolved["allow_warnings"]) y << YAML::Key << "allow_warnings" << YAML::Value << resolved["allow_warnings"];
  y << YAML::Key << "devices" << YAML::Value << YAML::BeginSeq << arm_node << YAML::EndSeq;
  y << YAML::Key << "controller" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "type" << YAML::Value << "task";
  y << YAML::Key << "programs" << YAML::Value << YAML::BeginSeq << YAML::Flow << YAML::BeginMap;
  y << YAML::Key << "robot" << YAML::Value << arm.name << YAML::Key << "script" << YAML::Value << "excite.lua";
  y << YAML::Key << "tip_site" << YAML::Value << tip << YAML::Key << "base_body" << YAML::Value << base;
  y << YAML::EndMap << YAML::EndSeq << YAML::EndMap;
  y << YAML::Key << "outputs" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "log" << YAML::Value
    << true << YAML::EndMap;
  y << YAML::Key << "checks" << YAML::Value << YAML::BeginSeq;
  y << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << "program_ended" << YAML::Key << "signal"
    << YAML::Value << "task." + arm.name + ".line" << YAML::Key << "reduce" << YAML::Value << "final" << YAML::Key
    << "max" << YAML::Value << 0 << YAML::EndMap;
  for (int i = 0; i < r.dof(); ++i) {
    const std::string& j = r.joint_names()[i];
    y << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << "speed_" + j << YAML::Key << "signal"
      << YAML::Value << arm.name + ".qd." + j << YAML::Key << "reduce" << YAML::Value << "max_abs" << YAML::Key << "max"
      << YAML::Value << limits.v_max[i] << YAML::EndMap;
    if (std::isfinite(limits.upper[i])) {
      y << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << "upper_" + j << YAML::Key << "signal"
        << YAML::Value << arm.name + ".q." + j << YAML::Key << "reduce" << YAML::Value << "max" << YAML::Key << "max"
        << YAML::Value << limits.upper[i] << YAML::EndMap;
      y << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << "lower_" + j << YAML::Key << "signal"
        << YAML::Value << arm.name + ".q." + j << YAML::Key << "reduce" << YAML::Value << "min" << YAML::Key << "min"
        << YAML::Value << limits.lower[i] << YAML::EndMap;
    }
  }
  y << YAML::EndSeq << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

nlohmann::ordered_json Record(const ExciteArgs& a, const lab::Scenario& s, const std::string& arm,
                              const control::DynamicsRegressor& r, const control::JointLimits& limits,
                              const control::ExcitationConfig& c, const control::ExcitationResult& res) {
  nlohmann::ordered_json j;
  j["command"] = "excite";
  j["vlab_version"] = VLAB_VERSION;
  j["scenario"] = s.file;
  j["arm"] = arm;
  j["joints"] = r.joint_names();
  j["harmonics"] = c.harmonics;
  j["period_s"] = c.period_s;
  j["cycles"] = a.cycles;
  j["control_period_s"] = c.control_period_s;
  j["seed"] = c.seed;
  j["evaluations"] = res.evaluations;
  j["condition_number"] = {{"initial", res.cond_initial}, {"optimised", res.cond_final}};
  j["start_rad"] = Values(res.trajectory.q_start);
  j["offsets_rad"] = Values(res.trajectory.Offsets());
  j["a_rad_per_s"] = Matrix(res.trajectory.a);
  j["b_rad_per_s"] = Matrix(res.trajectory.b);
  nlohmann::ordered_json l;
  l["lower_rad"] = Values(limits.lower);
  l["upper_rad"] = Values(limits.upper);
  l["speed_rad_per_s"] = Values(limits.v_max);
  l["acceleration_rad_per_s2"] = Values(limits.a_max);
  l["position_margin_rad"] = c.position_margin_rad;
  l["rate_fraction"] = c.rate_fraction;
  l["clearance_m"] = c.clearance_m;
  j["limits"] = l;
  j["peaks"] = {{"q_min_rad", Values(res.peaks.q_min)},
                {"q_max_rad", Values(res.peaks.q_max)},
                {"speed_rad_per_s", Values(res.peaks.v_abs)},
                {"acceleration_rad_per_s2", Values(res.peaks.a_abs)}};
  j["clearance_m"] = res.clearance_m;
  j["closest"] = res.closest;
  nlohmann::ordered_json base;
  base["parameters"] = r.parameters();
  std::vector<std::string> kept, dropped;
  for (int k : res.base.independent) kept.push_back(r.names()[k]);
  for (int k : res.base.dependent) dropped.push_back(r.names()[k]);
  base["independent"] = kept;
  base["dropped"] = dropped;
  j["base_parameters"] = base;
  return j;
}

}  // namespace

void WriteOutputs(const ExciteArgs& a, const lab::Scenario& s, const lab::DeviceConfig& arm, const std::string& tip,
                  const std::string& base, const control::DynamicsRegressor& r, const control::JointLimits& limits,
                  const control::ExcitationConfig& c, const control::ExcitationResult& res, lab::OutputDir& out) {
  WriteOutputFile(out.File("excite.lua"), Script(a, arm.name, res.trajectory, c.control_period_s, res.cond_final));
  const double duration = a.cycles * a.period_s + 1.0;  // the stream, and a second at rest
  WriteOutputFile(out.File("excite.yaml"), ScenarioYaml(a, s, arm, tip, base, r, limits, out.final_dir(), duration));
  WriteOutputFile(out.File("excite.json"), Record(a, s, arm.name, r, limits, c, res).dump(2) + "\n");
}

}  // namespace vlab::cli::excite
