// Tests the gripper and pose devices (src/lab/devices/device_gripper.cc,
// device_pose.cc) on the mjcf/gripper model mounted fixed, jaws pointing
// down, with a 5 cm cube between the pads:
//   - position mode: the opening ramps at the configured speed and settles at
//     the set-point; out-of-range and unknown-mode commands are refused;
//   - force mode: the jaws close on the cube and each pad presses with the
//     commanded grip force; the cube, hanging in the jaws, is held by friction
//     (it does not slide), grasped reads 1; opening again drops it, grasped 0;
//   - the watchdog hold keeps a grip force in effect;
//   - a pose device tracks the cube in the gripper's frame and its distance to
//     a target site;
//   - bad bindings name the device and the element.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_gripper.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_pose.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::gripper_device_test {
namespace {

constexpr double kCubeMass = 0.1;  // kg

// the gripper's and the pose's state payloads (docs/protocol.md)
constexpr int kStatus = bridge::StateIndex(bridge::DeviceKind::kGripper, "status");
constexpr int kOpening = bridge::StateIndex(bridge::DeviceKind::kGripper, "opening");
constexpr int kForce = bridge::StateIndex(bridge::DeviceKind::kGripper, "force");
constexpr int kGrasped = bridge::StateIndex(bridge::DeviceKind::kGripper, "grasped");
constexpr int kPoseQx = bridge::StateIndex(bridge::DeviceKind::kPose, "qx");

// the index of the log column `name` of `device`, -1 when it has none
int ColumnOf(const Device& device, const std::string& name) {
  const std::vector<std::string> columns = device.Columns();
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
}

// the scene, written in `dir`: MJCF includes are relative to the including file
std::string SceneXml(const std::string& dir) {
  const std::string g = std::filesystem::relative(VLAB_SOURCE_DIR "/mjcf/gripper", dir).string();
  return R"(
<mujoco>
  <option timestep="0.001" integrator="Euler"/>
  <include file=")" +
         g + R"(/gripper_defaults.xml"/>
  <worldbody>
    <!-- the gripper fixed 0.5 m up, approach direction (z) pointing down -->
    <body name="gripper" childclass="gripper" pos="0 0 0.5" quat="0 1 0 0">
      <include file=")" +
         g + R"(/gripper.xml"/>
    </body>
    <!-- a 5 cm cube centred between the pads (the TCP is 0.133 m from the mount) -->
    <body name="cube" pos="0 0 0.367">
      <freejoint/>
      <geom type="box" size="0.025 0.025 0.025" mass=")" +
         std::to_string(kCubeMass) + R"(" friction="1 0.005 0.0001"/>
      <site name="cube_centre"/>
    </body>
    <!-- a pedestal under the cube until the test takes it away (its contacts switched off) -->
    <geom name="pedestal" type="box" size="0.02 0.02 0.01" pos="0 0 0.332"/>
    <site name="below" pos="0 0 0.2"/>
  </worldbody>
  <include file=")" +
         g + R"(/gripper_actuators.xml"/>
</mujoco>)";
}

class GripperDeviceTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    testing::WriteFile(dir_ / "scene.xml", SceneXml(dir_.path()));
    m_ = LoadModel(dir_ / "scene.xml");
    d_ = MakeData(m_);
    // the jaws wide open around the cube
    for (const char* jaw : {"gripper_left", "gripper_right"})
      d_->qpos[m_->jnt_qposadr[mj_name2id(m_, mjOBJ_JOINT, jaw)]] = 0.034;
    mj_forward(m_, d_);
    DeviceConfig c;
    c.name = "gripper";
    c.kind = bridge::DeviceKind::kGripper;
    c.where = "test.yaml:1";
    gripper_ = MakeDevice({m_, 0.002, 1, ""}, c);
    gripper_->Reset(*d_);
    DeviceConfig p;
    p.name = "cube";
    p.kind = bridge::DeviceKind::kPose;
    p.EditParams<PoseParams>().site = "cube_centre";
    p.EditParams<PoseParams>().relative_to = "gripper";
    p.EditParams<PoseParams>().target = "below";
    pose_ = MakeDevice({m_, 0.002, 1, ""}, p);
    pose_->Reset(*d_);
  }

  // runs `seconds` of physics with the gripper acting, and samples both devices
  void Run(double seconds) {
    const int steps = static_cast<int>(std::lround(seconds / m_->opt.timestep));
    for (int i = 0; i < steps; ++i) {
      mj_step1(m_, d_);
      gripper_->step_hooks()->Actuate(*d_, m_->opt.timestep);
      mj_step2(m_, d_);
    }
    gripper_->Sample(*d_, d_->time);
    pose_->Sample(*d_, d_->time);
  }
  std::vector<double> State() const {
    std::vector<double> s;
    gripper_->State(&s);
    return s;
  }
  std::vector<double> PoseRow() const {
    std::vector<double> row(pose_->ColumnCount());
    pose_->Row(*d_, row.data());
    return row;
  }

  testing::TempDir dir_;
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  std::unique_ptr<Device> gripper_, pose_;
};

TEST_F(GripperDeviceTest, OpensAtItsSpeedAndRefusesWhatItCannotDo) {
  EXPECT_EQ(gripper_->command_input()->CheckCommand({0, 0.069}), bridge::CommandCheck::kLimits);  // beyond the stroke
  EXPECT_EQ(gripper_->command_input()->CheckCommand({1, 201}), bridge::CommandCheck::kLimits);    // beyond the drive
  EXPECT_EQ(gripper_->command_input()->CheckCommand({1, -1}), bridge::CommandCheck::kLimits);
  EXPECT_EQ(gripper_->command_input()->CheckCommand({2, 0}), bridge::CommandCheck::kMalformed);
  ASSERT_EQ(gripper_->command_input()->CheckCommand({0, 0.052}), bridge::CommandCheck::kAccept);
  const double start = State()[kOpening];
  EXPECT_NEAR(start, 0.068, 1e-6);                 // wide open, as set up
  gripper_->command_input()->Command({0, 0.052});  // close to 1 mm from the cube on each side
  Run(0.1);                                        // 0.1 s at 83 mm/s: 8.3 mm of set-point travel
  std::vector<double> row(gripper_->ColumnCount());
  gripper_->Row(*d_, row.data());
  const int setpoint = ColumnOf(*gripper_, "gripper.setpoint");
  ASSERT_GE(setpoint, 0);
  EXPECT_NEAR(start - row[setpoint], 0.083 * 0.1, 1e-9);        // the servo's set-point
  EXPECT_LT(start - State()[kOpening], start - row[setpoint]);  // the jaws follow it, behind
  EXPECT_EQ(State()[kStatus], 0.0);                             // commanded: not holding
  Run(3.0);
  EXPECT_NEAR(State()[kOpening], 0.052, 0.0005);
  EXPECT_EQ(State()[kGrasped], 0.0);  // nothing pressed between the pads
  EXPECT_LT(State()[kForce], 0.01);
}

TEST_F(GripperDeviceTest, GripsWithTheCommandedForceAndHoldsTheCube) {
  const double grip_N = 40.0;
  Run(0.1);  // the cube settles on its pedestal between the open jaws
  const double z0 = PoseRow()[2];
  EXPECT_EQ(State()[kGrasped], 0.0);
  gripper_->command_input()->Command({1, grip_N});
  Run(2.5);  // the jaws close against their damping (4800 N s/m each: about 8 mm/s at 40 N)
  std::vector<double> s = State();
  EXPECT_NEAR(s[kOpening], 0.05, 0.001);          // the jaws stopped at the cube's width
  EXPECT_NEAR(s[kForce], grip_N, grip_N * 0.05);  // each pad presses with the grip force
  EXPECT_EQ(s[kGrasped], 1.0);                    // grasped
  // take the pedestal away: friction alone holds the cube (2 pads x mu x 40 N >> m g)
  const int pedestal = mj_name2id(m_, mjOBJ_GEOM, "pedestal");
  m_->geom_contype[pedestal] = m_->geom_conaffinity[pedestal] = 0;
  const double z1 = PoseRow()[2];
  Run(1.0);
  const double z2 = PoseRow()[2];
  std::printf("cube along the gripper's z: on the pedestal %.6f m, gripped %.6f m, 1 s without it %.6f m\n", z0, z1,
              z2);
  // held: a cube that slipped would have fallen metres in that second; the soft
  // contacts let it creep a fraction of a millimetre
  EXPECT_LT(std::abs(z2 - z1), 1e-3);
  EXPECT_EQ(State()[kGrasped], 1.0);
  // the watchdog's hold keeps the grip
  gripper_->command_input()->Hold();
  Run(0.5);
  EXPECT_EQ(State()[kGrasped], 1.0);
  EXPECT_EQ(State()[kStatus], static_cast<double>(bridge::kStatusHolding));
  EXPECT_LT(std::abs(PoseRow()[2] - z1), 1e-3);
  // open: the cube falls out, nothing is grasped
  gripper_->command_input()->Command({0, 0.068});
  Run(0.5);
  EXPECT_EQ(State()[kGrasped], 0.0);
  EXPECT_LT(State()[kForce], 0.5);
  EXPECT_GT(PoseRow()[2], z1 + 0.05);  // the gripper's z points down: the cube moved away along it
}

TEST_F(GripperDeviceTest, PoseDeviceReportsTheFrameAndTheTarget) {
  // the cube's centre in the gripper frame, the target 0.167 m below it in the world
  const std::vector<double> row = PoseRow();
  ASSERT_EQ(pose_->Columns(),
            (std::vector<std::string>{"cube.x", "cube.y", "cube.z", "cube.drift", "cube.rot_drift", "cube.error"}));
  EXPECT_NEAR(row[0], 0, 1e-12);
  EXPECT_NEAR(row[1], 0, 1e-12);
  EXPECT_NEAR(row[2], 0.133, 1e-12);  // along the gripper's (downward) z
  EXPECT_NEAR(row[3], 0, 1e-12);      // no drift at the start
  EXPECT_NEAR(row[5], 0.167, 1e-12);  // |(0, 0, 0.367) - (0, 0, 0.2)|
  std::vector<double> state;
  pose_->State(&state);
  ASSERT_EQ(state.size(), 7u);
  EXPECT_NEAR(std::abs(state[kPoseQx]), 1.0,
              1e-12);  // the gripper is the world turned 180 deg about x: q = (0, 1, 0, 0)
}

TEST_F(GripperDeviceTest, BadBindingsNameTheElement) {
  DeviceConfig c;
  c.name = "hand";
  c.kind = bridge::DeviceKind::kGripper;
  c.where = "s.yaml:7";
  c.EditParams<GripperParams>().touch = {"gripper_touch_left", "no_such_sensor"};
  try {
    MakeDevice({m_, 0.002, 1, ""}, c);
    FAIL() << "an unknown sensor must be refused";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "s.yaml:7: device 'hand': the scene has no touch sensor 'no_such_sensor'");
  }
  c.params.reset();
  c.EditParams<GripperParams>().force_actuator = "gripper";
  c.EditParams<GripperParams>().servo = "nope";
  EXPECT_THROW(MakeDevice({m_, 0.002, 1, ""}, c), InputError);
  DeviceConfig p;
  p.name = "tcp";
  p.kind = bridge::DeviceKind::kPose;
  p.where = "s.yaml:9";
  p.EditParams<PoseParams>().site = "gripper_tcp";
  p.EditParams<PoseParams>().relative_to = "no_body";
  try {
    MakeDevice({m_, 0.002, 1, ""}, p);
    FAIL() << "an unknown body must be refused";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "s.yaml:9: device 'tcp': the scene has no body 'no_body'");
  }
}

}  // namespace
}  // namespace vlab::lab::gripper_device_test
