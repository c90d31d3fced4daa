// The lab's private state (Lab::Impl), shared by lab_runner.cc (creation and
// the run loop) and lab_runner_impl.cc (reset, log rows, controller periods,
// the bridge, the sim device). Not a public header.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_messages.h"
#include "core/core_clock.h"
#include "core/core_mujoco.h"
#include "lab/devices/device.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_sim.h"
#include "lab/lab_bridge.h"
#include "lab/lab_controller.h"
#include "lab/lab_runner.h"
#include "lab/lab_task.h"

namespace vlab::lab {

struct Lab::Impl {
  Scenario scenario;
  ModelPtr model;
  DataPtr data;
  int steps_per_period = 1;
  std::vector<std::unique_ptr<Device>> devices;  // every device, in scenario order
  std::vector<Device*> device_ptrs;               // the same, as the bridge and Bind take them
  std::vector<Device*> log_order;                 // by log rank, then scenario order
  SimControl* sim = nullptr;                      // the sim device, if the scenario has one
  std::unique_ptr<Controller> controller;
  SimArm* controller_arm = nullptr;
  int keyframe = -1;  // scene keyframe of every reset (-1: qpos0)
  std::unique_ptr<Randomizer> randomizer;  // the seeded layout every reset puts back, or null
  std::size_t controller_columns = 0;  // log columns the controller writes
  std::vector<std::string> columns;
  bridge::ArmCommand controller_command;  // the built-in controller's command of the period
  std::unique_ptr<TaskController> task;    // the task-language controller (type task), or null

  void ResetState();
  /// mj_resetData, or mj_resetDataKeyframe of the scenario's keyframe (at time 0); then
  /// the randomised layout, if the scenario has one.
  void ResetData(mjData* d) const;
  void WriteRow(double time_s, std::vector<double>& row) const;
  /// Binds every served device (cameras too); throws InputError.
  std::unique_ptr<LabBridge> MakeBridge(const BridgeOptions& options, const std::string& clock_name);
  // applies the sim device's commands; true when something changed
  bool HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left);
  // one controller period: computed (and recorded), or replayed from a recording
  void RunController(double t, const RunOptions& options, std::size_t* replay_at, RunResult* result,
                     double* columns);
};

}  // namespace vlab::lab
