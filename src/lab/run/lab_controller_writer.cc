#include "lab/run/lab_controller_writer.h"

#include <algorithm>
#include <stdexcept>

#include "lab/run/lab_runner.h"

namespace vlab::lab {

ControllerWriter::ControllerWriter(const mjModel* model, const ControllerConfig& config, SimArm& arm)
    : arm_(arm), where_(config.where), controller_(MakeController(model, config, arm.joint_names(), arm.state())),
      columns_(controller_->Columns().size()) {}

Claim ControllerWriter::ClaimOf(const ControllerConfig& config) {
  return {config.arm, "the built-in controller", config.where};
}

std::vector<Claim> ControllerWriter::Claims() const { return {{arm_.name(), "the built-in controller", where_}}; }

bool ControllerWriter::Restart(const CommandPeriod& period, std::string* failure) {
  (void)failure;
  replay_at_ = 0;  // a replay starts at the recording's start
  Update(period);
  return true;
}

bool ControllerWriter::Write(const CommandPeriod& period, std::string* failure) {
  (void)failure;
  if (period.k > 0) Update(period);  // period 0's command is row 0's (Restart)
  arm_.Command(command_);
  return true;
}

void ControllerWriter::Update(const CommandPeriod& period) {
  const int n = arm_.dof();
  const std::size_t width = 1 + n + columns_;
  const RunOptions& options = *period.options;
  if (options.replay) {
    // the recorded command and columns instead of the controller's work
    if (replay_at_ + width > options.replay->controller.size()) {
      throw std::runtime_error("replay: the recording is shorter than this run");
    }
    const double* r = options.replay->controller.data() + replay_at_;
    command_.mode = static_cast<bridge::ArmMode>(static_cast<int>(r[0]));
    command_.value = Eigen::Map<const Eigen::VectorXd>(r + 1, n);
    std::copy(r + 1 + n, r + width, period.columns);
    replay_at_ += width;
    return;
  }
  controller_->Update(period.t_s, arm_.state(), &command_, period.columns);
  if (options.record) {
    std::vector<double>& rec = period.result->recording.controller;
    rec.push_back(static_cast<double>(static_cast<int>(command_.mode)));
    for (int i = 0; i < n; ++i) rec.push_back(i < command_.value.size() ? command_.value[i] : 0.0);
    rec.insert(rec.end(), period.columns, period.columns + (width - 1 - n));
  }
}

}  // namespace vlab::lab
