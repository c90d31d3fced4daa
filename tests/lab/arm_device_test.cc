// SimArm on the PA10 scene: holds, refuses bad commands and keeps the last
// good one, tracks velocity and position commands, applies torques exactly,
// clips and flags saturation; binding errors name the device and the element.
#include "lab/devices/device_arm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "mujoco_fixture.h"

namespace vlab::lab::arm_device_test {
namespace {

using bridge::ArmCommand;
using bridge::ArmMode;
using bridge::ArmState;

constexpr double kPeriod = 0.002;  // control period of the default scenario
const std::vector<std::string> kJoints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
// "ready" pose of pa10_reach.yaml: no contact, every joint well inside its range
const std::vector<double> kReady = {0, 0.523599, 0, 1.047198, 0, 1.570796, 0};

DeviceConfig ArmConfig() {
  DeviceConfig c;
  c.name = "pa10";
  c.kind = bridge::DeviceKind::kArm;
  c.where = "arm.yaml:9";
  c.EditParams<ArmParams>().joints = kJoints;
  c.EditParams<ArmParams>().actuators = kJoints;
  c.EditParams<ArmParams>().initial = kReady;
  return c;
}

ArmCommand Cmd(ArmMode mode, std::vector<double> v) {
  ArmCommand c;
  c.mode = mode;
  c.value = Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  return c;
}

// The lab's sequence: initial state, servo start, then physics steps with the
// servo between mj_step1 and mj_step2. The fixture fails the test on any MuJoCo warning.
class ArmDeviceTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/pa10.xml");
    data_ = MakeData(model_);
    arm_ = SimArm::Create({model_, kPeriod, 1, "pa10.xml"}, ArmConfig());
    mj_resetData(m(), d());
    arm_->SetInitialState(*d());
    mj_forward(m(), d());
    arm_->Start(*d());
  }
  const mjModel* m() const { return model_; }
  mjData* d() { return data_; }
  double q(int i) { return d()->qpos[m()->jnt_qposadr[mj_name2id(m(), mjOBJ_JOINT, kJoints[i].c_str())]]; }
  double ctrl(int i) { return d()->ctrl[mj_name2id(m(), mjOBJ_ACTUATOR, kJoints[i].c_str())]; }
  // Runs `seconds` of physics (whole control periods), re-sending `cmd` every period if given.
  void Run(double seconds, const ArmCommand* cmd = nullptr) {
    const int steps = static_cast<int>(std::lround(kPeriod / m()->opt.timestep));
    for (long k = 0; k < std::lround(seconds / kPeriod); ++k) {
      if (cmd) {
        EXPECT_TRUE(arm_->Command(*cmd));
      }
      for (int i = 0; i < steps; ++i) {
        mj_step1(m(), d());
        arm_->Actuate(*d(), m()->opt.timestep);
        mj_step2(m(), d());
      }
    }
  }
  ArmState Sample() {
    ArmState s;
    arm_->Sample(*d(), d()->time, &s);
    return s;
  }

  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::unique_ptr<SimArm> arm_;
};

TEST_F(ArmDeviceTest, HoldsInitialPositionWithoutCommand) {
  ASSERT_EQ(arm_->dof(), 7);
  EXPECT_TRUE(Sample().status & bridge::kArmHolding);
  Run(2.0);
  // tau = kp (q0 - q) - kd qd + qfrc_bias(q, qd): the feed-forward is MuJoCo's own
  // bias force at the current state, so starting at rest on q0 the closed loop is
  // M qdd = -kp e - kd qd with e = qd = 0, and the arm stays put up to round-off.
  // A feed-forward error of dh N·m would show as a static offset dh / kp; with
  // kp >= 0.006 * (2 pi 10)^2 ~ 24 N·m/rad (wrist) an offset of 1e-9 rad means
  // a torque error below 3e-8 N·m, i.e. none: gravity on the wrist alone is ~1 N·m.
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(q(i), kReady[i], 1e-9) << kJoints[i];
  const ArmState s = Sample();
  EXPECT_TRUE(s.status & bridge::kArmHolding);
  EXPECT_FALSE(s.status & bridge::kArmTorqueSaturated);
  EXPECT_FALSE(s.status & bridge::kArmCommandRefused);
  EXPECT_EQ(arm_->refused_commands(), 0);
  // the holding torque is the gravity load: S2 and E1 carry the arm, S1 (vertical axis) nothing
  EXPECT_GT(std::abs(s.tau[1]), 10.0);
  EXPECT_NEAR(s.tau[0], 0.0, 1e-6);
  for (int i = 0; i < 7; ++i) EXPECT_DOUBLE_EQ(s.tau[i], ctrl(i));
}

TEST_F(ArmDeviceTest, RefusesBadCommandsAndKeepsThePreviousOne) {
  const double rate = 0.2;  // rad/s on S1
  const ArmCommand good = Cmd(ArmMode::kVelocity, {rate, 0, 0, 0, 0, 0, 0});
  ASSERT_TRUE(arm_->Command(good));
  Run(0.5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double s2_max = 94.0 * M_PI / 180.0;
  const std::vector<std::pair<std::string, ArmCommand>> bad = {
      {"wrong size", Cmd(ArmMode::kVelocity, {rate, 0, 0, 0, 0, 0})},
      {"empty", Cmd(ArmMode::kTorque, {})},
      {"NaN", Cmd(ArmMode::kVelocity, {0, 0, 0, 0, 0, 0, nan})},
      {"Inf", Cmd(ArmMode::kPosition, {0, 0.5, 0, 1, 0, inf, 0})},
      {"beyond joint limit", Cmd(ArmMode::kPosition, {0, s2_max + 0.01, 0, 1, 0, 1.5, 0})},
      {"below joint limit", Cmd(ArmMode::kPosition, {0, -s2_max - 0.01, 0, 1, 0, 1.5, 0})},
      {"beyond motor range", Cmd(ArmMode::kTorque, {0, 0, 0, 0, 15.5, 0, 0})},  // E2: +-15 N·m
      {"below motor range", Cmd(ArmMode::kTorque, {-201, 0, 0, 0, 0, 0, 0})},   // S1: +-200 N·m
  };
  long refused = 0;
  for (const auto& [what, cmd] : bad) {
    EXPECT_FALSE(arm_->Command(cmd)) << what;
    EXPECT_EQ(arm_->refused_commands(), ++refused) << what;
    EXPECT_TRUE(Sample().status & bridge::kArmCommandRefused) << what;
    // still the velocity command: S1 advances at its rate
    const double q0 = q(0);
    Run(0.2);
    EXPECT_NEAR((q(0) - q0) / 0.2, rate, 0.01 * rate) << what;
    EXPECT_FALSE(Sample().status & bridge::kArmHolding) << what;
  }
  // a good command clears the flag
  EXPECT_TRUE(arm_->Command(good));
  EXPECT_FALSE(Sample().status & bridge::kArmCommandRefused);
  EXPECT_EQ(arm_->refused_commands(), refused);
}

TEST_F(ArmDeviceTest, VelocityModeMovesAtCommandedRate) {
  // S1 (vertical axis, no gravity torque) and E2 (forearm roll) at once
  const ArmCommand cmd = Cmd(ArmMode::kVelocity, {0.3, 0, 0, 0, -0.5, 0, 0});
  ASSERT_TRUE(arm_->Command(cmd));
  Run(0.5);  // the servo settles in ~5 / (2 pi 10 Hz) = 0.08 s
  const double s1 = q(0), e2 = q(4), s2 = q(1);
  Run(1.0);
  EXPECT_NEAR(q(0) - s1, 0.3, 0.3 * 0.02);
  EXPECT_NEAR(q(4) - e2, -0.5, 0.5 * 0.02);
  EXPECT_NEAR(q(1), s2, 1e-3);  // commanded 0: stays
  EXPECT_NEAR(Sample().qd[0], 0.3, 0.3 * 0.02);
  EXPECT_FALSE(Sample().status & bridge::kArmTorqueSaturated);
}

TEST_F(ArmDeviceTest, PositionModeConverges) {
  std::vector<double> target = kReady;
  const std::vector<double> offset = {0.01, -0.01, 0.008, 0.01, -0.02, 0.02, 0.03};
  for (int i = 0; i < 7; ++i) target[i] += offset[i];
  const ArmCommand cmd = Cmd(ArmMode::kPosition, target);
  Run(2.0, &cmd);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(q(i), target[i], 1e-6) << kJoints[i];
  const ArmState s = Sample();
  EXPECT_FALSE(s.status & bridge::kArmHolding);
  EXPECT_LT(s.qd.norm(), 1e-5);
}

TEST_F(ArmDeviceTest, TorqueModeAppliesCommandExactly) {
  const std::vector<double> tau = {1.25, -3.5, 0.75, 2.0, -0.125, 0.5, -0.0625};
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kTorque, tau)));
  Run(0.01);
  const ArmState s = Sample();
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(ctrl(i), tau[i]) << kJoints[i];
    EXPECT_EQ(s.tau[i], tau[i]) << kJoints[i];
  }
  EXPECT_FALSE(s.status & bridge::kArmTorqueSaturated);
  EXPECT_FALSE(s.status & bridge::kArmHolding);
  // the commanded torque is what acts on the joint: actuator force = ctrl (gear 1)
  for (int i = 0; i < 7; ++i)
    EXPECT_EQ(d()->actuator_force[mj_name2id(m(), mjOBJ_ACTUATOR, kJoints[i].c_str())], tau[i]);
  // the extremes of the motor range are accepted as is
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kTorque, {200, -200, 80, -80, 15, -15, 10})));
  Run(kPeriod);
  EXPECT_EQ(ctrl(0), 200.0);
  EXPECT_EQ(ctrl(6), 10.0);
}

TEST_F(ArmDeviceTest, FarPositionTargetSaturatesAndIsFlagged) {
  std::vector<double> target = kReady;
  target[0] += 1.0;  // S1: kp * 1 rad is far beyond 200 N·m
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kPosition, target)));
  Run(kPeriod);
  EXPECT_GT(arm_->kp()[0] * 1.0, 200.0 * 2);  // premise of the test
  EXPECT_EQ(ctrl(0), 200.0);
  const ArmState s = Sample();
  EXPECT_EQ(s.tau[0], 200.0);
  EXPECT_TRUE(s.status & bridge::kArmTorqueSaturated);
  // the other joints hold and stay inside their ranges
  for (int i = 1; i < 7; ++i) EXPECT_LE(std::abs(ctrl(i)), std::abs(m()->actuator_ctrlrange[2 * i + 1]));
}

TEST_F(ArmDeviceTest, GainsFollowBandwidthRule) {
  const double w = 2 * M_PI * 10.0;
  for (int i = 0; i < 7; ++i) {
    const int dof = m()->jnt_dofadr[mj_name2id(m(), mjOBJ_JOINT, kJoints[i].c_str())];
    const double inertia = d()->qM[m()->dof_Madr[dof]];
    EXPECT_DOUBLE_EQ(arm_->kp()[i], inertia * w * w);
    EXPECT_DOUBLE_EQ(arm_->kd()[i], 2 * 1.0 * inertia * w);
  }
}

// log_command: the command in force as NAME.cmd_mode and NAME.cmd.JOINT after the arm's other
// columns; hold logs the position held, a refused command leaves the one before
TEST_F(ArmDeviceTest, LogsTheCommandInForce) {
  const std::vector<std::string> plain = arm_->Columns();
  EXPECT_EQ(plain.size(), 22u);  // without the key: q, qd, tau, limit_violation only
  DeviceConfig config = ArmConfig();
  config.EditParams<ArmParams>().log_command = true;
  arm_ = SimArm::Create({model_, kPeriod, 1, "pa10.xml"}, config);
  mj_resetData(m(), d());
  arm_->SetInitialState(*d());
  mj_forward(m(), d());
  arm_->Start(*d());
  const std::vector<std::string> columns = arm_->Columns();
  ASSERT_EQ(static_cast<int>(columns.size()), arm_->ColumnCount());
  ASSERT_EQ(columns.size(), 30u);
  EXPECT_EQ(columns[22], "pa10.cmd_mode");
  EXPECT_EQ(columns[23], "pa10.cmd.S1");
  EXPECT_EQ(columns[29], "pa10.cmd.W2");
  std::vector<double> row(columns.size());
  auto logged = [&](double mode, const std::vector<double>& value, const char* what) {
    arm_->Row(*d(), row.data());
    EXPECT_EQ(row[22], mode) << what;
    for (int i = 0; i < 7; ++i) EXPECT_EQ(row[23 + i], value[i]) << what << " " << kJoints[i];
  };
  logged(0, kReady, "holding the start");
  std::vector<double> target = kReady;
  target[0] += 0.05;
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kPosition, target)));
  Run(0.01);
  logged(1, target, "position");
  std::vector<double> beyond = target;
  beyond[1] = 2.0;  // beyond S2's range: refused
  EXPECT_FALSE(arm_->Command(Cmd(ArmMode::kPosition, beyond)));
  logged(1, target, "after a refused position");
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kHold, {})));
  Run(0.01);
  logged(0, target, "hold after a position");
  const std::vector<double> rate = {0.1, 0, 0, 0, -0.2, 0, 0};
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kVelocity, rate)));
  Run(0.01);
  logged(2, rate, "velocity");
  const std::vector<double> tau = {1.0, -2.0, 0.5, 0, 0, 0, 0.25};
  ASSERT_TRUE(arm_->Command(Cmd(ArmMode::kTorque, tau)));
  Run(0.002);
  logged(3, tau, "torque");
}

// ---- binding errors --------------------------------------------------------

std::string CreateError(const mjModel* m, const DeviceConfig& c) {
  try {
    SimArm::Create({m, 0.002, 1, "scene"}, c);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

class ArmDeviceCreateTest : public test::MujocoTest {};

TEST_F(ArmDeviceCreateTest, ErrorsNameDeviceAndElement) {
  const mjModel* model = LoadModel("scenes/pa10.xml");
  DeviceConfig c = ArmConfig();
  c.EditParams<ArmParams>().joints[3] = "E9";
  std::string e = CreateError(model, c);
  EXPECT_NE(e.find("arm.yaml:9"), std::string::npos) << e;
  EXPECT_NE(e.find("device 'pa10'"), std::string::npos) << e;
  EXPECT_NE(e.find("no joint 'E9'"), std::string::npos) << e;

  c = ArmConfig();
  c.EditParams<ArmParams>().actuators[6] = "W2_motor";
  e = CreateError(model, c);
  EXPECT_NE(e.find("device 'pa10'"), std::string::npos) << e;
  EXPECT_NE(e.find("no actuator 'W2_motor'"), std::string::npos) << e;

  c = ArmConfig();
  std::swap(c.EditParams<ArmParams>().actuators[0],
            c.EditParams<ArmParams>().actuators[1]);  // motors exist, but on the wrong joints
  e = CreateError(model, c);
  EXPECT_NE(e.find("actuator 'S2' is not a motor on joint 'S1'"), std::string::npos) << e;

  c = ArmConfig();
  c.EditParams<ArmParams>().initial[1] = 2.0;  // S2 range is +-94 deg = +-1.64 rad
  e = CreateError(model, c);
  EXPECT_NE(e.find("initial position of joint 'S2'"), std::string::npos) << e;
}

TEST_F(ArmDeviceCreateTest, RejectsNonMotorActuators) {
  const mjModel* model = LoadModelFromString("servo.xml", R"(
<mujoco>
  <worldbody>
    <body>
      <joint name="a" type="hinge" range="-1 1" limited="true"/>
      <geom type="sphere" size="0.1" mass="1"/>
      <body pos="0.3 0 0">
        <joint name="b" type="hinge" range="-1 1" limited="true"/>
        <geom type="sphere" size="0.1" mass="1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="pos_a" joint="a" kp="10"/>
    <motor name="geared_b" joint="b" gear="2"/>
    <motor name="motor_a" joint="a"/>
  </actuator>
</mujoco>)");
  DeviceConfig c;
  c.name = "toy";
  c.kind = bridge::DeviceKind::kArm;
  c.where = "toy.yaml:3";
  c.EditParams<ArmParams>().joints = {"a"};
  c.EditParams<ArmParams>().actuators = {"pos_a"};
  std::string e = CreateError(model, c);
  EXPECT_NE(e.find("device 'toy'"), std::string::npos) << e;
  EXPECT_NE(e.find("actuator 'pos_a' is not a motor on joint 'a'"), std::string::npos) << e;
  c.EditParams<ArmParams>().joints = {"b"};
  c.EditParams<ArmParams>().actuators = {"geared_b"};
  e = CreateError(model, c);
  EXPECT_NE(e.find("actuator 'geared_b' must have gear 1"), std::string::npos) << e;
  c.EditParams<ArmParams>().joints = {"a"};
  c.EditParams<ArmParams>().actuators = {"motor_a"};
  EXPECT_EQ(CreateError(model, c), "");  // the control: a plain motor binds
}

}  // namespace
}  // namespace vlab::lab::arm_device_test
