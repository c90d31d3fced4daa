#include "lab/run/lab_task.h"

#include <cstdio>
#include <map>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
#include "lab/run/lab_runner.h"
#include "task/task_markers.h"
#include "task/task_runtime.h"

namespace vlab::lab {

namespace {

// a lab device as the task runtime sees it: its wire payloads, in process
class LabChannel final : public task::Channel {
 public:
  explicit LabChannel(Device* d) : device_(d), input_(d->command_input()) {
    nlohmann::json layout;
    if (SimArm* arm = d->arm()) {
      layout = bridge::LayoutJson(bridge::DeviceKind::kArm, arm->dof());
      joints_ = arm->joint_names();
    } else {
      const nlohmann::json facts = nlohmann::json::parse(d->DescribeFacts(), nullptr, false);
      if (facts.is_object() && facts.contains("layout")) {
        layout = facts["layout"];
      } else if (bridge::FindKindLayout(static_cast<int>(d->kind())) &&
                 bridge::FindKindLayout(static_cast<int>(d->kind()))->float64) {
        layout = bridge::LayoutJson(d->kind());
      }
    }
    if (layout.is_object()) {
      state_names_ = bridge::ExpandLayoutFields(layout.value("state", nlohmann::json::array()), device_->name());
      command_names_ = bridge::ExpandLayoutFields(layout.value("command", nlohmann::json::array()), device_->name());
    }
    if (!d->arm() && static_cast<int>(command_names_.size()) != command_length()) {
      command_names_.clear();
    }
  }
  const std::string& name() const override { return device_->name(); }
  bridge::DeviceKind kind() const override { return device_->kind(); }
  const std::vector<std::string>& state_names() const override { return state_names_; }
  const std::vector<std::string>& command_names() const override { return command_names_; }
  std::vector<std::string> joint_names() const override { return joints_; }
  // the arm's max_velocity, where its scenario entry gives one
  std::vector<double> velocity_limits() const override {
    const SimArm* arm = device_->arm();
    if (!arm || arm->max_velocity().size() == 0) return {};
    return std::vector<double>(arm->max_velocity().data(), arm->max_velocity().data() + arm->max_velocity().size());
  }
  bool Read(std::vector<double>* values) override {
    // the state datagram the device would send now, decoded as a client would
    device_->EncodeState(0, 0, 0, &scratch_, &bytes_);
    bridge::Header header;
    if (bridge::DecodePacket(bytes_.data(), bytes_.size(), &header, values) != bridge::DecodeError::kNone) {
      values->clear();
    }
    return !values->empty();
  }
  bool Write(const std::vector<double>& values, std::string* why) override {
    if (SimArm* arm = device_->arm()) {
      // an arm takes its typed command: [mode, one value per joint]
      if (static_cast<int>(values.size()) != 1 + arm->dof()) {
        *why = "expected " + std::to_string(1 + arm->dof()) + " values, got " + std::to_string(values.size());
        return false;
      }
      arm_command_.mode = static_cast<bridge::ArmMode>(static_cast<int>(values[0]));
      arm_command_.value = Eigen::Map<const Eigen::VectorXd>(values.data() + 1, arm->dof());
      if (!arm->Command(arm_command_)) {
        *why = "refused by the arm (a position beyond a joint limit, or not finite)";
        return false;
      }
      return true;
    }
    if (static_cast<int>(values.size()) != command_length()) {
      *why = "expected " + std::to_string(command_length()) + " values, got " + std::to_string(values.size());
      return false;
    }
    for (double v : values) {
      if (!std::isfinite(v)) {
        *why = "a value is not finite";
        return false;
      }
    }
    const bridge::CommandCheck check = input_->CheckCommand(values);  // (command_length() > 0: it has an input)
    if (check != bridge::CommandCheck::kAccept) {
      *why = "refused by the device's command check (code " + std::to_string(static_cast<int>(check)) + ")";
      return false;
    }
    input_->Command(values);
    return true;
  }

  bool SetPayload(const bridge::ArmPayloadMsg& p, std::string* why) override {
    SimArm* arm = device_->arm();
    if (!arm) return task::Channel::SetPayload(p, why);
    return arm->SetPayload(PayloadFromWire(p), why);  // in process: from the next physics step
  }
  bool GetPayload(bridge::ArmPayloadMsg* p, std::string* why) override {
    const SimArm* arm = device_->arm();
    if (!arm) return task::Channel::GetPayload(p, why);
    *p = PayloadToWire(arm->payload());
    return true;
  }

 private:
  // payload length of its command input (0: none, or a typed one)
  int command_length() const { return input_ ? input_->command_length() : 0; }

  Device* device_;
  CommandInput* input_;  // null for an output-only device
  bridge::ArmCommand arm_command_;
  std::vector<double> scratch_;
  std::vector<unsigned char> bytes_;
  std::vector<std::string> state_names_, command_names_, joints_;
};

class LabDevices final : public task::Devices {
 public:
  LabDevices(const std::vector<Device*>& devices, const std::map<std::string, std::string>& markers) {
    for (Device* d : devices) {
      channels_.emplace(d->name(), std::make_unique<LabChannel>(d));
      names_.push_back(d->name());
    }
    // vision programs beside the lab: connected when a script first asks (markers(NAME)),
    // when the lab serves the camera they read; tried for up to 10 s
    for (const auto& [name, endpoint] : markers) {
      markers_.emplace(name, std::make_unique<task::UdpMarkers>(name, endpoint, 10.0));
    }
  }
  task::Channel* Find(const std::string& name) override {
    const auto it = channels_.find(name);
    return it == channels_.end() ? nullptr : it->second.get();
  }
  void SetIdle(const std::function<void()>& idle) {
    for (auto& [name, m] : markers_) m->set_idle(idle);
  }
  task::MarkerChannel* FindMarkers(const std::string& name) override {
    const auto it = markers_.find(name);
    return it == markers_.end() ? nullptr : it->second.get();
  }
  std::vector<std::string> Names() const override { return names_; }

 private:
  std::map<std::string, std::unique_ptr<LabChannel>> channels_;
  std::map<std::string, std::unique_ptr<task::UdpMarkers>> markers_;
  std::vector<std::string> names_;
};

}  // namespace

struct TaskController::Impl {
  const mjModel* model = nullptr;
  task::RuntimeConfig config;
  std::unique_ptr<LabDevices> devices;
  std::unique_ptr<task::Runtime> runtime;
  std::vector<Claim> claims;  // each program's robot arm
  bool used = false;          // Update ran since the runtime was made
  // where the programs' print() lines go: the run's result (task.log), and stdout unless quiet
  RunResult* result = nullptr;
  bool quiet = false;
  void Print(const std::string& who, double t, const std::string& text) {
    char head[160];
    std::snprintf(head, sizeof head, "[%s t=%.3f] ", who.c_str(), t);
    if (result) result->task_output += head + text + "\n";
    if (quiet) return;
    std::printf("%s%s\n", head, text.c_str());
    std::fflush(stdout);
  }
};

TaskController::TaskController(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TaskController::~TaskController() = default;

std::unique_ptr<TaskController> TaskController::Create(const mjModel* model, const Scenario& scenario,
                                                       const std::vector<Device*>& devices) {
  auto impl = std::make_unique<Impl>();
  impl->devices = std::make_unique<LabDevices>(devices, scenario.controller.markers);
  task::RuntimeConfig rc;
  rc.period_s = scenario.control_period_s;
  rc.seed = scenario.seed;
  rc.instruction_budget = scenario.controller.instruction_budget;
  // the scenario's clock (vlab serve --clock may override it: realtime then still holds)
  rc.markers_hold = scenario.clock != ClockMode::kRealtime;
  Impl* raw = impl.get();
  rc.print = [raw](const std::string& who, double t, const std::string& text) { raw->Print(who, t, text); };
  for (const TaskProgramEntry& e : scenario.controller.programs) {
    task::ProgramConfig p;
    p.script = e.script;
    p.robot = e.robot;
    p.base_body = e.base_body;
    p.tip_site = e.tip_site;
    p.wrench = e.wrench;
    p.where = e.where;
    p.params = e.params;
    rc.programs.push_back(p);
  }
  impl->claims = ClaimsOf(scenario);
  impl->model = model;
  impl->config = rc;
  impl->runtime = task::Runtime::Create(rc, model, impl->devices.get());
  return std::unique_ptr<TaskController>(new TaskController(std::move(impl)));
}

std::vector<std::string> TaskController::Columns() const { return impl_->runtime->Columns(); }
std::vector<Claim> TaskController::ClaimsOf(const Scenario& scenario) {
  std::vector<Claim> claims;
  for (const TaskProgramEntry& e : scenario.controller.programs) {
    if (!e.robot.empty()) claims.push_back({e.robot, "task program '" + e.script + "'", e.where});
  }
  return claims;
}
std::vector<Claim> TaskController::Claims() const { return impl_->claims; }
void TaskController::Restart() {
  if (!impl_->used) return;
  impl_->runtime = task::Runtime::Create(impl_->config, impl_->model, impl_->devices.get());
  impl_->used = false;
}
bool TaskController::Restart(const CommandPeriod& period, std::string* failure) {
  Restart();  // a lab run again starts its programs anew
  impl_->result = period.result;
  impl_->quiet = period.options && period.options->quiet;
  if (impl_->result) impl_->result->task_output.clear();
  return Step(period, failure);
}
bool TaskController::Write(const CommandPeriod& period, std::string* failure) {
  return period.k == 0 || Step(period, failure);  // period 0 ran with row 0 (Restart)
}
bool TaskController::Step(const CommandPeriod& period, std::string* failure) {
  impl_->used = true;
  if (impl_->runtime->Step(period.t_s, period.columns)) return true;
  *failure = impl_->runtime->error();  // a script error ends the run (the log keeps the periods before)
  // task.log ends with the error's first line (the traceback is on stderr)
  if (impl_->result) {
    char head[64];
    std::snprintf(head, sizeof head, "[error t=%.3f] ", period.t_s);
    impl_->result->task_output += head + failure->substr(0, failure->find('\n')) + "\n";
  }
  return false;
}
void TaskController::SetIdle(std::function<void()> idle) { impl_->devices->SetIdle(idle); }

}  // namespace vlab::lab
