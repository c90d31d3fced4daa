#include "lab/lab_runner_impl.h"

#include <algorithm>

#include "core/core_errors.h"

namespace vlab::lab {

void Lab::Impl::ResetData(mjData* d) const {
  if (keyframe < 0) {
    mj_resetData(model.get(), d);
    return;
  }
  mj_resetDataKeyframe(model.get(), d, keyframe);
  d->time = 0;  // the run's time starts at 0 whatever the keyframe's time
}

void Lab::Impl::ResetState() {
  mjData* d = data.get();
  ResetData(d);
  for (const auto& arm : arms) arm->SetInitialPositions(*d);
  mj_forward(model.get(), d);
  for (auto& arm : arms) arm->Start(*d, scenario.control_period_s);
  // the servos hold from the first instant: recompute forces with their torques,
  // so the sensors start settled on the load of an arm at rest
  for (auto& arm : arms) arm->Actuate(*d, 0.0);
  mj_forward(model.get(), d);
  for (auto& w : wrenches) w->Reset(*d);
  for (auto& dev : devices) dev->Reset(*d);
  for (std::size_t i = 0; i < arms.size(); ++i) arms[i]->Sample(*d, d->time, &arm_states[i]);
}

void Lab::Impl::WriteRow(double time_s, std::vector<double>& row) const {
  double* out = row.data();
  *out++ = time_s;
  for (const auto& arm : arms) {
    arm->Row(*data, out);
    out += arm->ColumnCount();
  }
  for (const auto& w : wrenches) {
    w->Row(out);
    out += w->ColumnCount();
  }
  for (const auto& dev : devices) {
    dev->Row(out);
    out += dev->ColumnCount();
  }
}

void Lab::Impl::RunController(double t, const RunOptions& options, std::size_t* replay_at, RunResult* result,
                              double* columns) {
  const int a = controller_arm;
  const int n = arms[a]->dof();
  const std::size_t width = 1 + n + controller_columns;
  bridge::ArmCommand& cmd = arm_commands[a];
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
  controller->Update(t, arm_states[a], &cmd, columns);
  if (options.record) {
    std::vector<double>& rec = result->recording.controller;
    rec.push_back(static_cast<double>(static_cast<int>(cmd.mode)));
    for (int i = 0; i < n; ++i) rec.push_back(i < cmd.value.size() ? cmd.value[i] : 0.0);
    rec.insert(rec.end(), columns, columns + (width - 1 - n));
  }
}

std::unique_ptr<LabBridge> Lab::Impl::MakeBridge(const BridgeOptions& options, const std::string& clock_name) {
  std::vector<SimArm*> arm_ptrs;
  for (auto& a : arms) arm_ptrs.push_back(a.get());
  std::vector<SimWrench*> wrench_ptrs;
  for (auto& w : wrenches) wrench_ptrs.push_back(w.get());
  std::vector<SimDevice*> device_ptrs;
  for (auto& dev : devices) device_ptrs.push_back(dev.get());
  std::unique_ptr<LabBridge> bridge =
      LabBridge::Create(scenario, options, arm_ptrs, wrench_ptrs, device_ptrs, clock_name);
  const std::string server = options.server + " (MuJoCo " + MujocoVersion() + ")";
  for (auto& cam : cameras) {
    cam->Unserve();
    int port = 0;
    for (const DeviceConfig& c : scenario.devices) port = c.name == cam->name() ? c.port : port;
    const auto override_port = options.ports.find(cam->name());
    if (override_port == options.ports.end() && port == 0) continue;
    cam->Serve(options.bind, override_port != options.ports.end() ? override_port->second : port, server, clock_name);
    SimCamera* c = cam.get();
    bridge->AddPollable(c->fd(), [c] { c->PollRequests(); });  // describe replies while lockstep waits
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

std::vector<ServedDevice> Lab::Impl::ServedDevices(const LabBridge& bridge) const {
  std::vector<ServedDevice> out = bridge.Devices();
  for (const auto& cam : cameras) {
    if (!cam->served()) continue;
    const bridge::CameraServer& s = *cam->server();
    out.push_back({cam->name(), "camera", s.config().bind_address, s.port(), s.describe_json(), s.counters().endpoint});
  }
  return out;
}

bool Lab::Impl::HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left) {
  bool changed = false;
  bridge::SimCommandMsg c;
  while (bridge.TakeSimCommand(&c)) {
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
