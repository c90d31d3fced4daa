// Tests the tool device (src/lab/devices/device_tool.cc) on the PA10 of
// scenes/pa10.xml: it holds before its first command; it moves the tool to a
// commanded pose (position and orientation) with the set-point ramped at
// max_speed and max_angular_speed (closed forms: a straight line and a turn
// about one axis at those rates), and the tool then sits on the pose; it
// refuses non-finite commands, quaternions that are not unit, positions out of
// the workspace box or beyond the reach sphere, and tool axes outside the tilt
// cone; it holds on the watchdog and resumes from where the tool is; and the
// scenario keys.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "arm_driver_fixture.h"
#include "bridge/bridge_layouts.h"
#include "control/task_space.h"
#include "lab/devices/device_tool.h"
#include "mujoco_fixture.h"

namespace vlab::lab::tool_device_test {
namespace {

using namespace arm_driver_rig;  // kPeriod, ColumnOf, ArmConfig, ArmDriverRig, Pa10ScenarioError

constexpr double kDeg = M_PI / 180;

// the tool device's state payload (docs/protocol.md)
constexpr int kStatus = bridge::StateIndex(bridge::DeviceKind::kTool, "status");
constexpr int kX = bridge::StateIndex(bridge::DeviceKind::kTool, "x");
constexpr int kQw = bridge::StateIndex(bridge::DeviceKind::kTool, "qw");
constexpr int kVx = bridge::StateIndex(bridge::DeviceKind::kTool, "vx");
constexpr int kWx = bridge::StateIndex(bridge::DeviceKind::kTool, "wx");
static_assert(bridge::CommandIndex(bridge::DeviceKind::kTool, "qw") == 3, "x, y, z, then the quaternion");

// the shoulder (S2's axis, scenes/pa10.xml: 0.200 + 0.115 m above the base)
const Eigen::Vector3d kShoulder(0, 0, 0.315);

DeviceConfig ToolConfig(double reach) {
  DeviceConfig c;
  c.name = "tool";
  c.kind = bridge::DeviceKind::kTool;
  c.where = "test.yaml:9";
  ToolParams& p = c.EditParams<ToolParams>();
  p.arm = "pa10";
  p.max_speed = 0.2;
  p.max_angular_speed = 1.0;
  p.workspace_min = {0.3, -0.5, 0.2};
  p.workspace_max = {1.2, 0.5, 1.2};
  p.reach = ToolParams::Reach::kFixed;
  p.reach_centre = {kShoulder.x(), kShoulder.y(), kShoulder.z()};
  p.reach_radius = reach;
  p.tilt_axis = {0, 0, -1};
  p.max_tilt_deg = 60;
  return c;
}

// The arm and its tool device (ArmDriverRig: Period, State, Tool, ToolR).
struct Rig : ArmDriverRig {
  Device* tool;
  double reach = 0;  // shoulder to tool site with the arm straight up (q = 0): the farthest it gets

  Rig(mjModel* m, mjData* d) : ArmDriverRig(m, d) {
    mj_resetData(model, data);
    mj_forward(model, data);
    reach = (Tool() - kShoulder).norm();
    Start(ToolConfig(reach));
    tool = driver.get();
  }
  void Command(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
    tool->command_input()->Command({p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()});
  }
};

class ToolDeviceTest : public test::MujocoTest {
 protected:
  Rig NewRig() {
    mjModel* m = LoadModel("scenes/pa10.xml");
    return Rig(m, MakeData(m));
  }
};

TEST_F(ToolDeviceTest, HoldsBeforeTheFirstCommandAndReportsThePose) {
  Rig rig = NewRig();
  const Eigen::Vector3d start = rig.Tool();
  for (int k = 0; k < 50; ++k) rig.Period();
  const std::vector<double> s = rig.State();
  ASSERT_EQ(s.size(), 14u);
  EXPECT_EQ(s[kStatus], static_cast<double>(bridge::kStatusHolding));
  EXPECT_LT((rig.Tool() - start).norm(), 1e-6);
  for (int i = 0; i < 3; ++i) EXPECT_DOUBLE_EQ(s[kX + i], rig.Tool()[i]);
  const Eigen::Quaterniond q(s[kQw], s[kQw + 1], s[kQw + 2], s[kQw + 3]);
  EXPECT_NEAR(q.norm(), 1.0, 1e-12);
  EXPECT_GE(q.w(), 0.0);
  EXPECT_LT(control::OrientationError(q.toRotationMatrix(), rig.ToolR()).norm(), 1e-9);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(s[kVx + i], 0.0, 1e-6);
    EXPECT_NEAR(s[kWx + i], 0.0, 1e-6);
  }
}

TEST_F(ToolDeviceTest, MovesTheToolToACommandedPose) {
  Rig rig = NewRig();
  const Eigen::Vector3d start = rig.Tool();
  const Eigen::Matrix3d R_start = rig.ToolR();
  // 0.1044 m away, turned 0.5 rad about an axis tilted from the vertical (a pick's yaw and a little tip)
  const Eigen::Vector3d goal = start + Eigen::Vector3d(0.06, -0.03, 0.08);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 0.1, 1.0).normalized();
  const double angle = 0.5;
  const Eigen::Quaterniond q_goal(Eigen::AngleAxisd(angle, axis) * R_start);
  rig.Command(goal, q_goal);
  // after 0.25 s: the set-point 0.05 m along the line (0.2 m/s) and turned 0.25 rad about the axis (1 rad/s)
  for (int k = 0; k < 25; ++k) rig.Period();
  std::vector<double> row(rig.tool->ColumnCount());
  rig.tool->Row(*rig.data, row.data());
  const int sx = ColumnOf(*rig.tool, "tool.setpoint.x");
  ASSERT_GE(sx, 0);
  const Eigen::Vector3d along = start + 0.05 * (goal - start).normalized();
  EXPECT_LT((Eigen::Vector3d(row[sx], row[sx + 1], row[sx + 2]) - along).norm(), 1e-12);
  const Eigen::Matrix3d R_along = Eigen::AngleAxisd(0.25, axis) * R_start;
  // the tool follows within the servo's lag: 3 mm as the point device's test; 0.02 rad = 1.1 deg,
  // the lag of a 1 rad/s turn at the orientation gain 20 /s is 1 / 20 = 0.05 s = 0.05 rad, and the
  // feed-forward takes most of it
  EXPECT_LT((rig.Tool() - along).norm(), 0.003);
  EXPECT_LT(control::OrientationError(R_along, rig.ToolR()).norm(), 0.02);
  const std::vector<double> s = rig.State();
  EXPECT_EQ(s[kStatus], 0.0);
  EXPECT_NEAR(Eigen::Vector3d(s[kVx], s[kVx + 1], s[kVx + 2]).norm(), 0.2, 0.01);
  EXPECT_NEAR(Eigen::Vector3d(s[kWx], s[kWx + 1], s[kWx + 2]).dot(axis), 1.0, 0.05);
  // 2 s in all: the ramps end at 0.52 s and 0.5 s; after 1.5 s more at gain 20 /s the errors are
  // what the servo leaves, measured 0.54 um and 1.4e-7 rad: bounds 5 um and 2e-6 rad (about 10x)
  for (int k = 0; k < 175; ++k) rig.Period();
  const double position_error = (rig.Tool() - goal).norm();
  const double orientation_error = control::OrientationError(q_goal.toRotationMatrix(), rig.ToolR()).norm();
  std::printf("tool pose error after 2 s: %.3g m, %.3g rad\n", position_error, orientation_error);
  EXPECT_LT(position_error, 5e-6);
  EXPECT_LT(orientation_error, 2e-6);
  rig.tool->Row(*rig.data, row.data());
  EXPECT_LT(row[ColumnOf(*rig.tool, "tool.rot_error")], 2e-6);
  EXPECT_LT(row[ColumnOf(*rig.tool, "tool.error")], 5e-6);
  // q and -q are the same orientation: the tool does not move
  rig.Command(goal, Eigen::Quaterniond(-q_goal.coeffs()));
  for (int k = 0; k < 20; ++k) rig.Period();
  EXPECT_LT(control::OrientationError(q_goal.toRotationMatrix(), rig.ToolR()).norm(), 1e-4);
}

TEST_F(ToolDeviceTest, RefusesMalformedAndOutOfLimitCommands) {
  Rig rig = NewRig();
  // tool pointing down: its z axis along -z, inside the 60 deg cone about (0, 0, -1)
  const Eigen::Quaterniond down(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  auto check = [&](const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
    return rig.tool->command_input()->CheckCommand({p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()});
  };
  const Eigen::Vector3d p(0.7, 0.0, 0.5);
  EXPECT_EQ(rig.tool->command_input()->command_length(), 7);
  EXPECT_EQ(check(p, down), bridge::CommandCheck::kAccept);
  EXPECT_EQ(rig.tool->command_input()->CheckCommand({NAN, 0, 0.5, 1, 0, 0, 0}), bridge::CommandCheck::kMalformed);
  EXPECT_EQ(rig.tool->command_input()->CheckCommand({0.7, 0, 0.5, 0, INFINITY, 0, 0}),
            bridge::CommandCheck::kMalformed);
  EXPECT_EQ(rig.tool->command_input()->CheckCommand({0.7, 0, 0.5, 0, 1}),
            bridge::CommandCheck::kMalformed);  // 5 values
  // |q| within 1 +- 0.001
  EXPECT_EQ(check(p, Eigen::Quaterniond(down.coeffs() * 1.0009)), bridge::CommandCheck::kAccept);
  EXPECT_EQ(check(p, Eigen::Quaterniond(down.coeffs() * 1.0011)), bridge::CommandCheck::kMalformed);
  EXPECT_EQ(check(p, Eigen::Quaterniond(0, 0, 0, 0)), bridge::CommandCheck::kMalformed);
  // the workspace box
  EXPECT_EQ(check(Eigen::Vector3d(0.29, 0, 0.5), down), bridge::CommandCheck::kLimits);
  EXPECT_EQ(check(Eigen::Vector3d(0.7, 0, 0.19), down), bridge::CommandCheck::kLimits);
  // the reach sphere: the arm straight up reaches rig.reach from the shoulder, not 1 mm more
  const Eigen::Vector3d out = Eigen::Vector3d(1, 0, 1).normalized();
  EXPECT_EQ(check(kShoulder + (rig.reach - 0.001) * out, down), bridge::CommandCheck::kAccept);
  EXPECT_EQ(check(kShoulder + (rig.reach + 0.001) * out, down), bridge::CommandCheck::kLimits);
  // the tilt cone: 59 deg from straight down is accepted, 61 deg refused
  for (double tilt : {59.0, 61.0}) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(tilt * kDeg, Eigen::Vector3d::UnitY()) * down);
    EXPECT_EQ(check(p, q), tilt < 60 ? bridge::CommandCheck::kAccept : bridge::CommandCheck::kLimits) << tilt;
  }
  // the served endpoint refuses (and counts by reason) with the same check
  bridge::EndpointConfig endpoint;
  rig.tool->ConfigureEndpoint(100, &endpoint);
  EXPECT_EQ(endpoint.kind, bridge::DeviceKind::kTool);
  EXPECT_EQ(endpoint.command_length, 7);
  EXPECT_TRUE(endpoint.status_first);
  ASSERT_TRUE(endpoint.check_command);
  const Eigen::Vector3d far = kShoulder + (rig.reach + 0.001) * out;
  EXPECT_EQ(endpoint.check_command({far.x(), far.y(), far.z(), down.w(), down.x(), down.y(), down.z()}),
            bridge::CommandCheck::kLimits);
}

TEST_F(ToolDeviceTest, ByDefaultRefusesWhatNoPostureReaches) {
  // reach auto: from S1's anchor (0, 0, 0.2), the chain's length; with the arm straight up
  // (q = 0) every anchor and the tool site lie on the z axis, so that length is the tool
  // site's height above the anchor there
  mjModel* m = LoadModel("scenes/pa10.xml");
  mjData* d = MakeData(m);
  mj_forward(m, d);
  const Eigen::Vector3d anchor(0, 0, 0.2);
  const double length =
      (Eigen::Map<const Eigen::Vector3d>(d->site_xpos + 3 * mj_name2id(m, mjOBJ_SITE, "tool")) - anchor).norm();
  DeviceConfig c = ToolConfig(1.0);
  c.EditParams<ToolParams>().reach = ToolParams::Reach::kAuto;
  c.EditParams<ToolParams>().workspace_min = {-2, -2, -2};
  c.EditParams<ToolParams>().workspace_max = {2, 2, 2};
  c.EditParams<ToolParams>().max_tilt_deg = 180;
  auto arm = SimArm::Create({m, kPeriod, 1, "pa10.xml"}, ArmConfig());
  auto tool = MakeDevice({m, kPeriod, 1, "pa10.xml"}, c);
  tool->Bind({arm.get(), tool.get()});
  const Eigen::Vector3d out = Eigen::Vector3d(0.6, -0.3, 0.2).normalized();
  auto check = [&](double r) {
    const Eigen::Vector3d p = anchor + r * out;
    return tool->command_input()->CheckCommand({p.x(), p.y(), p.z(), 1, 0, 0, 0});
  };
  EXPECT_EQ(check(length - 0.001), bridge::CommandCheck::kAccept);
  EXPECT_EQ(check(length + 0.001), bridge::CommandCheck::kLimits);
  EXPECT_GT(length, 1.0);  // 0.115 + 0.45 + 0.5 + 0.08 m of links, and the JR3 and tool below the site
}

TEST_F(ToolDeviceTest, HoldsOnTheWatchdogAndResumesFromWhereItIs) {
  Rig rig = NewRig();
  const Eigen::Vector3d start = rig.Tool();
  const Eigen::Quaterniond q_start(rig.ToolR());
  rig.Command(start + Eigen::Vector3d(0, 0, 0.2), Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()) * q_start);
  for (int k = 0; k < 20; ++k) rig.Period();  // 0.2 s: 4 cm up, 0.2 rad turned
  rig.tool->command_input()->Hold();
  for (int k = 0; k < 50; ++k) rig.Period();
  const Eigen::Vector3d held = rig.Tool();
  const Eigen::Matrix3d R_held = rig.ToolR();
  EXPECT_EQ(rig.State()[kStatus], static_cast<double>(bridge::kStatusHolding));
  EXPECT_GT(control::OrientationError(q_start.toRotationMatrix(), R_held).norm(), 0.15);
  for (int k = 0; k < 50; ++k) rig.Period();
  EXPECT_LT((rig.Tool() - held).norm(), 1e-6);
  // the next command starts from there: no jump to the old set-point
  rig.Command(held, Eigen::Quaterniond(R_held));
  rig.Period();
  EXPECT_LT((rig.Tool() - held).norm(), 1e-4);
  EXPECT_LT(control::OrientationError(R_held, rig.ToolR()).norm(), 1e-3);
}

TEST(ToolScenarioTest, ScenarioKeysAndRules) {
  vlab::testing::TempDir dir;
  auto error_of = [&](const std::string& rest) { return Pa10ScenarioError(dir, rest); };
  EXPECT_EQ(error_of("  - {name: tool, kind: tool, arm: pa10, max_speed: 0.1, max_angular_speed: 0.5, "
                     "workspace: {min: [0.3, -0.5, 0.4], max: [1.1, 0.5, 1.2]}, "
                     "reach: {centre: [0, 0, 0.315], radius: 1.0}, tilt: {axis: [0, 0, -1], max_deg: 90}}\n"),
            "");
  EXPECT_EQ(error_of("  - {name: tool, kind: tool, arm: pa10, reach: off}\n"), "");
  EXPECT_NE(error_of("  - {name: tool, kind: tool, arm: pa10, reach: far}\n").find("reach: is auto, off or"),
            std::string::npos);
  EXPECT_NE(error_of("  - {name: tool, kind: tool, arm: nope}\n").find("no arm device 'nope'"), std::string::npos);
  EXPECT_NE(error_of("  - {name: tool, kind: tool, arm: pa10, reach: {radius: 0}}\n").find("reach.radius: must be > 0"),
            std::string::npos);
  EXPECT_NE(
      error_of("  - {name: tool, kind: tool, arm: pa10, reach: {centre: [0, 0]}}\n").find("reach.centre: needs 3"),
      std::string::npos);
  EXPECT_NE(error_of("  - {name: tool, kind: tool, arm: pa10, tilt: {max_deg: 200}}\n").find("tilt.max_deg: must be"),
            std::string::npos);
  EXPECT_NE(error_of("  - {name: tool, kind: tool, arm: pa10, tilt: {axis: [0, 0, 0]}}\n")
                .find("tilt.axis: must not be zero"),
            std::string::npos);
  EXPECT_NE(error_of("  - {name: tool, kind: tool, arm: pa10, max_angular_speed: 0}\n")
                .find("max_angular_speed: must be > 0"),
            std::string::npos);
  EXPECT_NE(
      error_of("  - {name: tool, kind: tool, arm: pa10}\n  - {name: hand, kind: point, arm: pa10}\n").find("driven by"),
      std::string::npos);
}

}  // namespace
}  // namespace vlab::lab::tool_device_test
