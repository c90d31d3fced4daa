// The describe replies of the lab's devices against the table of wire layouts
// (bridge/bridge_layouts.h): `vlab devices --json` of every shipped scenario,
// and of a scenario with the kinds no shipped scenario serves (gripper, pose,
// gaze), must describe each float64
// device with the table's layout (the arm's with its joint count, feet and imu
// with their sensor values' names).
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "test_util.h"

namespace vlab::bridge {
namespace {

using nlohmann::json;

// the describe replies `vlab devices SCENARIO --json` prints
std::vector<json> Describes(const std::string& scenario) {
  const testing::ProcessResult r = testing::RunVlab("devices '" + scenario + "' --json", 60);
  EXPECT_EQ(r.exit_code, 0) << scenario << ": " << r.err;
  std::vector<json> out;
  const std::string tag = "describe: ";
  for (const std::string& line : testing::Lines(r.out)) {
    const auto at = line.find(tag);
    if (at != std::string::npos) out.push_back(json::parse(line.substr(at + tag.size())));
  }
  return out;
}

// the layout the table gives the device of this describe reply
json Expected(const KindLayout& k, const json& describe) {
  if (k.kind == DeviceKind::kArm) return LayoutJson(k.kind, static_cast<int>(describe.at("joints").size()));
  if (k.kind == DeviceKind::kFeet || k.kind == DeviceKind::kImu || k.kind == DeviceKind::kScene) {
    return LayoutJson(k.kind, describe.at("layout").at("state").get<std::vector<std::string>>());
  }
  if (k.kind == DeviceKind::kWord) {  // spelled, then the letters' values
    std::vector<std::string> values = describe.at("layout").at("state").get<std::vector<std::string>>();
    if (!values.empty()) values.erase(values.begin());
    return LayoutJson(k.kind, values);
  }
  return LayoutJson(k.kind);
}

// checks every float64 device of the scenario; adds the kinds seen
void CheckScenario(const std::string& scenario, std::set<std::string>* kinds) {
  for (const json& d : Describes(scenario)) {  // none where the controller runs in process
    const std::string kind = d.at("kind").get<std::string>();
    const KindLayout* k = FindKindLayout(kind);
    ASSERT_NE(k, nullptr) << scenario << ": device '" << d.value("name", "") << "' of kind '" << kind << "'";
    if (!k->float64) continue;
    EXPECT_EQ(d.at("layout"), Expected(*k, d)) << scenario << ": device '" << d.value("name", "") << "'";
    kinds->insert(kind);
  }
}

TEST(DescribeLayoutsTest, EveryShippedScenariosDevicesDescribeTheTablesLayouts) {
  std::set<std::string> kinds;
  for (const auto& entry : std::filesystem::directory_iterator(VLAB_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".yaml") continue;
    CheckScenario("scenes/" + entry.path().filename().string(), &kinds);
  }
  // a gripper on the PA10, a pose and a gaze device on its cube, served
  testing::TempDir dir;
  testing::WriteFile(dir / "served.yaml",
                     "name: served_layouts\n"
                     "scene: " VLAB_SOURCE_DIR
                     "/scenes/pa10_gripper.xml\n"
                     "duration: 1\ncontrol_period: 0.002\nseed: 1\nclock: lockstep\n"
                     "devices:\n"
                     "  - {name: gripper, kind: gripper, port: 50099}\n"
                     "  - {name: cube_pose, kind: pose, site: cube, port: 50098}\n"
                     "  - {name: gaze, kind: gaze, camera: overview, target: cube, width: 320, height: 240, "
                     "port: 50097}\n"
                     "  - {name: word, kind: word, word: A, slots: [cube], letters: {A: cube}, port: 50096}\n"
                     "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2]}\n"
                     "  - {name: tool, kind: tool, arm: pa10, port: 50095}\n");
  CheckScenario(dir / "served.yaml", &kinds);
  // every float64 kind the lab serves was seen
  const std::set<std::string> lab = {"arm",   "wrench", "sim",  "base", "gripper", "feet", "imu",
                                     "point", "yoyo",   "gaze", "pose", "scene",   "word", "tool"};
  EXPECT_EQ(kinds, lab);
}

}  // namespace
}  // namespace vlab::bridge
