// Tests the base, feet and imu devices (src/lab/devices/device_base.cc,
// device_sensors.cc): a holonomic base on planar joints with velocity
// actuators tracks commands within its acceleration limits, in the base and
// the world frame, brakes on hold, keeps exact odometry without drift and a
// seeded, repeatable drift with it; touch sensors under a resting body sum to
// its weight and an IMU at rest reads +g. Then the same base served over UDP
// in lockstep, commanded by the generic client.
#include <algorithm>
#include <cmath>
#include <future>
#include <thread>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_base.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_sensors.h"
#include "lab/run/lab_runner.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::base_device_test {
namespace {

// the base's state payload (docs/protocol.md)
constexpr int kStatus = bridge::StateIndex(bridge::DeviceKind::kBase, "status");
constexpr int kX = bridge::StateIndex(bridge::DeviceKind::kBase, "x");
constexpr int kY = bridge::StateIndex(bridge::DeviceKind::kBase, "y");
constexpr int kYaw = bridge::StateIndex(bridge::DeviceKind::kBase, "yaw");
constexpr int kVx = bridge::StateIndex(bridge::DeviceKind::kBase, "vx");
constexpr int kVy = bridge::StateIndex(bridge::DeviceKind::kBase, "vy");
constexpr int kWz = bridge::StateIndex(bridge::DeviceKind::kBase, "wz");

// 40 kg base on x, y, yaw joints; four feet with touch sensors; an IMU.
constexpr const char* kBaseXml = R"(
<mujoco>
  <option timestep="0.001"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="base" pos="0 0 0.1">
      <joint name="bx" type="slide" axis="1 0 0" damping="1"/>
      <joint name="by" type="slide" axis="0 1 0" damping="1"/>
      <joint name="byaw" type="hinge" axis="0 0 1" damping="1"/>
      <geom type="box" size="0.3 0.3 0.1" mass="40" contype="0" conaffinity="0"/>
      <site name="imu" pos="0 0 0.05"/>
    </body>
    <body name="block" pos="2 2 0.1">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" mass="5" contype="0" conaffinity="0"/>
      <geom name="f1" type="sphere" size="0.01" pos=" 0.09  0.09 -0.1" mass="0.01"/>
      <geom name="f2" type="sphere" size="0.01" pos="-0.09  0.09 -0.1" mass="0.01"/>
      <geom name="f3" type="sphere" size="0.01" pos=" 0.09 -0.09 -0.1" mass="0.01"/>
      <geom name="f4" type="sphere" size="0.01" pos="-0.09 -0.09 -0.1" mass="0.01"/>
      <site name="s1" type="sphere" size="0.02" pos=" 0.09  0.09 -0.1"/>
      <site name="s2" type="sphere" size="0.02" pos="-0.09  0.09 -0.1"/>
      <site name="s3" type="sphere" size="0.02" pos=" 0.09 -0.09 -0.1"/>
      <site name="s4" type="sphere" size="0.02" pos="-0.09 -0.09 -0.1"/>
      <site name="block_imu" pos="0 0 0"/>
    </body>
  </worldbody>
  <actuator>
    <velocity name="vx" joint="bx" kv="4000"/>
    <velocity name="vy" joint="by" kv="4000"/>
    <velocity name="wz" joint="byaw" kv="400"/>
  </actuator>
  <sensor>
    <touch name="t1" site="s1"/> <touch name="t2" site="s2"/> <touch name="t3" site="s3"/> <touch name="t4" site="s4"/>
    <gyro name="gyro" site="block_imu"/> <accelerometer name="acc" site="block_imu"/>
  </sensor>
</mujoco>)";

DeviceConfig BaseConfig(bool drift) {
  DeviceConfig c;
  c.name = "nomad";
  c.kind = bridge::DeviceKind::kBase;
  c.where = "test.yaml:1";
  c.EditParams<BaseParams>().joints = {"bx", "by", "byaw"};
  c.EditParams<BaseParams>().actuators = {"vx", "vy", "wz"};
  c.EditParams<BaseParams>().max_velocity = {1.0, 1.0, 2.0};
  c.EditParams<BaseParams>().max_acceleration = {1.0, 1.0, 2.0};
  c.EditParams<BaseParams>().odometry_drift = drift;
  c.EditParams<BaseParams>().drift_scale = 0.02;
  c.EditParams<BaseParams>().drift_yaw_rate = 0.01;
  return c;
}

// The base on a model and data the fixture owns.
struct Rig {
  mjModel* model;
  mjData* data;
  std::unique_ptr<Device> base;
  Rig(mjModel* m, mjData* d, bool drift, std::uint64_t seed) : model(m), data(d) {
    base = MakeDevice({model, 0.002, seed, ""}, BaseConfig(drift));
    mj_forward(model, data);
    base->Reset(*data);
  }
  // one control period of 10 ms
  void Period() {
    for (int i = 0; i < 10; ++i) {
      mj_step1(model, data);
      base->step_hooks()->Actuate(*data, 0.001);
      mj_step2(model, data);
    }
    base->Sample(*data, data->time);
  }
  std::vector<double> State() const {
    std::vector<double> s;
    base->State(&s);
    return s;
  }
};

class BaseDeviceTest : public test::MujocoTest {
 protected:
  Rig NewRig(bool drift = false, std::uint64_t seed = 7) {
    mjModel* m = LoadModelFromString("base.xml", kBaseXml);
    return Rig(m, MakeData(m), drift, seed);
  }
};

class SensorDeviceTest : public test::MujocoTest {};

// the wire index of the sensor value `name` ("acc.z") in the state of a feet or imu device
int SensorValueIndex(const Device& device, const std::string& name) {
  const nlohmann::json state = nlohmann::json::parse(device.DescribeFacts()).at("layout").at("state");
  const auto it = std::find(state.begin(), state.end(), name);
  return it == state.end() ? -1 : static_cast<int>(it - state.begin());
}

TEST_F(BaseDeviceTest, TracksABaseFrameCommandWithinTheAccelerationLimit) {
  Rig rig = NewRig();
  EXPECT_EQ(rig.State()[kStatus], static_cast<double>(bridge::kStatusHolding));
  rig.base->command_input()->Command({0, 0.5, 0, 0});
  rig.Period();  // 10 ms at 1 m/s^2: at most 0.01 m/s
  EXPECT_LE(rig.State()[kVx], 0.0101);
  EXPECT_GT(rig.State()[kVx], 0.002);          // moving, behind the reference by the servo lag (10 ms)
  for (int k = 0; k < 100; ++k) rig.Period();  // 1 s: long reached 0.5 m/s
  const std::vector<double> s = rig.State();
  EXPECT_EQ(s[kStatus], 0.0);
  EXPECT_NEAR(s[kVx], 0.5, 0.005);
  EXPECT_NEAR(s[kVy], 0.0, 1e-3);
  // position after the ramp (0.5 s, 0.125 m) and 0.51 s at 0.5 m/s, within the servo lag
  EXPECT_NEAR(s[kX], 0.125 + 0.5 * 0.51, 0.01);
}

TEST_F(BaseDeviceTest, BaseFrameFollowsTheYawWorldFrameDoesNot) {
  Rig rig = NewRig();
  rig.data->qpos[2] = M_PI / 2;  // facing +y
  mj_forward(rig.model, rig.data);
  rig.base->Reset(*rig.data);
  rig.base->command_input()->Command({0, 0.3, 0, 0});  // forward = world +y
  for (int k = 0; k < 150; ++k) rig.Period();
  EXPECT_NEAR(rig.data->qvel[0], 0.0, 2e-3);
  EXPECT_NEAR(rig.data->qvel[1], 0.3, 3e-3);
  rig.base->command_input()->Command({1, 0.3, 0, 0});  // world +x, whatever the yaw
  for (int k = 0; k < 150; ++k) rig.Period();
  EXPECT_NEAR(rig.data->qvel[0], 0.3, 3e-3);
  EXPECT_NEAR(rig.data->qvel[1], 0.0, 2e-3);
  EXPECT_NEAR(rig.State()[kVy], -0.3, 3e-3);  // seen from the base: to its right
}

TEST_F(BaseDeviceTest, HoldBrakesAtTheAccelerationLimit) {
  Rig rig = NewRig();
  rig.base->command_input()->Command({0, 0.8, 0, 1.0});
  for (int k = 0; k < 120; ++k) rig.Period();
  rig.base->command_input()->Hold();
  for (int k = 0; k < 40; ++k) rig.Period();  // 0.4 s of 0.8 s needed to stop
  EXPECT_NEAR(std::hypot(rig.State()[kVx], rig.State()[kVy]), 0.4, 0.02);
  for (int k = 0; k < 60; ++k) rig.Period();
  for (int i : {kVx, kVy, kWz}) EXPECT_NEAR(rig.State()[i], 0.0, 1e-3);
  EXPECT_EQ(rig.State()[kStatus], static_cast<double>(bridge::kStatusHolding));
}

TEST_F(BaseDeviceTest, OdometryIsExactWithoutDriftAndSeededWithIt) {
  Rig exact = NewRig(), drift_a = NewRig(true, 7), drift_b = NewRig(true, 7), drift_c = NewRig(true, 8);
  for (Rig* r : {&exact, &drift_a, &drift_b, &drift_c}) {
    r->base->command_input()->Command({0, 0.4, 0.1, 0.5});
    for (int k = 0; k < 300; ++k) r->Period();
  }
  const std::vector<double> e = exact.State();
  EXPECT_NEAR(e[kX], exact.data->qpos[0], 1e-12);  // the joints bx, by, byaw
  EXPECT_NEAR(e[kY], exact.data->qpos[1], 1e-12);
  EXPECT_NEAR(e[kYaw], exact.data->qpos[2], 1e-12);
  const std::vector<double> a = drift_a.State(), b = drift_b.State(), c = drift_c.State();
  EXPECT_EQ(a, b);  // same seed: the same drift, bit for bit
  EXPECT_NE(a[kX], c[kX]);
  const double error = std::hypot(a[kX] - drift_a.data->qpos[0], a[kY] - drift_a.data->qpos[1]);
  EXPECT_GT(error, 1e-5);  // it drifts ...
  EXPECT_LT(error, 0.2);   // ... by a few percent of the 1.2 m travelled at most
}

TEST_F(BaseDeviceTest, ChecksCommands) {
  Rig rig = NewRig();
  EXPECT_EQ(rig.base->command_input()->command_length(), 4);
  EXPECT_EQ(rig.base->command_input()->CheckCommand({0, 1.0, -1.0, 2.0}), bridge::CommandCheck::kAccept);
  EXPECT_EQ(rig.base->command_input()->CheckCommand({2, 0, 0, 0}), bridge::CommandCheck::kMalformed);
  EXPECT_EQ(rig.base->command_input()->CheckCommand({0.5, 0, 0, 0}), bridge::CommandCheck::kMalformed);
  EXPECT_EQ(rig.base->command_input()->CheckCommand({1, 1.01, 0, 0}), bridge::CommandCheck::kLimits);
  EXPECT_EQ(rig.base->command_input()->CheckCommand({1, 0, 0, -2.5}), bridge::CommandCheck::kLimits);
}

TEST_F(BaseDeviceTest, BadBindingsNameTheElement) {
  mjModel* model = LoadModelFromString("base.xml", kBaseXml);
  DeviceConfig c = BaseConfig(false);
  c.EditParams<BaseParams>().joints[2] = "nope";
  EXPECT_THROW(
      {
        try {
          MakeDevice({model, 0.002, 1, ""}, c);
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("no joint 'nope'"), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);
  c = BaseConfig(false);
  c.EditParams<BaseParams>().joints = {"by", "bx", "bx"};  // yaw must be a hinge
  EXPECT_THROW(MakeDevice({model, 0.002, 1, ""}, c), InputError);
  c = BaseConfig(false);
  c.EditParams<BaseParams>().actuators = {"vy", "vx", "wz"};  // actuators of the wrong joints
  EXPECT_THROW(MakeDevice({model, 0.002, 1, ""}, c), InputError);
  DeviceConfig feet;
  feet.name = "feet";
  feet.kind = bridge::DeviceKind::kFeet;
  feet.EditParams<SensorParams>().sensors = {"t1", "gyro"};  // a gyro is no foot sensor
  EXPECT_THROW(MakeDevice({model, 0.002, 1, ""}, feet), InputError);
}

TEST_F(SensorDeviceTest, FeetCarryTheWeightAndTheImuReadsGravity) {
  mjModel* model = LoadModelFromString("base.xml", kBaseXml);
  mjData* data = MakeData(model);
  DeviceConfig feet;
  feet.name = "feet";
  feet.kind = bridge::DeviceKind::kFeet;
  feet.EditParams<SensorParams>().sensors = {"t1", "t2", "t3", "t4"};
  DeviceConfig imu;
  imu.name = "imu";
  imu.kind = bridge::DeviceKind::kImu;
  imu.EditParams<SensorParams>().sensors = {"gyro", "acc"};
  auto f = MakeDevice({model, 0.002, 1, ""}, feet);
  auto i = MakeDevice({model, 0.002, 1, ""}, imu);
  EXPECT_EQ(f->Columns().size(), 4u);
  EXPECT_EQ(i->Columns(), (std::vector<std::string>{"imu.gyro.x", "imu.gyro.y", "imu.gyro.z", "imu.acc.x", "imu.acc.y",
                                                    "imu.acc.z"}));
  for (int k = 0; k < 2000; ++k) mj_step(model, data);
  f->Sample(*data, data->time);
  i->Sample(*data, data->time);
  std::vector<double> forces, imu_values;
  f->State(&forces);
  i->State(&imu_values);
  double sum = 0;
  for (double v : forces) sum += v;
  const double weight = 5.04 * 9.81;  // box and the four feet
  EXPECT_NEAR(sum, weight, 0.005 * weight);
  for (double v : forces) EXPECT_NEAR(v, weight / 4, 0.05 * weight);  // symmetric
  for (const char* axis : {"gyro.x", "gyro.y", "gyro.z"}) {
    const int k = SensorValueIndex(*i, axis);
    ASSERT_GE(k, 0) << axis;
    EXPECT_NEAR(imu_values[k], 0.0, 1e-3) << axis;
  }
  const int acc_z = SensorValueIndex(*i, "acc.z");
  ASSERT_GE(acc_z, 0);
  EXPECT_NEAR(imu_values[acc_z], 9.81, 0.01);
}

// The base in a lockstep lab, commanded over UDP by the generic client.
TEST(BaseServeTest, LockstepCommandsOverUdpMoveTheBase) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir.path() + "/base.xml", kBaseXml);
  vlab::testing::WriteFile(dir.path() + "/base.yaml", R"(
scene: base.xml
duration: 1.2
control_period: 0.01
clock: lockstep
lockstep: {timeout: 0.05, release_after: 100}  # the controller keeps the base through its silence
devices:
  - {name: nomad, kind: base, joints: [bx, by, byaw], actuators: [vx, vy, wz], port: 0}
  - {name: feet, kind: feet, sensors: [t1, t2, t3, t4], port: 0}
checks:
  - {name: moved, signal: nomad.true_x, reduce: final, min: 0.3}
)");
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(dir.path() + "/base.yaml"));
  BridgeOptions bo;
  bo.ports = {{"nomad", 0}, {"feet", 0}};
  std::promise<std::vector<ServedDevice>> served;
  RunOptions ro;
  ro.serve = &bo;
  ro.on_serving = [&](const std::vector<ServedDevice>& d) { served.set_value(d); };
  RunResult result;
  std::thread run([&] { result = lab->Run(ro); });
  const std::vector<ServedDevice> devices = served.get_future().get();
  ASSERT_EQ(devices.size(), 2u);
  auto base = bridge::Device::Connect(bridge::DeviceKind::kBase, "127.0.0.1", devices[0].port, 5.0);
  auto feet = bridge::Device::Connect(bridge::DeviceKind::kFeet, "127.0.0.1", devices[1].port, 5.0);
  EXPECT_EQ(base.command_length(), 4);
  EXPECT_EQ(base.state_length(), 7);
  EXPECT_EQ(feet.state_length(), 4);
  EXPECT_EQ(base.describe()["kind"], "base");
  bridge::Device::State s = base.Read(5.0), at_1s;
  std::uint32_t silent_status = 0;
  while (s.seq < 120) {
    if (s.seq == 100) at_1s = s;
    // periods 100-105 unanswered: the lab waits 0.05 s for each, and the watchdog holds the base
    if (s.seq < 100 || s.seq >= 106) base.Write({1, 0.5, 0, 0}, s.seq);  // world x at 0.5 m/s
    s = base.Read(5.0);
    if (s.seq > 104 && s.seq <= 106) silent_status |= static_cast<std::uint32_t>(s.values[0]);
  }
  run.join();
  EXPECT_EQ(result.exit_code, 0) << result.failure;
  EXPECT_EQ(result.periods, 120);
  EXPECT_NEAR(at_1s.values[kX], 0.125 + 0.5 * 0.5, 0.02);  // odometry x after the ramp and 0.5 s at speed
  EXPECT_NEAR(at_1s.values[kVx], 0.5, 0.01);
  // the endpoint's bits are in the base's status word, as in an arm's
  EXPECT_EQ(silent_status & (bridge::kStatusWatchdog | bridge::kStatusHolding),
            bridge::kStatusWatchdog | bridge::kStatusHolding);
  EXPECT_EQ(static_cast<std::uint32_t>(s.values[0]) & bridge::kStatusWatchdog, 0u) << "commands end the hold";
}

}  // namespace
}  // namespace vlab::lab::base_device_test
