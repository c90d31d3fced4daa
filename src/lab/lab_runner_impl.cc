#include "lab/lab_runner_impl.h"

#include <algorithm>

#include "core/core_errors.h"

namespace vlab::lab {

void Lab::Impl::ResetData(mjData* d) const {
  if (keyframe < 0) {
    mj_resetData(model.get(), d);
  } else {
    mj_resetDataKeyframe(model.get(), d, keyframe);
    d->time = 0;  // the run's time starts at 0 whatever the keyframe's time
  }
  if (randomizer) randomizer->Apply(model.get(), d);
}

void Lab::Impl::ResetState() {
  mjData* d = data.get();
  ResetData(d);
  for (const auto& dev : devices) dev->SetInitialState(*d);
  mj_forward(model.get(), d);
  // the servos hold from the first instant: recompute forces with their torques,
  // so the sensors start settled on the load of an arm at rest
  for (auto& dev : devices) dev->Start(*d);
  mj_forward(model.get(), d);
  for (auto& dev : devices) dev->Reset(*d);
}

void Lab::Impl::WriteRow(double time_s, std::vector<double>& row) const {
  double* out = row.data();
  *out++ = time_s;
  for (const Device* dev : log_order) {
    dev->Row(*data, out);
    out += dev->ColumnCount();
  }
}

void Lab::Impl::RunController(double t, const RunOptions& options, std::size_t* replay_at, RunResult* result,
                              double* columns) {
  const int n = controller_arm->dof();
  const std::size_t width = 1 + n + controller_columns;
  bridge::ArmCommand& cmd = controller_command;
  if (options.replay) {
    // the recorded command and columns instead of the controller's work
    if (*replay_at + width > options.replay->controller.size()) {
      throw std::runtime_error("replay: the recording is shorter than this run");
    }
    const double* r = options.replay->controller.data() + *replay_at;
    cmd.mode = static_cast<bridge::ArmMode>(static_cast<int>(r[0]));
    cmd.value = Eigen::Map<const Eigen::VectorXd>(r + 1, n);
    std::copy(r + 1 + n, r + width, columns);
    *replay_at += width;
    return;
  }
  controller->Update(t, controller_arm->state(), &cmd, columns);
  if (options.record) {
    std::vector<double>& rec = result->recording.controller;
    rec.push_back(static_cast<double>(static_cast<int>(cmd.mode)));
    for (int i = 0; i < n; ++i) rec.push_back(i < cmd.value.size() ? cmd.value[i] : 0.0);
    rec.insert(rec.end(), columns, columns + (width - 1 - n));
  }
}

std::unique_ptr<LabBridge> Lab::Impl::MakeBridge(const BridgeOptions& options, const std::string& clock_name) {
  std::unique_ptr<LabBridge> bridge = LabBridge::Create(scenario, options, device_ptrs, clock_name);
  if (task) {
    for (const ServedDevice& sd : bridge->Devices()) {
      for (const std::string& arm : task->arms()) {
        if (sd.name == arm) {
          throw InputError(scenario.controller.where + ": controller: arm '" + sd.name +
                           "' is served over UDP and commanded by a task program: one owner at a time "
                           "(remove the device's port)");
        }
      }
    }
  }
  if (controller) {
    for (const ServedDevice& sd : bridge->Devices()) {
      if (sd.name == scenario.controller.arm) {
        throw InputError(scenario.controller.where + ": controller: arm '" + sd.name +
                         "' is served over UDP and commanded by the built-in controller: one owner at a time "
                         "(remove the controller, or the device's port)");
      }
    }
  }
  return bridge;
}

bool Lab::Impl::HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left) {
  bool changed = false;
  bridge::SimCommandMsg c;
  while (sim && bridge.TakeCommand(*sim) && sim->TakeOp(&c)) {
    changed = true;
    switch (static_cast<bridge::SimOp>(c.op)) {
      case bridge::SimOp::kReset:
        ResetState();
        break;
      case bridge::SimOp::kPause:
        *paused = true;
        *steps_left = -1;
        break;
      case bridge::SimOp::kResume:
        *paused = false;
        *steps_left = -1;
        clock.set_factor(clock.factor());  // realtime: pace from now, no catch-up burst
        break;
      case bridge::SimOp::kStep:
        *paused = false;
        *steps_left = static_cast<long>(c.arg);
        clock.set_factor(clock.factor());
        break;
      case bridge::SimOp::kSetRealtimeFactor:
        clock.set_factor(c.arg);
        break;
    }
  }
  return changed;
}

}  // namespace vlab::lab
