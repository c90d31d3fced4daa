// `input: reference`: the rollout's input side when the arms ran their own servos. Each
// workspace holds one lab::SimArm per arm device, made from the scenario's device config and
// bound to the workspace's model, so the replay runs the very servo the lab runs (Command:
// modes, refusals, the rate feed-forward of position commands; Actuate: the PD law, the
// following-error window, the bias feed-forward from the world or the servo's own model,
// torque clipping, encoder sensing) rather than a second copy of its law. The parameters
// reach it through the model (the world's bias forces and joint inertia) and Tune (the gain
// parameters); the gains are made by the arm's Start at the scenario's initial pose, as the
// lab makes them.
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/core_errors.h"
#include "identify/identify_problem.h"
#include "lab/outputs/lab_log.h"
#include "scene/scene_csv.h"

namespace vlab::identify {

void Problem::ReadCommands(const scene::CsvTable& table, const std::string& file, int steps, Log* log) const {
  const int rows = static_cast<int>(table.rows.size());
  log->mode.resize(rows, static_cast<int>(arms_.size()));
  log->command.resize(rows, static_cast<int>(joints_.size()));
  auto column = [&](const std::string& name) {
    const int c = table.Column(name);
    if (c < 0) {
      throw InputError("log '" + file + "': no column '" + name +
                       "' (input: reference replays every arm's recorded commands, NAME.cmd_mode and "
                       "NAME.cmd.JOINT: the arm's log_command: true logs them)");
    }
    return c;
  };
  for (std::size_t a = 0; a < arms_.size(); ++a) {
    const Arm& arm = arms_[a];
    const std::string mode_name = arm.config.name + ".cmd_mode";
    const int mode = column(mode_name);
    std::vector<int> value(arm.joints);
    for (int j = 0; j < arm.joints; ++j) value[j] = column(arm.config.name + ".cmd." + joints_[arm.first + j].name);
    for (int r = 0; r < rows; ++r) {
      const std::vector<double>& row = table.rows[r];
      const double m = row[mode];
      if (!(m == 0 || m == 1 || m == 2 || m == 3)) {
        throw InputError("log '" + file + "': row " + std::to_string(r + 2) + ": column '" + mode_name + "' is " +
                         lab::FormatDouble(m) + ", not a command mode (0 hold, 1 position, 2 velocity, 3 torque)");
      }
      log->mode(r, static_cast<int>(a)) = m;
      for (int j = 0; j < arm.joints; ++j) {
        const double v = row[value[j]];
        if (!std::isfinite(v)) {
          throw InputError("log '" + file + "': row " + std::to_string(r + 2) + ": column '" + table.columns[value[j]] +
                           "' is not a finite number");
        }
        log->command(r, arm.first + j) = v;
      }
    }
  }
  // the servo's position reference at each row. Hold and position modes log it; velocity mode
  // integrates it from the reference it took over, step by step as the servo does (the
  // following-error window aside); torque mode makes it follow the joint (NaN: unknown). Before
  // the first row the arm held its start: the first row's measured position stands for it.
  const double timestep = model_->opt.timestep;
  log->reference.resize(rows, static_cast<int>(joints_.size()));
  for (std::size_t a = 0; a < arms_.size(); ++a) {
    const Arm& arm = arms_[a];
    for (int j = 0; j < arm.joints; ++j) {
      const int c = arm.first + j;
      for (int r = 0; r < rows; ++r) {
        const auto m = static_cast<bridge::ArmMode>(static_cast<int>(log->mode(r, static_cast<int>(a))));
        double ref = std::numeric_limits<double>::quiet_NaN();
        if (m == bridge::ArmMode::kHold || m == bridge::ArmMode::kPosition) {
          ref = log->command(r, c);
        } else if (m == bridge::ArmMode::kVelocity) {
          ref = r > 0 ? log->reference(r - 1, c) : log->q(0, c);
          for (int s = 0; s < steps; ++s) ref += log->command(r, c) * timestep;
        }
        log->reference(r, c) = ref;
      }
    }
  }
}

void Problem::TuneServos(const std::vector<double>& values, Workspace& ws) const {
  // the lab's start: the scenario's initial state, then each arm's Start makes its gains from
  // the joints' inertia there (kp = H_ii w^2, kd = 2 zeta H_ii w)
  const mjModel* m = ws.model.get();
  mjData* d = ws.data.get();
  mj_resetData(m, d);
  std::copy(qpos_init_.begin(), qpos_init_.end(), d->qpos);
  mj_forward(m, d);
  for (std::size_t a = 0; a < arms_.size(); ++a) {
    const Arm& arm = arms_[a];
    const lab::ServoConfig& servo = arm.config.ParamsAs<lab::ArmParams>().servo;
    ws.arms[a]->Tune(arm.bandwidth >= 0 ? values[arm.bandwidth] : servo.bandwidth_hz,
                     arm.damping >= 0 ? values[arm.damping] : servo.damping_ratio);
    ws.arms[a]->Start(*d);
  }
}

void Problem::StartServos(const Window& win, Workspace& ws) const {
  // the servo as the period that ends at the window's first row left it: the command in force
  // there and the reference it holds (its rate is the next command's to set)
  const Log& log = logs_[win.log];
  const mjData* d = ws.data.get();
  const int row = win.first;
  for (std::size_t a = 0; a < arms_.size(); ++a) {
    const Arm& arm = arms_[a];
    Eigen::VectorXd q_ref(arm.joints);
    for (int j = 0; j < arm.joints; ++j) {
      // the reference at the row (ReadCommands); where it is unknown (torque mode, or velocity
      // mode after it), the start's position
      const double ref = log.reference(row, arm.first + j);
      q_ref[j] = std::isfinite(ref) ? ref : d->qpos[joints_[arm.first + j].qpos];
    }
    ws.arms[a]->Resume(*d, q_ref);
    // the row's command in force: its mode, and the position the next one's rate counts from
    CommandServos(log, row, ws, static_cast<int>(a));
  }
}

void Problem::CommandServos(const Log& log, int row, Workspace& ws, int only) const {
  for (std::size_t a = 0; a < arms_.size(); ++a) {
    if (only >= 0 && static_cast<int>(a) != only) continue;
    const Arm& arm = arms_[a];
    ws.command.mode = static_cast<bridge::ArmMode>(static_cast<int>(log.mode(row, static_cast<int>(a))));
    ws.command.value = log.command.row(row).segment(arm.first, arm.joints).transpose();
    // a command the arm refuses (a position beyond the joint's range...) leaves the previous
    // one in force, as on the arm
    ws.arms[a]->Command(ws.command);
  }
}

void Problem::StepWithServos(Workspace& ws) const {
  // the lab's step: the servos act between its two halves, on the state after the first
  const mjModel* m = ws.model.get();
  mjData* d = ws.data.get();
  mj_step1(m, d);
  for (const auto& arm : ws.arms) arm->Actuate(*d, m->opt.timestep);
  mj_step2(m, d);
}

}  // namespace vlab::identify
