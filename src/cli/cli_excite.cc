// vlab excite SCENARIO: an excitation trajectory for identifying an arm's
// dynamics (control/excitation_optimizer.h), written as a task that runs in
// the lab and, unchanged, against the real arm.
//
// Ports
//   input   the scenario (its scene, the arm device's joints, initial pose,
//           max_velocity; the control period), the options
//   output  DIR/excite.lua (movej to the start pose, then one servoj per
//           period for --cycles periods of the series), DIR/excite.yaml (the
//           scenario's scene and arm, a task controller running excite.lua,
//           checks on the arm's logged joints), DIR/excite.json (coefficients,
//           limits, peaks, the condition numbers, the base parameters);
//           the summary on stdout
// Exit 2 on bad input (nothing written), 0 once written.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "cli/cli_commands.h"
#include "control/dynamics_regressor.h"
#include "control/excitation_optimizer.h"
#include "control/robot_model.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_arm.h"
#include "lab/outputs/lab_output.h"
#include "lab/scenario/lab_scenario.h"
#include "task/task_rates.h"

namespace vlab::cli::excite {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

struct ExciteArgs {
  std::string scenario, arm, tip, out_dir;
  int harmonics = 5;
  double period_s = 10;
  int cycles = 3;
  long long seed = -1;  // < 0: the scenario's
  int evaluations = 1600;
  double clearance_m = 0.01;
  bool quiet = false;
};

std::string Num(double x) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", x);
  return s;
}

// the scenario's arm device: --arm, or its only arm
const lab::DeviceConfig& FindArm(const lab::Scenario& s, const std::string& name) {
  std::vector<const lab::DeviceConfig*> arms;
  for (const lab::DeviceConfig& d : s.devices) {
    if (d.kind == bridge::DeviceKind::kArm) arms.push_back(&d);
  }
  std::string names;
  for (const auto* a : arms) names += (names.empty() ? "" : ", ") + a->name;
  if (arms.empty()) throw InputError("excite: scenario '" + s.file + "' has no arm device (kind: arm)");
  if (name.empty()) {
    if (arms.size() > 1)
      throw InputError("excite: scenario '" + s.file + "' has several arms (" + names + "): --arm NAME");
    return *arms[0];
  }
  for (const auto* a : arms) {
    if (a->name == name) return *a;
  }
  throw InputError("excite: --arm " + name + ": scenario '" + s.file + "' has no arm device named '" + name +
                   "' (arms: " + names + ")");
}

// the pose every run of the scenario starts from: the keyframe, then the arm's initial
std::vector<double> StartQpos(const mjModel* m, const lab::Scenario& s, const lab::ArmParams& arm) {
  std::vector<double> qpos(m->qpos0, m->qpos0 + m->nq);
  if (!s.keyframe.empty()) {
    const int key = mj_name2id(m, mjOBJ_KEY, s.keyframe.c_str());
    if (key < 0) throw InputError("excite: the scene has no keyframe '" + s.keyframe + "'");
    std::copy(m->key_qpos + key * m->nq, m->key_qpos + (key + 1) * m->nq, qpos.begin());
  }
  for (std::size_t i = 0; i < arm.initial.size() && i < arm.joints.size(); ++i) {
    const int j = mj_name2id(m, mjOBJ_JOINT, arm.joints[i].c_str());
    if (j >= 0) qpos[m->jnt_qposadr[j]] = arm.initial[i];
  }
  return qpos;
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

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file.flush()) throw std::runtime_error(path + ": write failed");
}

void WriteOutputs(const ExciteArgs& a, const lab::Scenario& s, const lab::DeviceConfig& arm, const std::string& tip,
                  const std::string& base, const control::DynamicsRegressor& r, const control::JointLimits& limits,
                  const control::ExcitationConfig& c, const control::ExcitationResult& res, lab::OutputDir& out) {
  WriteFile(out.File("excite.lua"), Script(a, arm.name, res.trajectory, c.control_period_s, res.cond_final));
  const double duration = a.cycles * a.period_s + 1.0;  // the stream, and a second at rest
  WriteFile(out.File("excite.yaml"), ScenarioYaml(a, s, arm, tip, base, r, limits, out.final_dir(), duration));
  WriteFile(out.File("excite.json"), Record(a, s, arm.name, r, limits, c, res).dump(2) + "\n");
}

void PrintSummary(const ExciteArgs& a, const lab::Scenario& s, const std::string& arm,
                  const control::DynamicsRegressor& r, const control::JointLimits& limits,
                  const control::ExcitationConfig& c, const control::ExcitationResult& res, double seconds,
                  const std::string& where) {
  std::printf("vlab excite: arm %s of %s, %d harmonics, period %g s, seed %llu\n", arm.c_str(), s.file.c_str(),
              c.harmonics, c.period_s, static_cast<unsigned long long>(c.seed));
  std::printf("  regressor: %d parameters, %zu base parameters (%zu dropped: zero or combinations of others)\n",
              r.parameters(), res.base.independent.size(), res.base.dependent.size());
  std::printf("  condition number: %.6g (initial guess) -> %.6g (optimised), %d evaluations, %.1f s\n",
              res.cond_initial, res.cond_final, res.evaluations, seconds);
  if (!a.quiet) {
    std::printf("  %-6s %21s %17s %15s %19s\n", "joint", "q min .. max (deg)", "range (deg)", "|qd| (deg/s)",
                "|qdd| (deg/s^2)");
    for (int i = 0; i < r.dof(); ++i) {
      std::printf("  %-6s %9.2f .. %8.2f %7.1f .. %6.1f %6.1f of %5.1f %8.1f of %6.1f\n", r.joint_names()[i].c_str(),
                  res.peaks.q_min[i] / kDeg, res.peaks.q_max[i] / kDeg, limits.lower[i] / kDeg, limits.upper[i] / kDeg,
                  res.peaks.v_abs[i] / kDeg, limits.v_max[i] / kDeg, res.peaks.a_abs[i] / kDeg, limits.a_max[i] / kDeg);
    }
    std::printf("  clearance: at least %.1f mm from the scene and between links at every period%s%s\n",
                res.clearance_m * 1000, res.closest.empty() ? "" : ", closest: ", res.closest.c_str());
  }
  std::printf("vlab excite: wrote %s/excite.lua, excite.yaml, excite.json (run: vlab run %s/excite.yaml)\n",
              where.c_str(), where.c_str());
}

}  // namespace

int Excite(const ExciteArgs& a) {
  if (a.harmonics < 2 || a.harmonics > 50) throw InputError("excite: --harmonics must be 2 ... 50");
  if (!(a.period_s > 0 && a.period_s <= 1000)) throw InputError("excite: --period must be > 0 s and at most 1000 s");
  if (a.cycles < 1 || a.cycles > 1000) throw InputError("excite: --cycles must be 1 ... 1000");
  if (a.evaluations < 4 || a.evaluations > 1000000) throw InputError("excite: --evaluations must be 4 ... 1e6");
  if (!(a.clearance_m >= 0 && a.clearance_m <= 1)) throw InputError("excite: --clearance must be 0 ... 1 m");
  const lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(a.scenario));
  const lab::DeviceConfig& arm_device = FindArm(scenario, a.arm);
  const auto& arm = arm_device.ParamsAs<lab::ArmParams>();
  const ModelPtr model = LoadModel(scenario.scene);
  const int n = static_cast<int>(arm.joints.size());
  const double T = scenario.control_period_s;
  const double steps = a.period_s / T;
  if (std::abs(steps - std::round(steps)) > 1e-6 || steps < 10) {
    char why[200];
    std::snprintf(why, sizeof why,
                  "excite: --period %g s is not a whole number (at least 10) of the scenario's control periods (%g s)",
                  a.period_s, T);
    throw InputError(why);
  }
  // the task's chain: the scenario's task program of this arm, else --tip (default tool)
  std::string tip = a.tip, base = "world";
  if (tip.empty() && scenario.controller.type == lab::ControllerType::kTask) {
    for (const auto& p : scenario.controller.programs) {
      if (p.robot == arm_device.name) tip = p.tip_site, base = p.base_body;
    }
  }
  if (tip.empty()) tip = "tool";
  std::unique_ptr<control::RobotModel> chain;
  try {
    chain = control::RobotModel::Create(model.get(), {base, tip});
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("excite: --tip ") + tip + ": " + e.what());
  }
  if (chain->joint_names() != arm.joints) {
    throw InputError("excite: the chain from '" + base + "' to site '" + tip + "' is not arm '" + arm_device.name +
                     "''s joints in order: give --tip");
  }
  // the limits the task language keeps (task_rates.h): the arm's max_velocity, else the defaults
  const std::vector<double> qpos = StartQpos(model.get(), scenario, arm);
  std::unique_ptr<control::DynamicsRegressor> regressor;
  try {
    regressor = control::DynamicsRegressor::Create(model.get(), arm.joints, qpos);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("excite: arm '") + arm_device.name + "': " + e.what());
  }
  const task::JointRateLimits rates = task::DefaultRateLimits(n);
  control::JointLimits limits;
  limits.lower = regressor->lower_limits();
  limits.upper = regressor->upper_limits();
  limits.v_max = rates.v_rps;
  for (int i = 0; i < n && i < static_cast<int>(arm.max_velocity.size()); ++i) limits.v_max[i] = arm.max_velocity[i];
  limits.a_max = rates.a_rps2;
  Eigen::VectorXd q_start(n);
  for (int i = 0; i < n; ++i) q_start[i] = qpos[regressor->qpos_addresses()[i]];
  control::ExcitationConfig config;
  config.harmonics = a.harmonics;
  config.period_s = a.period_s;
  config.control_period_s = T;
  config.seed = a.seed >= 0 ? static_cast<std::uint64_t>(a.seed) : scenario.seed;
  config.evaluations = a.evaluations;
  config.clearance_m = a.clearance_m;
  // refused before the search: a folder vlab may not replace
  std::unique_ptr<lab::OutputDir> out =
      lab::OutputDir::Create(a.out_dir.empty() ? "out/excite-" + arm_device.name : a.out_dir);
  const auto t0 = std::chrono::steady_clock::now();
  control::ExcitationResult r;
  try {
    r = control::OptimizeExcitation(model.get(), regressor.get(), qpos, q_start, limits, config);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("excite: arm '") + arm_device.name + "': " + e.what());
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  WriteOutputs(a, scenario, arm_device, tip, base, *regressor, limits, config, r, *out);
  const std::string where = out->Commit();
  PrintSummary(a, scenario, arm_device.name, *regressor, limits, config, r, seconds, where);
  if (!out->note().empty()) std::fprintf(stderr, "vlab excite: %s\n", out->note().c_str());
  return 0;
}

}  // namespace vlab::cli::excite

namespace vlab::cli {

Subcommand AddExciteCommand(CLI::App& app) {
  auto args = std::make_shared<excite::ExciteArgs>();
  CLI::App* cmd = app.add_subcommand(
      "excite",
      "An excitation trajectory for identifying an arm's dynamics: a finite Fourier series per joint, optimised for "
      "the condition number of the regressor within the joints' range, speed and acceleration limits and clear of "
      "the scene. Writes DIR/excite.lua (a task: movej to the start pose, then servoj once per period), "
      "DIR/excite.yaml (a scenario that runs it in the lab) and DIR/excite.json; exit 2 on bad input (nothing "
      "written)");
  cmd->add_option("SCENARIO", args->scenario, "Scenario with the arm (its scene, joints, initial pose, max_velocity)")
      ->required();
  cmd->add_option("--arm", args->arm, "The arm device (default: the scenario's only arm)");
  cmd->add_option("--tip", args->tip,
                  "Site at the arm's tool flange, for the task (default: the scenario's task program of the arm, "
                  "else 'tool')");
  cmd->add_option("--harmonics", args->harmonics, "Harmonics per joint, 2 ... 50 (default 5)");
  cmd->add_option("--period", args->period_s,
                  "Period of the series, s: a whole number of the scenario's control periods (default 10)");
  cmd->add_option("--cycles", args->cycles, "Periods the task runs, 1 ... 1000 (default 3)");
  cmd->add_option("--seed", args->seed, "Seed of the search (default: the scenario's seed)");
  cmd->add_option("--evaluations", args->evaluations, "Evaluations of the criterion, 4 ... 1e6 (default 1600)");
  cmd->add_option("--clearance", args->clearance_m,
                  "Distance the arm keeps from the scene and between its links, m (default 0.01)");
  cmd->add_option("--out", args->out_dir, "Output folder (default out/excite-ARM); replaced only as vlab run's");
  cmd->add_flag("-q,--quiet", args->quiet, "No per-joint table");
  return {cmd, [args] { return WithErrorReport([&] { return excite::Excite(*args); }); }};
}

}  // namespace vlab::cli
