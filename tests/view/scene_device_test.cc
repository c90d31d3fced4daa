// Tests the scene device (src/lab/devices/device_scene.cc) in process: at
// rate 50 Hz and a 2 ms control period a frame is due every 10 periods
// exactly (0.02 / 0.002) and only then published (PublishDue); its state is
// mjData's xpos and xquat of the visual bodies, bit for bit, the others held;
// the describe reply lists the bodies and geoms; the pose recording
// (outputs.poses) writes the same frame bytes; and the keys and binding
// errors name the device, the key and the cause.
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "lab/devices/device_kinds.h"
#include "lab/devices/device_scene.h"
#include "lab/outputs/lab_poses.h"
#include "lab/scenario/lab_scenario.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab {
namespace {

constexpr const char* kXml = R"(<mujoco>
  <option timestep="0.001"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="bob" pos="0 0 1">
      <joint name="swing" type="hinge" axis="0 1 0"/>
      <geom name="rod" type="capsule" fromto="0 0 0 0.5 0 0" size="0.02"/>
    </body>
    <body name="ghost" pos="0 1 1">
      <joint type="free"/>
      <geom type="sphere" size="0.1" rgba="1 1 1 0"/>
    </body>
  </worldbody>
</mujoco>)";
constexpr const char* kEmptyXml = R"(<mujoco><worldbody><geom type="plane" size="1 1 0.1"/></worldbody></mujoco>)";

DeviceConfig Scene(double rate_hz) {
  DeviceConfig c;
  c.name = "scene";
  c.kind = bridge::DeviceKind::kScene;
  c.where = "test.yaml:1";
  c.EditParams<SceneParams>().rate_hz = rate_hz;
  return c;
}

class SceneDeviceTest : public test::MujocoTest {};

TEST_F(SceneDeviceTest, FramesAreDueAtTheRateAndCarryXposAndXquat) {
  mjModel* m = LoadModelFromString("scene.xml", kXml);
  mjData* d = MakeData(m);
  mj_forward(m, d);
  const double period = 0.002;
  auto scene = MakeDevice({m, period, 1, "scene.xml"}, Scene(50));
  EXPECT_EQ(SceneBodies(m), std::vector<int>({1}));  // the transparent ghost is not drawn
  scene->Reset(*d);
  EXPECT_TRUE(scene->PublishDue());  // a frame at t = 0
  std::vector<double> state;
  int due = 0;
  for (int k = 1; k <= 100; ++k) {
    for (int s = 0; s < 2; ++s) mj_step(m, d);
    scene->Sample(*d, k * period);
    if (!scene->PublishDue()) continue;
    ++due;
    EXPECT_EQ(k % 10, 0) << "period " << k;
    scene->State(&state);
    ASSERT_EQ(state.size(), 7u);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(state[i], d->xpos[3 + i]);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(state[3 + i], d->xquat[4 + i]);
  }
  EXPECT_EQ(due, 10);
  EXPECT_EQ(scene->ColumnCount(), 0);  // nothing in the log
  const nlohmann::json facts = nlohmann::json::parse(scene->DescribeFacts());
  EXPECT_EQ(facts["bodies"], nlohmann::json::array({"bob"}));
  EXPECT_EQ(facts["geoms"].size(), 2u);
  EXPECT_EQ(facts["layout"]["state"].size(), 7u);
  EXPECT_EQ(facts["layout"]["state"][3], "bob.qw");
  EXPECT_DOUBLE_EQ(facts["rate_hz"].get<double>(), 50);
}

TEST_F(SceneDeviceTest, TheRecordingsFrameIsTheStreamsBytes) {
  std::string frame;
  const double poses[7] = {1.5, -2.25, 0.125, 1, 0, 0, 0};
  EncodePoseFrame(0.5, 250, poses, 7, &frame);
  ASSERT_EQ(frame.size(), 16u + 28u);
  double t = 0, k = 0;
  float x = 0, qw = 0;
  std::memcpy(&t, frame.data(), 8);
  std::memcpy(&k, frame.data() + 8, 8);
  std::memcpy(&x, frame.data() + 16, 4);
  std::memcpy(&qw, frame.data() + 16 + 12, 4);
  EXPECT_EQ(t, 0.5);
  EXPECT_EQ(k, 250);
  EXPECT_EQ(x, 1.5f);
  EXPECT_EQ(qw, 1.0f);
}

TEST_F(SceneDeviceTest, ErrorsNameTheDeviceAndTheCause) {
  mjModel* m = LoadModelFromString("scene.xml", kXml);
  mjModel* empty = LoadModelFromString("empty.xml", kEmptyXml);
  auto error = [&](mjModel* model, const DeviceConfig& c) {
    try {
      MakeDevice({model, 0.01, 1, "scene.xml"}, c);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error(m, Scene(200)), "test.yaml:1: device 'scene': rate 200 Hz is faster than the control rate (100 Hz)");
  EXPECT_EQ(error(m, Scene(100)), "no error");
  EXPECT_EQ(error(empty, Scene(30)),
            "test.yaml:1: device 'scene': the scene has no body with a visible geom to stream");

  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "scene.xml", kXml);
  auto load = [&](const std::string& device, const std::string& outputs = "") {
    vlab::testing::WriteFile(dir / "s.yaml", "scene: scene.xml\nduration: 0.1\ncontrol_period: 0.01\ndevices:\n  - " +
                                                 device + "\n" + outputs);
    try {
      LoadScenario(dir / "s.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(load("{name: scene, kind: scene, rate: 20}"), "no error");
  EXPECT_NE(load("{name: scene, kind: scene, rate: -1}").find("rate: must be >= 0 Hz"), std::string::npos);
  EXPECT_NE(load("{name: scene, kind: scene, fps: 3}").find("fps"), std::string::npos);
  EXPECT_NE(load("{name: scene, kind: scene}", "outputs: {poses: {rate: -2}}").find("rate: must be >= 0 Hz"),
            std::string::npos);
  EXPECT_NE(load("{name: scene, kind: scene}", "outputs: {poses: {every: 2}}").find("every"), std::string::npos);
}

}  // namespace
}  // namespace vlab::lab
