// The lab's private state (Lab::Impl), shared by lab_runner.cc (creation, the
// claims of the command sources), lab_runner_impl.cc (reset, log rows, the
// bridge and its claims, the sim device's ops) and lab_run_session.cc (one
// run: Lab::Run). Not a public header.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_messages.h"
#include "core/core_clock.h"
#include "core/core_mujoco.h"
#include "lab/devices/device.h"
#include "lab/devices/device_sim.h"
#include "lab/run/lab_bridge.h"
#include "lab/run/lab_command_writer.h"
#include "lab/run/lab_controller_writer.h"
#include "lab/run/lab_runner.h"
#include "lab/run/lab_task.h"

namespace vlab::lab {

struct Lab::Impl {
  Scenario scenario;
  ModelPtr model;
  DataPtr data;
  int steps_per_period = 1;
  std::vector<std::unique_ptr<Device>> devices;  // every device, in scenario order
  std::vector<Device*> device_ptrs;              // the same, as the bridge and Bind take them
  std::vector<Device*> log_order;                // by log rank, then scenario order
  // the devices with each capability (device_capabilities.h), in scenario order, asked once at load
  std::vector<StepHooks*> step_hooks;            // every physics step: Actuate, AfterStep
  std::vector<RenderedOutput*> rendered;         // BeforeRun, Deliver, AfterPublish
  std::vector<LogReader*> log_readers;           // BindLog, LogRow
  SimControl* sim = nullptr;                     // the sim device, if the scenario has one
  std::unique_ptr<ControllerWriter> controller;  // the built-in controller (joint_pd and its kin), or null
  int keyframe = -1;                             // scene keyframe of every reset (-1: qpos0)
  std::unique_ptr<Randomizer> randomizer;        // the seeded layout every reset puts back, or null
  std::size_t controller_columns = 0;            // log columns the controller writes
  std::vector<std::string> columns;
  std::unique_ptr<TaskController> task;  // the task-language controller (type task), or null
  /// Every command source's claims but the wire's (MakeBridge checks those,
  /// once its sockets say which devices are served).
  ClaimTable claims;
  /// The command sources but the wire, in the order they write each period: the
  /// built-in controller or the task programs, then the devices that drive another.
  std::vector<CommandWriter*> writers;

  void ResetState();
  /// mj_resetData, or mj_resetDataKeyframe of the scenario's keyframe (at time 0); then
  /// the randomised layout, if the scenario has one.
  void ResetData(mjData* d) const;
  void WriteRow(double time_s, std::vector<double>& row) const;
  /// Binds every served device (cameras too) and checks the wire's claims
  /// against the others'; throws InputError.
  std::unique_ptr<LabBridge> MakeBridge(const BridgeOptions& options, const std::string& clock_name);
  /// The claims of the devices that drive another (after Bind); marks the
  /// arms they drive. Throws InputError on a second claim.
  void ClaimDriven();
  // applies the sim device's commands; true when something changed
  bool HandleSimCommands(LabBridge& bridge, Clock& clock, bool* paused, long* steps_left);
};

}  // namespace vlab::lab
