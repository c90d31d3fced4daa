// The lab's private state (Lab::Impl), shared by lab_runner.cc (creation and
// the run loop) and lab_runner_impl.cc (reset, log rows, controller periods,
// the bridge, the sim device). Not a public header.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_messages.h"
#include "lab/lab_arm_device.h"
#include "lab/lab_bridge.h"
#include "lab/lab_camera_device.h"
#include "core/core_clock.h"
#include "lab/lab_controller.h"
#include "lab/lab_device.h"
#include "core/core_mujoco.h"
#include "lab/lab_runner.h"
#include "lab/lab_wrench_device.h"

namespace vlab::lab {

struct Lab::Impl {
  Scenario scenario;
  ModelPtr model;
  DataPtr data;
  int steps_per_period = 1;
  std::vector<std::unique_ptr<SimArm>> arms;
  std::vector<std::unique_ptr<SimWrench>> wrenches;
  std::vector<std::unique_ptr<SimDevice>> devices;  // base, feet, imu, ...
  std::vector<std::unique_ptr<SimCamera>> cameras;
  std::unique_ptr<Controller> controller;
  int controller_arm = -1;
  int keyframe = -1;  // scene keyframe of every reset (-1: qpos0)
  std::size_t controller_columns = 0;  // log columns the controller writes
  std::vector<std::string> columns;
  std::vector<bridge::ArmState> arm_states;
  std::vector<bridge::ArmCommand> arm_commands;

  void ResetState();
  /// mj_resetData, or mj_resetDataKeyframe of the scenario's keyframe (at time 0).
  void ResetData(mjData* d) const;
  void WriteRow(double time_s, std::vector<double>& row) const;
  /// Binds every served device (cameras too); throws InputError.
  std::unique_ptr<LabBridge> MakeBridge(const BridgeOptions& options, const std::string& clock_name);
  /// The bridge's devices and the served cameras.
  std::vector<ServedDevice> ServedDevices(const LabBridge& bridge) const;
  // applies the sim device's commands; true when something changed
  bool HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left);
  // one controller period: computed (and recorded), or replayed from a recording
  void RunController(double t, const RunOptions& options, std::size_t* replay_at, RunResult* result,
                     double* columns);
};

}  // namespace vlab::lab
