// What the tests of the devices that drive an arm (kinds point and tool,
// src/lab/devices/device_arm_chain.h) share: the PA10 of scenes/pa10.xml as an
// arm device in its ready pose, a rig that steps it with its driving device as
// the lab's run loop does, and a scenario of that arm whose setup error is read.
#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_kinds.h"
#include "lab/run/lab_command_writer.h"
#include "lab/run/lab_runner.h"
#include "test_util.h"

namespace vlab::lab::arm_driver_rig {

inline constexpr double kPeriod = 0.01;  // s: 10 physics steps of 1 ms

/// The index of the log column `name` of `device`, -1 when it has none.
inline int ColumnOf(const Device& device, const std::string& name) {
  const std::vector<std::string> columns = device.Columns();
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
}

/// The arm device pa10 on the PA10's seven joints, starting in the ready pose
/// (tool down), velocity limits 180 deg/s.
inline DeviceConfig ArmConfig() {
  auto p = std::make_shared<ArmParams>();
  p->joints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
  p->actuators = p->joints;                                 // the motors have the joints' names
  p->initial = {0, 0.523599, 0, 1.047198, 0, 1.570796, 0};  // ready: tool down
  p->max_velocity = std::vector<double>(7, 3.1416);
  return DeviceConfig{"pa10", bridge::DeviceKind::kArm, "test.yaml:1", 0, std::move(p)};
}

/// The arm and a device that drives it, on a model and data the test fixture
/// owns (scenes/pa10.xml). Start makes both and resets them in the ready pose;
/// Period steps one control period as the lab's run loop does.
struct ArmDriverRig {
  mjModel* model;
  mjData* data;
  std::unique_ptr<SimArm> arm;
  std::unique_ptr<Device> driver;
  int site;  // the site "tool"

  ArmDriverRig(mjModel* m, mjData* d) : model(m), data(d), site(mj_name2id(m, mjOBJ_SITE, "tool")) {}

  void Start(const DeviceConfig& driver_config) {
    arm = SimArm::Create({model, kPeriod, 1, "pa10.xml"}, ArmConfig());
    driver = MakeDevice({model, kPeriod, 1, "pa10.xml"}, driver_config);
    driver->Bind({arm.get(), driver.get()});
    mj_resetData(model, data);
    arm->SetInitialState(*data);
    mj_forward(model, data);
    arm->Start(*data);
    driver->Reset(*data);
  }
  void Period() {
    CommandPeriod period;  // the driver writes its arm's command as a command source of the lab's run does
    period.t_s = data->time;
    period.data = data;
    std::string failure;
    driver->command_writer()->Write(period, &failure);
    for (int i = 0; i < 10; ++i) {
      mj_step1(model, data);
      arm->Actuate(*data, 0.001);
      mj_step2(model, data);
    }
    mj_forward(model, data);  // positions of the state reached, for exact comparisons
    driver->Sample(*data, data->time);
  }
  std::vector<double> State() const {
    std::vector<double> s;
    driver->State(&s);
    return s;
  }
  Eigen::Vector3d Tool() const { return Eigen::Map<const Eigen::Vector3d>(data->site_xpos + 3 * site); }
  Eigen::Matrix3d ToolR() const {
    return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(data->site_xmat + 9 * site);
  }
};

/// The InputError text of Lab::Create for a scenario of scenes/pa10.xml (0.1 s,
/// 10 ms periods) with the arm device pa10 and then the device lines `rest`,
/// written into `dir`; "" when it raises none.
inline std::string Pa10ScenarioError(const vlab::testing::TempDir& dir, const std::string& rest) {
  const std::string head = std::string("scene: ") + VLAB_SOURCE_DIR +
                           "/scenes/pa10.xml\nduration: 0.1\n"
                           "control_period: 0.01\ndevices:\n"
                           "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2]}\n";
  vlab::testing::WriteFile(dir.path() + "/s.yaml", head + rest);
  try {
    Lab::Create(LoadScenario(dir.path() + "/s.yaml"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace vlab::lab::arm_driver_rig
