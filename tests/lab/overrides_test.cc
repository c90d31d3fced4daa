// --set KEY=VALUE (lab_overrides.h): dotted paths reach map keys and list items by
// name or index; values get the scenario file's typing and errors, and an error
// on an overridden key names the --set; `vlab run --set` records them in summary.json.
#include "lab/devices/device_arm.h"
#include "lab/devices/device_wrench.h"
#include "lab/scenario/lab_overrides.h"
#include "lab/scenario/lab_scenario.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "test_util.h"

namespace vlab::lab::overrides_test {
namespace {

using vlab::testing::TempDir;
using vlab::testing::WriteFile;

constexpr const char* kScenario = R"(name: reach
scene: scene.xml
duration: 2.5
seed: 42
devices:
  - name: arm
    kind: arm
    joints: [a, b]
    servo: {bandwidth_hz: 8}
  - name: ft
    kind: wrench
    force_sensor: f
    torque_sensor: t
    filter: 2
controller:
  type: joint_pd
  arm: arm
  tip_site: tip
  waypoints:
    - {q: [0.1, 0.2], duration: 1.5}
checks:
  - {name: c, signal: time, reduce: final, max: 3}
)";

Scenario Load(const std::vector<std::string>& sets) {
  TempDir dir;
  WriteFile(dir / "s.yaml", kScenario);
  return LoadScenario(dir / "s.yaml", sets);
}

std::string ErrorOf(const std::vector<std::string>& sets) {
  try {
    Load(sets);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(OverridesTest, SetsMapKeysListItemsByNameAndByIndex) {
  const Scenario s = Load({"duration=4", "devices.ft.filter=5", "devices.arm.servo.bandwidth_hz=12",
                           "controller.waypoints.0.duration=0.75", "checks.c.max=9", "controller.gains.kp=[3, 4]"});
  EXPECT_DOUBLE_EQ(s.duration_s, 4.0);
  EXPECT_EQ(s.devices[1].ParamsAs<WrenchParams>().filter, 5);
  EXPECT_DOUBLE_EQ(s.devices[0].ParamsAs<ArmParams>().servo.bandwidth_hz, 12.0);
  EXPECT_DOUBLE_EQ(s.controller.joint.at(0).duration_s, 0.75);
  EXPECT_DOUBLE_EQ(s.checks.at(0).max, 9.0);
  EXPECT_EQ(s.controller.kp, (std::vector<double>{3, 4}));
  // untouched keys keep the file's values; the overrides are kept in order as given
  EXPECT_EQ(s.seed, 42u);
  EXPECT_EQ(s.devices[0].ParamsAs<ArmParams>().joints, (std::vector<std::string>{"a", "b"}));
  ASSERT_EQ(s.overrides.size(), 6u);
  EXPECT_EQ(s.overrides[1], (std::pair<std::string, std::string>{"devices.ft.filter", "5"}));
}

TEST(OverridesTest, LaterOverrideOfTheSameKeyWins) {
  EXPECT_DOUBLE_EQ(Load({"duration=4", "duration=6"}).duration_s, 6.0);
}

TEST(OverridesTest, WrongTypeGivesTheFilesErrorAndNamesTheSet) {
  const std::string e = ErrorOf({"devices.ft.filter=abc"});
  EXPECT_NE(e.find("s.yaml: devices[1].filter: expected an integer, got 'abc'"), std::string::npos) << e;
  EXPECT_NE(e.find("(from --set devices.ft.filter=abc)"), std::string::npos) << e;
  const std::string range = ErrorOf({"duration=-1"});
  EXPECT_NE(range.find("duration: must be > 0 s"), std::string::npos) << range;
  EXPECT_NE(range.find("(from --set duration=-1)"), std::string::npos) << range;
  const std::string list = ErrorOf({"controller.gains.kp=fast"});
  EXPECT_NE(list.find("controller.gains.kp: expected a list of numbers, got 'fast'"), std::string::npos) << list;
}

TEST(OverridesTest, UnknownKeyIsRejectedLikeInTheFile) {
  const std::string e = ErrorOf({"devices.ft.filtr=2"});
  EXPECT_NE(e.find("devices[1].filtr: unknown key (known:"), std::string::npos) << e;
  EXPECT_NE(e.find("(from --set devices.ft.filtr=2)"), std::string::npos) << e;
  EXPECT_NE(ErrorOf({"durration=2"}).find("durration: unknown key"), std::string::npos);
}

TEST(OverridesTest, MissingListItemNamesTheItemsThereAre) {
  const std::string e = ErrorOf({"devices.jr3.filter=2"});
  EXPECT_NE(e.find("--set devices.jr3.filter=2: devices has no item named 'jr3' (items: arm, ft)"), std::string::npos)
      << e;
  EXPECT_NE(ErrorOf({"controller.waypoints.3.duration=1"}).find("has no item named '3'"), std::string::npos);
}

TEST(OverridesTest, PathThroughAValueAndMalformedInput) {
  EXPECT_NE(ErrorOf({"duration.x=1"}).find("duration is a value, not a mapping or a list"), std::string::npos);
  EXPECT_NE(ErrorOf({"duration"}).find("--set 'duration': expected KEY=VALUE"), std::string::npos);
  EXPECT_NE(ErrorOf({"a..b=1"}).find("KEY has an empty part"), std::string::npos);
  EXPECT_NE(ErrorOf({"=1"}).find("KEY has an empty part"), std::string::npos);
  EXPECT_NE(ErrorOf({"devices.ft.filter=[1"}).find("the value is not valid YAML"), std::string::npos);
}

TEST(OverridesTest, TheFileOnDiskIsNotChanged) {
  TempDir dir;
  WriteFile(dir / "s.yaml", kScenario);
  LoadScenario(dir / "s.yaml", {"duration=4"});
  EXPECT_EQ(vlab::testing::ReadFile(dir / "s.yaml"), kScenario);
  EXPECT_DOUBLE_EQ(LoadScenario(dir / "s.yaml").duration_s, 2.5);
}

// the real binary: overrides change the run and are recorded in summary.json
TEST(OverridesCliTest, RunRecordsOverridesInSummary) {
  TempDir dir;
  const std::string out = dir / "o";
  const auto r =
      vlab::testing::RunVlab("run " + std::string(VLAB_SOURCE_DIR) + "/scenes/pa10_reach --duration 0.1 -q --out " +
                             out + " --set devices.jr3.filter=2 --set controller.gains.position=15");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(vlab::testing::ReadFile(out + "/summary.json"));
  EXPECT_EQ(summary.at("overrides"),
            (nlohmann::json{{"devices.jr3.filter", "2"}, {"controller.gains.position", "15"}}));
  const auto bad =
      vlab::testing::RunVlab("run " + std::string(VLAB_SOURCE_DIR) + "/scenes/pa10_reach --duration 0.1 -q --out " +
                             dir / "bad" + " --set devices.jr3.filter=abc");
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("pa10_reach.yaml: devices[1].filter: expected an integer, got 'abc' (from --set "
                         "devices.jr3.filter=abc)"),
            std::string::npos)
      << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad")) << "nothing written on bad input";
}

}  // namespace
}  // namespace vlab::lab::overrides_test
