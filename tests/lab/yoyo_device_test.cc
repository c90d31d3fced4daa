// Tests the yoyo device (src/lab/devices/device_yoyo.cc) in scenes/pa10_yoyo.xml:
// its values against the model's state and the closed forms of DATASHEET §6.3
// (centre = hand - d along the hand's z, tension = sum of the two sensors, zero
// when slack, T = m g J / (J + m r²) while descending), the 25 Hz sample and
// hold, seeded noise; the JR3 under the yo-yo hanging at rest; the scene's arm
// equal to scenes/pa10.xml's; and the point and yoyo devices served in
// lockstep, the hand moved up 5 cm by the generic client.
#include <cmath>
#include <future>
#include <thread>

#include <gtest/gtest.h>

#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_yoyo.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_yoyo.h"
#include "lab/run/lab_runner.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::yoyo_device_test {
namespace {

constexpr const char* kScene = VLAB_SOURCE_DIR "/scenes/pa10_yoyo.xml";

// the yoyo's and the point device's state payloads (docs/protocol.md)
constexpr int kStatus = bridge::StateIndex(bridge::DeviceKind::kYoyo, "status");
constexpr int kX = bridge::StateIndex(bridge::DeviceKind::kYoyo, "x");
constexpr int kY = bridge::StateIndex(bridge::DeviceKind::kYoyo, "y");
constexpr int kZ = bridge::StateIndex(bridge::DeviceKind::kYoyo, "z");
constexpr int kVz = bridge::StateIndex(bridge::DeviceKind::kYoyo, "vz");
constexpr int kStringForce = bridge::StateIndex(bridge::DeviceKind::kYoyo, "string_force");
constexpr int kSpin = bridge::StateIndex(bridge::DeviceKind::kYoyo, "spin");
static_assert(kY == kX + 1 && kZ == kX + 2, "x, y, z follow each other");
constexpr int kPointStatus = bridge::StateIndex(bridge::DeviceKind::kPoint, "status");
constexpr int kPointX = bridge::StateIndex(bridge::DeviceKind::kPoint, "x");
constexpr int kPointY = bridge::StateIndex(bridge::DeviceKind::kPoint, "y");
constexpr int kPointZ = bridge::StateIndex(bridge::DeviceKind::kPoint, "z");

DeviceConfig YoyoConfig(double rate_hz = 0, double noise = 0) {
  DeviceConfig c;
  c.name = "yoyo";
  c.kind = bridge::DeviceKind::kYoyo;
  c.where = "test.yaml:1";
  c.EditParams<YoyoParams>().rate_hz = rate_hz;
  c.EditParams<YoyoParams>().noise = noise;
  return c;
}

// The arm holding its ready pose with the yo-yo under its tool, from a keyframe,
// on a model and data the fixture owns.
struct Rig {
  mjModel* model;
  mjData* data;
  std::unique_ptr<SimArm> arm;
  std::unique_ptr<Device> yoyo;

  Rig(mjModel* m, mjData* d, const char* keyframe, double rate_hz, double noise, std::uint64_t seed)
      : model(m), data(d) {
    DeviceConfig a;
    a.name = "pa10";
    a.kind = bridge::DeviceKind::kArm;
    a.EditParams<ArmParams>().joints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
    a.EditParams<ArmParams>().actuators = a.EditParams<ArmParams>().joints;
    arm = SimArm::Create({model, 0.01, 1, kScene}, a);
    yoyo = MakeDevice({model, 0.002, seed, ""}, YoyoConfig(rate_hz, noise));
    mj_resetDataKeyframe(model, data, mj_name2id(model, mjOBJ_KEY, keyframe));
    mj_forward(model, data);
    arm->Start(*data);
    yoyo->Reset(*data);
  }
  void Run(double seconds) {
    for (long i = std::lround(seconds / 0.001); i > 0; --i) {
      mj_step1(model, data);
      arm->Actuate(*data, 0.001);
      mj_step2(model, data);
    }
    mj_forward(model, data);  // kinematics and sensors of the state reached
  }
  std::vector<double> State() const {
    std::vector<double> s;
    yoyo->State(&s);
    return s;
  }
  int Id(mjtObj type, const char* name) const { return mj_name2id(model, type, name); }
  double Sensor(const char* name) const { return data->sensordata[model->sensor_adr[Id(mjOBJ_SENSOR, name)]]; }
  double Drop() const { return data->qpos[model->jnt_qposadr[Id(mjOBJ_JOINT, "yoyo_drop")]]; }
};

class YoyoDeviceTest : public test::MujocoTest {
 protected:
  Rig NewRig(const char* keyframe, double rate_hz = 0, double noise = 0, std::uint64_t seed = 3) {
    mjModel* m = LoadModel(kScene);
    return Rig(m, MakeData(m), keyframe, rate_hz, noise, seed);
  }
};

class YoyoSceneTest : public test::MujocoTest {};

TEST_F(YoyoDeviceTest, ValuesAreTheModelsStateAndTheDescentsClosedForms) {
  Rig rig = NewRig("ready");  // wound, taut, at rest
  rig.Run(0.5);               // descending on the string
  rig.yoyo->Sample(*rig.data, 0.5);
  const std::vector<double> s = rig.State();
  ASSERT_EQ(s.size(), bridge::kYoyoStateLayout.size());
  EXPECT_EQ(s[kStatus], 0.0);
  // centre = hand origin - d along the hand frame's z (the string's line)
  const int hand = rig.Id(mjOBJ_BODY, "yoyo_hand");
  const Eigen::Vector3d p_hand = Eigen::Map<const Eigen::Vector3d>(rig.data->xpos + 3 * hand);
  const Eigen::Vector3d z_hand(rig.data->xmat[9 * hand + 2], rig.data->xmat[9 * hand + 5],
                               rig.data->xmat[9 * hand + 8]);
  const double d = rig.Drop();
  const Eigen::Vector3d centre = p_hand - d * z_hand;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s[kX + i], centre[i], 1e-12);
  EXPECT_NEAR(z_hand.z(), 1.0, 1e-9);  // the tool points down: the string is vertical
  // the yo-yo's parameters from the model: m, J about the spin axis, r = the string's coefficient
  const mjModel* m = rig.model;
  const double mass = m->body_mass[rig.Id(mjOBJ_BODY, "yoyo")];
  const double J = m->body_inertia[3 * rig.Id(mjOBJ_BODY, "yoyo") + 1];
  const int plus = rig.Id(mjOBJ_TENDON, "yoyo_string_plus");
  const double r = std::abs(m->wrap_prm[m->tendon_adr[plus] + 1]);
  const double g = 9.81;
  const double a = g * mass * r * r / (mass * r * r + J);
  EXPECT_NEAR(s[kVz], -a * 0.5, 2e-3);                                    // falling from rest at a
  EXPECT_NEAR(s[kStringForce], mass * g * J / (J + mass * r * r), 1e-4);  // T = 0.444 N
  EXPECT_DOUBLE_EQ(s[kStringForce], rig.Sensor("yoyo_string_plus_force") + rig.Sensor("yoyo_string_minus_force"));
  EXPECT_DOUBLE_EQ(s[kSpin], rig.data->qvel[m->jnt_dofadr[rig.Id(mjOBJ_JOINT, "yoyo_spin")]]);
  std::vector<double> row(rig.yoyo->ColumnCount());
  rig.yoyo->Row(*rig.data, row.data());
  EXPECT_EQ(rig.yoyo->Columns(),
            (std::vector<std::string>{"yoyo.z", "yoyo.vz", "yoyo.string_force", "yoyo.spin", "yoyo.depth"}));
  EXPECT_EQ(row[0], s[kZ]);
  EXPECT_EQ(row[4], d);
  // d0 + a (t^2 + t h) / 2: constant acceleration under semi-implicit Euler, step h = 1 ms
  EXPECT_NEAR(d, 0.0449558333 + 0.5 * a * (0.25 + 0.5 * 0.001), 5e-6);  // + the string's stretch (1.6 um)
}

TEST_F(YoyoDeviceTest, ASlackStringReadsZero) {
  Rig rig = NewRig("ready");
  rig.data->qpos[rig.model->jnt_qposadr[rig.Id(mjOBJ_JOINT, "yoyo_drop")]] = 0.5;  // d + r|theta| = 0.5 < L
  rig.data->qpos[rig.model->jnt_qposadr[rig.Id(mjOBJ_JOINT, "yoyo_spin")]] = 0.0;
  mj_forward(rig.model, rig.data);
  rig.yoyo->Sample(*rig.data, 0.0);
  EXPECT_EQ(rig.State()[kStringForce], 0.0);
}

TEST_F(YoyoDeviceTest, Jr3ReadsTheToolSideAndTheYoyoHangingAtRest) {
  Rig rig = NewRig("hanging");  // at the end of the string, both tendons at their limit
  rig.Run(1.0);
  rig.yoyo->Sample(*rig.data, 1.0);
  const mjModel* m = rig.model;
  const double g = 9.81;
  const double yoyo = m->body_mass[rig.Id(mjOBJ_BODY, "yoyo")];
  double beyond = 0;  // what hangs beyond the JR3's measuring plane
  for (const char* b : {"jr3_tool_side", "tool_body", "yoyo_hand", "yoyo"})
    beyond += m->body_mass[rig.Id(mjOBJ_BODY, b)];
  EXPECT_NEAR(beyond, 0.085 + 0.3416 + 0.05, 1e-12);
  EXPECT_NEAR(rig.State()[kStringForce], yoyo * g, 1e-4);  // the string carries the yo-yo: m g = 0.4905 N
  const int adr = m->sensor_adr[rig.Id(mjOBJ_SENSOR, "jr3_force")];
  const Eigen::Vector3d f_S(rig.data->sensordata[adr], rig.data->sensordata[adr + 1], rig.data->sensordata[adr + 2]);
  EXPECT_NEAR(f_S.norm(), beyond * g, 1e-4);  // 4.6754 N
  const int site = rig.Id(mjOBJ_SITE, "jr3");
  const Eigen::Matrix3d R_WS =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rig.data->site_xmat + 9 * site);
  EXPECT_NEAR(std::abs((R_WS * f_S).z()), beyond * g, 1e-4);  // vertical
}

TEST_F(YoyoDeviceTest, SampleAndHoldAt25Hz) {
  Rig rig = NewRig("ready", 25.0);
  const std::vector<double> first = rig.State();  // the sample at t = 0 (reset)
  for (int k = 1; k <= 8; ++k) {
    rig.Run(0.01);
    rig.yoyo->Sample(*rig.data, k * 0.01);
    const std::vector<double> s = rig.State();
    const bool fresh = k % 4 == 0;  // 0.04 s, 0.08 s
    EXPECT_EQ(s[kStatus], fresh ? 0.0 : static_cast<double>(bridge::kYoyoNotSeen)) << k;
    if (k < 4) {
      for (int i : {kX, kY, kZ, kVz, kStringForce, kSpin}) EXPECT_EQ(s[i], first[i]) << k;  // held
    }
    if (fresh) {
      EXPECT_EQ(s[kZ], rig.data->site_xpos[3 * rig.Id(mjOBJ_SITE, "yoyo_centre") + 2]);
    }
  }
  EXPECT_LT(rig.State()[kZ], first[kZ] - 1e-3);  // it has fallen meanwhile
}

TEST_F(YoyoDeviceTest, NoiseIsSeeded) {
  Rig a = NewRig("ready", 0, 0.002, 5), b = NewRig("ready", 0, 0.002, 5), c = NewRig("ready", 0, 0.002, 6);
  EXPECT_EQ(a.State(), b.State());
  EXPECT_NE(a.State()[kX], c.State()[kX]);
  const double truth = a.data->site_xpos[3 * a.Id(mjOBJ_SITE, "yoyo_centre") + 2];
  EXPECT_NE(a.State()[kZ], truth);
  EXPECT_LT(std::abs(a.State()[kZ] - truth), 5 * 0.002);
  EXPECT_EQ(a.State()[kStringForce], c.State()[kStringForce]);  // no noise on the force
}

TEST_F(YoyoSceneTest, TheArmIsPa10xmlsArm) {
  const mjModel* yoyo = LoadModel(kScene);
  const mjModel* plain = LoadModel("scenes/pa10.xml");
  auto same = [](const mjtNum* x, const mjtNum* y, int n) { return std::equal(x, x + n, y); };
  for (int b = 1; b < plain->nbody; ++b) {
    const char* name = mj_id2name(plain, mjOBJ_BODY, b);
    const int y = mj_name2id(yoyo, mjOBJ_BODY, name);
    ASSERT_GE(y, 0) << name;
    EXPECT_EQ(plain->body_mass[b], yoyo->body_mass[y]) << name;
    EXPECT_TRUE(same(plain->body_inertia + 3 * b, yoyo->body_inertia + 3 * y, 3)) << name;
    EXPECT_TRUE(same(plain->body_ipos + 3 * b, yoyo->body_ipos + 3 * y, 3)) << name;
    EXPECT_TRUE(same(plain->body_pos + 3 * b, yoyo->body_pos + 3 * y, 3)) << name;
    EXPECT_TRUE(same(plain->body_quat + 4 * b, yoyo->body_quat + 4 * y, 4)) << name;
  }
  ASSERT_EQ(plain->njnt + 2, yoyo->njnt);  // + the yo-yo's slide and spin
  for (int j = 0; j < plain->njnt; ++j) {
    EXPECT_TRUE(same(plain->jnt_range + 2 * j, yoyo->jnt_range + 2 * j, 2));
    EXPECT_TRUE(same(plain->jnt_axis + 3 * j, yoyo->jnt_axis + 3 * j, 3));
    EXPECT_EQ(plain->dof_armature[j], yoyo->dof_armature[j]);
    EXPECT_EQ(plain->dof_damping[j], yoyo->dof_damping[j]);
    EXPECT_EQ(plain->dof_frictionloss[j], yoyo->dof_frictionloss[j]);
  }
  ASSERT_EQ(plain->nu, yoyo->nu);
  EXPECT_TRUE(same(plain->actuator_ctrlrange, yoyo->actuator_ctrlrange, 2 * plain->nu));
  EXPECT_TRUE(same(plain->actuator_gear, yoyo->actuator_gear, 6 * plain->nu));
}

// The stage-1 devices in a lockstep lab: the generic client moves the hand up
// 5 cm through the point device and reads the yo-yo. pa10 is served too, and
// nobody commands it: lockstep must not wait for it (its point device drives it).
TEST(YoyoServeTest, LockstepPointCommandsMoveTheHandAndTheYoyoIsRead) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir.path() + "/s.yaml", std::string("scene: ") + kScene + R"(
duration: 1.2
control_period: 0.01
clock: lockstep
lockstep: {start_timeout: 5.0, on_timeout: fail}
devices:
  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2], initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0], port: 0}
  - {name: hand, kind: point, arm: pa10, workspace: {min: [0.5, -0.2, 1.0], max: [0.9, 0.2, 1.7]}, port: 0}
  - {name: yoyo, kind: yoyo, port: 0}
)");
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(dir.path() + "/s.yaml"));
  BridgeOptions bo;
  bo.ports = {{"pa10", 0}, {"hand", 0}, {"yoyo", 0}};
  std::promise<std::vector<ServedDevice>> served;
  RunOptions ro;
  ro.serve = &bo;
  ro.on_serving = [&](const std::vector<ServedDevice>& d) { served.set_value(d); };
  RunResult result;
  std::thread run([&] { result = lab->Run(ro); });
  const std::vector<ServedDevice> devices = served.get_future().get();
  ASSERT_EQ(devices.size(), 3u);
  auto hand = bridge::Device::Connect(bridge::DeviceKind::kPoint, "127.0.0.1", devices[1].port, 5.0);
  auto yoyo = bridge::Device::Connect(bridge::DeviceKind::kYoyo, "127.0.0.1", devices[2].port, 5.0);
  EXPECT_EQ(hand.command_length(), 3);
  EXPECT_EQ(hand.state_names(),
            (std::vector<std::string>(bridge::kPointStateLayout.begin(), bridge::kPointStateLayout.end())));
  EXPECT_EQ(yoyo.state_names(),
            (std::vector<std::string>(bridge::kYoyoStateLayout.begin(), bridge::kYoyoStateLayout.end())));
  EXPECT_EQ(yoyo.command_length(), 0);
  bridge::Device::State s = hand.Read(5.0);
  EXPECT_EQ(s.values[kPointStatus], static_cast<double>(bridge::kStatusHolding));
  const std::vector<double> start = s.values;
  bridge::Device::State y;
  while (s.seq < 120) {
    hand.Write({start[kPointX], start[kPointY], start[kPointZ] + 0.05}, s.seq);  // up 5 cm, x and y kept
    s = hand.Read(5.0);
    y = yoyo.ReadLatest(5.0);
  }
  run.join();
  EXPECT_EQ(result.exit_code, 0) << result.failure;
  EXPECT_EQ(result.periods, 120);
  EXPECT_EQ(s.values[kPointStatus], 0.0);
  EXPECT_NEAR(s.values[kPointX], start[kPointX], 1e-4);
  EXPECT_NEAR(s.values[kPointY], start[kPointY], 1e-4);
  EXPECT_NEAR(s.values[kPointZ], start[kPointZ] + 0.05, 1e-4);
  // the yo-yo on its way down below the hand (its first bottom comes at 1.43 s)
  EXPECT_GE(y.seq, 119);
  EXPECT_NEAR(y.values[kX], s.values[kPointX], 1e-3);
  EXPECT_LT(y.values[kZ], s.values[kPointZ] - 0.5);
  EXPECT_LT(y.values[kVz], -0.5);                    // m/s
  EXPECT_NEAR(y.values[kStringForce], 0.444, 0.01);  // the descent's tension, N
  EXPECT_LT(y.values[kSpin], 0.0);                   // spinning (unwinding: theta decreases)
}

}  // namespace
}  // namespace vlab::lab::yoyo_device_test
