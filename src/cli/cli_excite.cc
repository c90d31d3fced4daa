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
#include <memory>
#include <string>
#include <vector>

#include "cli/cli_commands.h"
#include "cli/cli_excite.h"
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
  // the task's chain: the scenario's task program of this arm, else --tip (default tool) and
  // --base (default world)
  std::string tip = a.tip, base = a.base;
  if (scenario.controller.type == lab::ControllerType::kTask) {
    for (const auto& p : scenario.controller.programs) {
      if (p.robot != arm_device.name) continue;
      if (tip.empty()) tip = p.tip_site;
      if (base.empty()) base = p.base_body;
    }
  }
  if (tip.empty()) tip = "tool";
  if (base.empty()) base = "world";
  std::unique_ptr<control::RobotModel> chain;
  try {
    chain = control::RobotModel::Create(model.get(), {base, tip});
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("excite: the task's chain (--base ") + base + ", --tip " + tip + "): " + e.what());
  }
  if (chain->joint_names() != arm.joints) {
    throw InputError("excite: the chain from body '" + base + "' to site '" + tip + "' is not the joints of arm '" +
                     arm_device.name + "' in order: give --base and --tip");
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
  cmd->add_option("--base", args->base,
                  "Body the task's chain starts from (default: the scenario's task program of the arm, else 'world')");
  cmd->add_option("--harmonics", args->harmonics, "Harmonics per joint, 2 ... 50 (default 5)");
  cmd->add_option("--period", args->period_s,
                  "Period of the series, s: a whole number of the scenario's control periods (default 10)");
  cmd->add_option("--cycles", args->cycles, "Periods the task runs, 1 ... 1000 (default 3)");
  cmd->add_option("--seed", args->seed, "Seed of the search, >= 0 (default: the scenario's seed)");
  cmd->add_option("--evaluations", args->evaluations, "Evaluations of the criterion, 4 ... 1e6 (default 1600)");
  cmd->add_option("--clearance", args->clearance_m,
                  "Distance the arm keeps from the scene and between its links, m (default 0.01)");
  cmd->add_option("--out", args->out_dir, "Output folder (default out/excite-ARM); replaced only as vlab run's");
  cmd->add_flag("-q,--quiet", args->quiet, "No per-joint table");
  return {cmd, [args, cmd] {
            return WithErrorReport([&] {
              if (cmd->count("--seed") > 0 && args->seed < 0) throw InputError("excite: --seed must be >= 0");
              return excite::Excite(*args);
            });
          }};
}

}  // namespace vlab::cli
