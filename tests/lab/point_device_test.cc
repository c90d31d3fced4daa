// Tests the point device (src/lab/devices/device_point.cc) on the PA10 of
// scenes/pa10.xml: it holds before its first command, moves the tool tip to a
// commanded point with the start orientation kept, ramps at max_speed, refuses
// non-finite and out-of-workspace commands, holds on the watchdog, overrides
// the arm's own commands, and the scenario rules around it (its arm must exist,
// one driver per arm).
#include <cmath>

#include <gtest/gtest.h>

#include "arm_driver_fixture.h"
#include "bridge/bridge_layouts.h"
#include "control/task_space.h"
#include "lab/devices/device_point.h"
#include "lab/run/lab_command_writer.h"
#include "mujoco_fixture.h"

namespace vlab::lab::point_device_test {
namespace {

using namespace arm_driver_rig;  // kPeriod, ColumnOf, ArmConfig, ArmDriverRig, Pa10ScenarioError

// the point device's state payload (docs/protocol.md)
constexpr int kStatus = bridge::StateIndex(bridge::DeviceKind::kPoint, "status");
constexpr int kX = bridge::StateIndex(bridge::DeviceKind::kPoint, "x");
constexpr int kVx = bridge::StateIndex(bridge::DeviceKind::kPoint, "vx");
constexpr int kVy = bridge::StateIndex(bridge::DeviceKind::kPoint, "vy");
constexpr int kVz = bridge::StateIndex(bridge::DeviceKind::kPoint, "vz");
static_assert(bridge::StateIndex(bridge::DeviceKind::kPoint, "z") == kX + 2, "x, y, z follow each other");

DeviceConfig PointConfig(double max_speed = 0.2) {
  DeviceConfig c;
  c.name = "hand";
  c.kind = bridge::DeviceKind::kPoint;
  c.where = "test.yaml:9";
  c.EditParams<PointParams>().arm = "pa10";
  c.EditParams<PointParams>().max_speed = max_speed;
  c.EditParams<PointParams>().workspace_min = {0.5, -0.3, 0.2};
  c.EditParams<PointParams>().workspace_max = {0.9, 0.3, 0.8};
  return c;
}

// The arm and its point device (ArmDriverRig: Period, State, Tool, ToolR).
struct Rig : ArmDriverRig {
  Device* point;

  Rig(mjModel* m, mjData* d, double max_speed) : ArmDriverRig(m, d) {
    Start(PointConfig(max_speed));
    point = driver.get();
  }
  // the point's set-point from its log row
  Eigen::Vector3d Setpoint() const {
    std::vector<double> row(point->ColumnCount());
    point->Row(*data, row.data());
    const int x = ColumnOf(*point, "hand.setpoint.x");
    EXPECT_GE(x, 0);
    EXPECT_EQ(ColumnOf(*point, "hand.setpoint.z"), x + 2);
    return Eigen::Vector3d(row[x], row[x + 1], row[x + 2]);
  }
};

class PointDeviceTest : public test::MujocoTest {
 protected:
  Rig NewRig(double max_speed = 0.2) {
    mjModel* m = LoadModel("scenes/pa10.xml");
    return Rig(m, MakeData(m), max_speed);
  }
};

TEST_F(PointDeviceTest, HoldsBeforeTheFirstCommand) {
  Rig rig = NewRig();
  const Eigen::Vector3d start = rig.Tool();
  EXPECT_NEAR(start.x(), 0.725, 1e-4);  // the ready pose's tool tip (scenes/pa10.xml)
  EXPECT_NEAR(start.z(), 0.435, 5e-4);  // 0.43471: the pose's angles are rounded to 1e-6 rad
  for (int k = 0; k < 100; ++k) rig.Period();
  const std::vector<double> s = rig.State();
  ASSERT_EQ(s.size(), 7u);
  EXPECT_EQ(s[kStatus], static_cast<double>(bridge::kStatusHolding));
  EXPECT_LT((rig.Tool() - start).norm(), 1e-6);
  for (int i = 0; i < 3; ++i) EXPECT_DOUBLE_EQ(s[kX + i], rig.Tool()[i]);
  for (int i : {kVx, kVy, kVz}) EXPECT_NEAR(s[i], 0.0, 1e-6);
}

TEST_F(PointDeviceTest, MovesTheToolToTheCommandKeepingItsOrientation) {
  Rig rig = NewRig();  // max_speed 0.2 m/s
  const Eigen::Vector3d start = rig.Tool();
  const Eigen::Matrix3d R_start = rig.ToolR();
  const Eigen::Vector3d goal = start + Eigen::Vector3d(0.06, -0.03, 0.08);  // 0.1044 m away
  rig.point->command_input()->Command({goal.x(), goal.y(), goal.z()});
  // the set-point ramps at 0.2 m/s: after 0.25 s it is 0.05 m along the line (closed form)
  std::vector<double> row(rig.point->ColumnCount());
  for (int k = 0; k < 25; ++k) rig.Period();
  rig.point->Row(*rig.data, row.data());
  const Eigen::Vector3d setpoint = rig.Setpoint();
  const Eigen::Vector3d along = start + 0.05 * (goal - start).normalized();
  EXPECT_LT((setpoint - along).norm(), 1e-12);
  EXPECT_LT((rig.Tool() - along).norm(), 0.003);  // the tip follows within the servo's lag
  EXPECT_NEAR(std::hypot(std::hypot(rig.State()[kVx], rig.State()[kVy]), rig.State()[kVz]), 0.2, 0.01);
  EXPECT_EQ(rig.State()[kStatus], 0.0);
  for (int k = 0; k < 175; ++k) rig.Period();  // 2 s in all
  EXPECT_LT((rig.Tool() - goal).norm(), 2e-6);
  EXPECT_LT(control::OrientationError(R_start, rig.ToolR()).norm(), 2e-5);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(rig.State()[kX + i], goal[i], 2e-6);
  const int rot_error = ColumnOf(*rig.point, "hand.rot_error");
  ASSERT_GE(rot_error, 0);
  EXPECT_LT(row[rot_error], 1e-3);  // while moving, rad
}

TEST_F(PointDeviceTest, RefusesNonFiniteAndOutOfWorkspaceCommands) {
  Rig rig = NewRig();
  EXPECT_EQ(rig.point->command_input()->command_length(), 3);
  EXPECT_EQ(rig.point->command_input()->CheckCommand({0.7, 0.0, 0.5}), bridge::CommandCheck::kAccept);
  EXPECT_EQ(rig.point->command_input()->CheckCommand({NAN, 0.0, 0.5}), bridge::CommandCheck::kMalformed);
  EXPECT_EQ(rig.point->command_input()->CheckCommand({0.7, INFINITY, 0.5}), bridge::CommandCheck::kMalformed);
  EXPECT_EQ(rig.point->command_input()->CheckCommand({0.7, 0.0, 0.81}), bridge::CommandCheck::kLimits);
  EXPECT_EQ(rig.point->command_input()->CheckCommand({0.49, 0.0, 0.5}), bridge::CommandCheck::kLimits);
  EXPECT_EQ(rig.point->command_input()->CheckCommand({0.9, 0.3, 0.8}),
            bridge::CommandCheck::kAccept);  // the box's corner
}

TEST_F(PointDeviceTest, HoldsOnTheWatchdogAndResumesFromWhereItIs) {
  Rig rig = NewRig(1.0);
  const Eigen::Vector3d start = rig.Tool();
  rig.point->command_input()->Command({start.x(), start.y(), start.z() + 0.2});
  for (int k = 0; k < 10; ++k) rig.Period();  // 0.1 s of 0.2: moving up at 1 m/s
  rig.point->command_input()->Hold();
  for (int k = 0; k < 50; ++k) rig.Period();
  const Eigen::Vector3d held = rig.Tool();
  EXPECT_EQ(rig.State()[kStatus], static_cast<double>(bridge::kStatusHolding));
  EXPECT_GT(held.z() - start.z(), 0.08);
  EXPECT_LT(held.z() - start.z(), 0.13);
  for (int k = 0; k < 50; ++k) rig.Period();
  EXPECT_LT((rig.Tool() - held).norm(), 1e-6);  // stopped where it was
  // the next command starts from there: no jump to the old set-point
  rig.point->command_input()->Command({held.x(), held.y(), held.z()});
  rig.Period();
  EXPECT_LT((rig.Setpoint() - held).norm(), 1e-6);
}

TEST_F(PointDeviceTest, OverridesTheArmsOwnCommandsEveryPeriod) {
  Rig rig = NewRig();
  const Eigen::Vector3d start = rig.Tool();
  bridge::ArmCommand spin;
  spin.mode = bridge::ArmMode::kVelocity;
  spin.value = Eigen::VectorXd::Zero(7);
  spin.value[0] = 1.0;  // S1 at 1 rad/s would swing the tool 7 cm in 0.1 s
  for (int k = 0; k < 50; ++k) {
    ASSERT_TRUE(rig.arm->Command(spin));  // given first, as the lab's bridge does ...
    rig.Period();                         // ... then the point device's hold replaces it
  }
  EXPECT_LT((rig.Tool() - start).norm(), 1e-6);
}

TEST(PointScenarioTest, ScenarioRules) {
  vlab::testing::TempDir dir;
  auto error_of = [&](const std::string& rest) { return Pa10ScenarioError(dir, rest); };
  EXPECT_NE(error_of("  - {name: hand, kind: point, arm: nope}\n").find("no arm device 'nope'"), std::string::npos);
  // a second driver: the claim table names both claimants, the second at its own line
  const std::string two =
      error_of("  - {name: hand, kind: point, arm: pa10}\n  - {name: hand2, kind: point, arm: pa10}\n");
  EXPECT_NE(two.find("s.yaml:7: point device 'hand2': device 'pa10' is driven by point device 'hand' ("),
            std::string::npos)
      << two;
  EXPECT_NE(two.find("s.yaml:6) already: one owner at a time"), std::string::npos) << two;
  EXPECT_NE(error_of("  - {name: hand, kind: point, arm: pa10, site: nope}\n").find("nope"), std::string::npos);
  EXPECT_NE(error_of("  - {name: hand, kind: point, arm: pa10, workspace: {min: [0, 0, 1], max: [1, 1, 0]}}\n")
                .find("must be > min"),
            std::string::npos);
  EXPECT_EQ(error_of("  - {name: hand, kind: point, arm: pa10, port: 0}\n"), "");
}

// One claimant per device's command input, whoever the two are (lab_command_writer.h).
TEST(PointScenarioTest, OneClaimantPerArmWhateverTheSources) {
  vlab::testing::TempDir dir;
  auto error_of = [&](const std::string& rest) { return Pa10ScenarioError(dir, rest); };
  const std::string hand = "  - {name: hand, kind: point, arm: pa10}\n";
  const std::string builtin =
      "controller: {type: joint_pd, arm: pa10, tip_site: tool, waypoints: [{q: [0, 0, 0, 0, 0, 0, 0], "
      "duration: 1}]}\n";
  const std::string task = std::string("controller: {type: task, programs: [{robot: pa10, script: ") + VLAB_SOURCE_DIR +
                           "/scenes/tasks/square.lua, tip_site: tool}]}\n";
  // each alone is fine
  EXPECT_EQ(error_of(builtin), "");
  EXPECT_EQ(error_of(task), "");
  // with a point device on the same arm, the lab's controller is refused, naming both
  const std::string with_builtin = error_of(hand + builtin);
  EXPECT_NE(with_builtin.find(": the built-in controller: device 'pa10' is driven by point device 'hand' (" +
                              dir.path() + "/s.yaml:6) already: one owner at a time"),
            std::string::npos)
      << with_builtin;
  const std::string with_task = error_of(hand + task);
  EXPECT_NE(with_task.find(": task program '"), std::string::npos) << with_task;
  EXPECT_NE(with_task.find("square.lua': device 'pa10' is driven by point device 'hand'"), std::string::npos)
      << with_task;
  // two programs on one robot: the same rule, the same message
  const std::string square = std::string(VLAB_SOURCE_DIR) + "/scenes/tasks/square.lua";
  const std::string two = error_of("controller: {type: task, programs: [{robot: pa10, script: " + square +
                                   ", tip_site: tool}, {robot: pa10, script: " + square + ", tip_site: tool}]}\n");
  EXPECT_NE(two.find("square.lua': device 'pa10' is driven by task program '" + square + "' ("), std::string::npos)
      << two;
}

// The wire claims a served device's command input when its sockets are bound: a served arm that the
// built-in controller commands is refused then (a served arm under a point device is not: the point
// device holds its claim, and its own clients only read it).
TEST(PointScenarioTest, TheWireClaimsServedDevicesWhenItBinds) {
  vlab::testing::TempDir dir;
  const std::string head = std::string("scene: ") + VLAB_SOURCE_DIR +
                           "/scenes/pa10.xml\nduration: 0.1\n"
                           "control_period: 0.01\ndevices:\n"
                           "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2], port: auto}\n";
  vlab::testing::WriteFile(dir.path() + "/builtin.yaml",
                           head +
                               "controller: {type: joint_pd, arm: pa10, tip_site: tool, waypoints: [{q: [0, 0, 0, 0, "
                               "0, 0, 0], duration: 1}]}\n");
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(dir.path() + "/builtin.yaml"));  // nothing served yet
  try {
    lab->Describe(BridgeOptions{}, std::nullopt);
    ADD_FAILURE() << "a served arm commanded by the built-in controller was bound";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("builtin.yaml:5: the UDP clients of its port: device 'pa10' is driven by "
                                         "the built-in controller ("),
              std::string::npos)
        << e.what();
  }
  vlab::testing::WriteFile(dir.path() + "/point.yaml", head + "  - {name: hand, kind: point, arm: pa10, port: auto}\n");
  lab = Lab::Create(LoadScenario(dir.path() + "/point.yaml"));
  EXPECT_EQ(lab->Describe(BridgeOptions{}, std::nullopt).size(), 2u);
}

TEST(ClaimTableTest, RefusesASecondClaimantByName) {
  ClaimTable table;
  table.Add(Claim{"pa10", "point device 'hand'", "a.yaml:6"});
  table.Add(Claim{"gripper", "task program 'x.lua'", "a.yaml:9"});
  ASSERT_NE(table.Holder("pa10"), nullptr);
  EXPECT_EQ(table.Holder("pa10")->who, "point device 'hand'");
  EXPECT_EQ(table.Holder("nope"), nullptr);
  try {
    table.Add(Claim{"pa10", "the built-in controller", "a.yaml:12"});
    ADD_FAILURE() << "a second claim was taken";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "a.yaml:12: the built-in controller: device 'pa10' is driven by point device "
              "'hand' (a.yaml:6) already: one owner at a time");
  }
  EXPECT_EQ(table.Holder("pa10")->who, "point device 'hand'");  // the first claim stays
}

}  // namespace
}  // namespace vlab::lab::point_device_test
