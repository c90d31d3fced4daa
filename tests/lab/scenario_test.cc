// Scenario loading: valid files parse into the right values; every kind of bad
// input is an InputError naming the file, the line and the key.
#include "lab/devices/device_arm.h"
#include "lab/devices/device_wrench.h"
#include "lab/scenario/lab_scenario.h"

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "test_util.h"

namespace vlab::lab::scenario_test {
namespace {

using vlab::testing::TempDir;
using vlab::testing::WriteFile;

// Loads `text` as a scenario file and returns the error message ("" if none).
std::string ErrorOf(const std::string& text) {
  TempDir dir;
  WriteFile(dir / "s.yaml", text);
  try {
    LoadScenario(dir / "s.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

constexpr const char* kValid = R"(
name: reach
scene: scene.xml
duration: 2.5
control_period: 0.004
seed: 42
devices:
  - name: arm
    kind: arm
    joints: [a, b]
    initial: [0.1, -0.2]
    servo: {bandwidth_hz: 8}
  - name: ft
    kind: wrench
    force_sensor: f
    torque_sensor: t
    filter: 2
    noise: false
controller:
  type: task_space
  arm: arm
  tip_site: tip
  start: 0.25
  waypoints:
    - {position: [0.1, 0.2, 0.3], rpy_deg: [180, 0, 90], duration: 1.5}
checks:
  - {name: c, signal: time, reduce: final, max: 3, from: 1}
)";

TEST(ScenarioTest, ParsesValidFile) {
  TempDir dir;
  WriteFile(dir / "s.yaml", kValid);
  const Scenario s = LoadScenario(dir / "s.yaml");
  EXPECT_EQ(s.name, "reach");
  EXPECT_EQ(s.scene, dir / "scene.xml");  // relative to the scenario file
  EXPECT_DOUBLE_EQ(s.duration_s, 2.5);
  EXPECT_DOUBLE_EQ(s.control_period_s, 0.004);
  EXPECT_EQ(s.seed, 42u);
  ASSERT_EQ(s.devices.size(), 2u);
  EXPECT_EQ(s.devices[0].ParamsAs<ArmParams>().joints, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(s.devices[0].ParamsAs<ArmParams>().actuators, s.devices[0].ParamsAs<ArmParams>().joints);  // default
  EXPECT_DOUBLE_EQ(s.devices[0].ParamsAs<ArmParams>().servo.bandwidth_hz, 8);
  EXPECT_DOUBLE_EQ(s.devices[0].ParamsAs<ArmParams>().servo.damping_ratio, 1.0);
  EXPECT_EQ(s.devices[1].ParamsAs<WrenchParams>().filter, 2);
  EXPECT_FALSE(s.devices[1].ParamsAs<WrenchParams>().noise);
  ASSERT_EQ(s.controller.cartesian.size(), 1u);
  // rpy (180, 0, 90): x axis of the frame -> world y, z axis -> world -z
  const Eigen::Matrix3d R = s.controller.cartesian[0].orientation_W.toRotationMatrix();
  EXPECT_NEAR((R.col(0) - Eigen::Vector3d::UnitY()).norm(), 0, 1e-12);
  EXPECT_NEAR((R.col(2) + Eigen::Vector3d::UnitZ()).norm(), 0, 1e-12);
  ASSERT_EQ(s.checks.size(), 1u);
  EXPECT_EQ(s.checks[0].reduce, Reduce::kFinal);
  EXPECT_DOUBLE_EQ(s.checks[0].from_s, 1.0);
}

TEST(ScenarioTest, NameDefaultsToFileStem) {
  TempDir dir;
  WriteFile(dir / "my_case.yaml", "scene: x.xml\nduration: 1\n");
  EXPECT_EQ(LoadScenario(dir / "my_case.yaml").name, "my_case");
}

TEST(ScenarioTest, UnknownKeyNamesFileLineAndKey) {
  const std::string e = ErrorOf("scene: x.xml\nduration: 1\ndurration: 2\n");
  EXPECT_NE(e.find("s.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("durration: unknown key"), std::string::npos) << e;
}

TEST(ScenarioTest, NestedUnknownKeyNamesPath) {
  std::string text = kValid;
  text.replace(text.find("servo: {bandwidth_hz: 8}"), 24, "servo: {bandwith_hz: 8}");
  const std::string e = ErrorOf(text);
  EXPECT_NE(e.find("s.yaml:12:"), std::string::npos) << e;
  EXPECT_NE(e.find("devices[0].servo.bandwith_hz: unknown key"), std::string::npos) << e;
}

TEST(ScenarioTest, WrongTypesNameKeyAndLine) {
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: ten\n").find("s.yaml:2: duration: expected a finite number, got 'ten'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\nseed: 1.5\n").find("seed: must be a non-negative integer"),
            std::string::npos);
  EXPECT_NE(ErrorOf("scene: [x]\nduration: 1\n").find("scene: expected a string"), std::string::npos);
  std::string text = kValid;
  text.replace(text.find("noise: false"), 12, "noise: maybe");
  EXPECT_NE(ErrorOf(text).find("devices[1].noise: expected true or false, got 'maybe'"), std::string::npos);
}

TEST(ScenarioTest, MissingRequiredKeys) {
  EXPECT_NE(ErrorOf("duration: 1\n").find("scene: missing required key"), std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\n").find("duration: missing required key"), std::string::npos);
}

TEST(ScenarioTest, RejectsBadValues) {
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: -1\n").find("duration: must be > 0"), std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\nclock: warp\n").find("unknown clock 'warp'"), std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\nallow_warnings: [badqacc]\n").find("non-allowable warning 'badqacc'"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf("scene: x.xml\nduration: 1\ndevices: [{name: a, kind: lidar}]\n").find("unknown device kind 'lidar'"),
      std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\nchecks: [{name: c, signal: time}]\n").find("a check needs a bound"),
            std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\nchecks: [{name: c, signal: t, reduce: median, max: 1}]\n")
                .find("unknown reduction 'median'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\ndevices: [{name: s, kind: sim, on_owner_lost: wait}]\n")
                .find("devices[0].on_owner_lost: must be resume or stay_paused, not 'wait'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: 1\ndevices: [{name: s, kind: sim, owner_timeout: 0}]\n")
                .find("devices[0].owner_timeout: must be > 0 and <= 3600 s"),
            std::string::npos);
  std::string text = kValid;
  text.replace(text.find("initial: [0.1, -0.2]"), 20, "initial: [0.1]");
  EXPECT_NE(ErrorOf(text).find("devices[0].initial: needs one value per joint"), std::string::npos);
}

TEST(ScenarioTest, DuplicateDeviceNames) {
  const std::string e = ErrorOf(
      "scene: x.xml\nduration: 1\ndevices:\n  - {name: a, kind: arm, joints: [j]}\n  - {name: a, kind: arm, joints: "
      "[k]}\n");
  EXPECT_NE(e.find("duplicate device name 'a'"), std::string::npos) << e;
}

TEST(ScenarioTest, MalformedYamlAndMissingFile) {
  EXPECT_NE(ErrorOf("scene: x.xml\nduration: [1\n").find("malformed YAML"), std::string::npos);
  try {
    LoadScenario("/nonexistent/dir/none.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("none.yaml': cannot open file"), std::string::npos);
  }
}

}  // namespace
}  // namespace vlab::lab::scenario_test
