#include "lab/run/lab_runner.h"

#include <algorithm>
#include <cmath>

#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_kinds.h"
#include "lab/outputs/lab_log.h"
#include "lab/run/lab_external.h"
#include "lab/run/lab_runner_impl.h"

namespace vlab::lab {

namespace {

// 64-bit mix of the scenario seed and a device name: each device gets its own stream
std::uint64_t DeviceSeed(std::uint64_t seed, const std::string& name) {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a
  for (unsigned char c : name) h = (h ^ c) * 1099511628211ULL;
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (h | 1);  // splitmix64 finaliser
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace

Lab::Lab(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Lab::~Lab() = default;
const mjModel* Lab::model() const { return impl_->model.get(); }
const Scenario& Lab::scenario() const { return impl_->scenario; }
std::vector<std::string> Lab::Columns() const { return impl_->columns; }
std::vector<double> Lab::FinalQpos() const {
  return std::vector<double>(impl_->data->qpos, impl_->data->qpos + impl_->model->nq);
}

std::unique_ptr<Lab> Lab::Create(const Scenario& scenario) {
  auto impl = std::make_unique<Impl>();
  impl->scenario = scenario;
  try {
    impl->model = LoadModel(scenario.scene);
  } catch (const InputError& e) {
    // name the scenario's file, line and key too (a scenario built in code has no position)
    if (scenario.scene_where.empty()) throw;
    throw InputError(scenario.scene_where + ": scene: " + e.what());
  }
  const mjModel* m = impl->model.get();
  impl->data = MakeData(m);
  if (!scenario.keyframe.empty()) {
    impl->keyframe = mj_name2id(m, mjOBJ_KEY, scenario.keyframe.c_str());
    if (impl->keyframe < 0) {
      throw InputError(scenario.keyframe_where + ": keyframe: the scene '" + scenario.scene + "' has no keyframe '" +
                       scenario.keyframe + "'");
    }
  }

  if (!scenario.randomize.bodies.empty()) {
    impl->randomizer = Randomizer::Create(m, scenario.randomize, scenario.seed);
  }

  // a run simulates at least one period
  if (std::lround(scenario.duration_s / scenario.control_period_s) < 1) {
    throw InputError(scenario.file + ": duration " + FormatDouble(scenario.duration_s) +
                     " s is shorter than half a control period (" + FormatDouble(scenario.control_period_s) +
                     " s): nothing would be simulated");
  }
  // the control period must be a whole number of physics steps
  const double ts = m->opt.timestep;
  const double ratio = scenario.control_period_s / ts;
  impl->steps_per_period = static_cast<int>(std::lround(ratio));
  if (impl->steps_per_period < 1 || std::abs(ratio - impl->steps_per_period) > 1e-9 * ratio) {
    throw InputError(scenario.file + ": control_period " + FormatDouble(scenario.control_period_s) +
                     " s is not a whole multiple of the scene timestep " + FormatDouble(ts) + " s");
  }

  // every device by its kind's factory, then bound to the others (a point device to its arm)
  for (const DeviceConfig& device : scenario.devices) {
    const DeviceContext context{m, scenario.control_period_s, DeviceSeed(scenario.seed, device.name), scenario.scene};
    impl->devices.push_back(MakeDevice(context, device));
    impl->device_ptrs.push_back(impl->devices.back().get());
    if (SimControl* sim = impl->devices.back()->sim_control()) impl->sim = sim;
  }
  for (Device* device : impl->device_ptrs) device->Bind(impl->device_ptrs);
  impl->ClaimDriven();
  impl->log_order = impl->device_ptrs;
  std::stable_sort(impl->log_order.begin(), impl->log_order.end(),
                   [](const Device* a, const Device* b) { return a->log_rank() < b->log_rank(); });

  impl->columns.push_back("time");
  for (const Device* device : impl->log_order) {
    for (auto& c : device->Columns()) impl->columns.push_back(c);
  }

  impl->ResetState();
  const ControllerConfig& cc = scenario.controller;
  if (cc.type == ControllerType::kExternal) {
    ExpandCommand(cc.command, CommandValues(scenario, {}), cc.where);  // placeholders checked now
  } else if (cc.type == ControllerType::kTask) {
    for (const Claim& claim : TaskController::ClaimsOf(scenario)) impl->claims.Add(claim);  // before the scripts load
    impl->task = TaskController::Create(m, scenario, impl->device_ptrs);
    impl->controller_columns = impl->task->Columns().size();
    for (auto& c : impl->task->Columns()) impl->columns.push_back(c);
  } else if (cc.type != ControllerType::kNone) {
    SimArm* arm = nullptr;
    for (Device* device : impl->device_ptrs) {
      if (device->name() == cc.arm) arm = device->arm();
    }
    if (!arm) throw InputError(cc.where + ": controller.arm: no arm device named '" + cc.arm + "'");
    impl->claims.Add(ControllerWriter::ClaimOf(cc));
    impl->controller = std::make_unique<ControllerWriter>(m, cc, *arm);
    impl->controller_columns = impl->controller->Columns().size();
    for (auto& c : impl->controller->Columns()) impl->columns.push_back(c);
  }
  // the command sources in the order they write each period (the wire's bridge comes first, per run)
  if (impl->controller) impl->writers.push_back(impl->controller.get());
  if (impl->task) impl->writers.push_back(impl->task.get());
  for (Device* device : impl->device_ptrs) {
    if (CommandWriter* writer = device->command_writer()) impl->writers.push_back(writer);
  }
  // the capability lists, asked once (device_capabilities.h)
  for (Device* device : impl->device_ptrs) {
    if (StepHooks* hooks = device->step_hooks()) impl->step_hooks.push_back(hooks);
    if (RenderedOutput* output = device->rendered_output()) impl->rendered.push_back(output);
    if (LogReader* reader = device->log_reader()) impl->log_readers.push_back(reader);
  }
  for (LogReader* reader : impl->log_readers) reader->BindLog(impl->columns);
  return std::unique_ptr<Lab>(new Lab(std::move(impl)));
}

void Lab::InitialState(mjData* d) const {
  impl_->ResetData(d);
  for (const auto& device : impl_->devices) device->SetInitialState(*d);
  mj_forward(impl_->model.get(), d);
}

std::vector<ServedDevice> Lab::Describe(const BridgeOptions& options, std::optional<ClockMode> clock) const {
  const std::string name = ClockModeName(clock.value_or(impl_->scenario.clock));
  std::unique_ptr<LabBridge> bridge = impl_->MakeBridge(options, name);
  return bridge->Devices();  // the bridge's end frees the ports
}

}  // namespace vlab::lab
