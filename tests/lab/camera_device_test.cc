// Tests the lab's simulated webcam (src/lab/devices/device_camera.cc) end to end:
// a scenario's camera device served by the lab in realtime, received by the
// C++ camera client. Frames come at the camera's rate with consecutive ids,
// stamped with the simulated time they show, carrying the camera's pose; the
// describe reply has the intrinsics of the MJCF camera; a red box lies where
// the intrinsics project it. Bad bindings fail at creation with the device's name;
// the render profile is draft, fast or quality.
#include <cmath>
#include <future>
#include <thread>
#include <utility>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_client.h"
#include "core/core_errors.h"
#include "lab/devices/device_camera.h"
#include "lab/run/lab_runner.h"
#include "test_util.h"

namespace vlab::lab::camera_device_test {
namespace {

// a camera 1 m above the floor looking straight down; a red box below it, 0.1 m right of the optical axis
constexpr const char* kSceneXml = R"(
<mujoco>
  <visual><global offwidth="640" offheight="480"/></visual>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <geom type="plane" size="2 2 0.1" rgba="0.8 0.8 0.8 1"/>
    <geom type="box" size="0.02 0.02 0.001" pos="0.1 0 0.001" rgba="1 0 0 1"/>
    <camera name="top" pos="0 0 1" fovy="45"/>
  </worldbody>
</mujoco>)";

std::string Scenario(const std::string& camera = "top", int width = 320) {
  return "scene: scene.xml\nduration: 1.5\ncontrol_period: 0.002\nclock: realtime\ndevices:\n"
         "  - {name: webcam, kind: camera, camera: " +
         camera + ", width: " + std::to_string(width) +
         ", height: 240, fps: 25, latency: 0.04, encoding: raw, port: 0}\n";
}

TEST(CameraDeviceTest, FramesArriveAtTheCameraRateWithStampsPoseAndIntrinsics) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "scene.xml", kSceneXml);
  vlab::testing::WriteFile(dir / "cam.yaml", Scenario());
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(dir / "cam.yaml"));
  BridgeOptions bo;
  bo.ports = {{"webcam", 0}};  // any free port
  std::promise<std::vector<ServedDevice>> served;
  RunOptions ro;
  ro.serve = &bo;
  ro.on_serving = [&](const std::vector<ServedDevice>& d) { served.set_value(d); };
  RunResult result;
  std::thread run([&] { result = lab->Run(ro); });
  const std::vector<ServedDevice> devices = served.get_future().get();
  ASSERT_EQ(devices.size(), 1u);
  EXPECT_EQ(devices[0].kind, "camera");
  bridge::CameraClientOptions co;
  co.timeout_s = 5;
  auto client = bridge::CameraClient::Connect("127.0.0.1", devices[0].port, co);
  const double f = 120.0 / std::tan(22.5 * M_PI / 180);  // (H/2) / tan(fovy/2)
  EXPECT_NEAR(client.calibration().fx, f, 1e-9);
  EXPECT_NEAR(client.calibration().cx, 159.5, 1e-12);
  EXPECT_EQ(client.width(), 320);
  EXPECT_EQ(client.describe()["latency_s"], 0.04);
  std::vector<bridge::CameraClient::Frame> frames;
  for (;;) {
    try {
      frames.push_back(client.Receive(1.0));
    } catch (const bridge::TimeoutError&) {
      break;  // the run is over
    }
  }
  run.join();
  EXPECT_EQ(result.exit_code, 0) << result.failure;
  ASSERT_GE(frames.size(), 20u);  // 1.5 s at 25 Hz, less the time to connect
  // in order; a frame missing is one the device dropped (its render worker behind: on a busy
  // machine) or one it sent that did not arrive whole, and it counts both
  long missing = 0;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_GT(frames[i].id, frames[i - 1].id);
    missing += frames[i].id - frames[i - 1].id - 1;
    // rendered at the first period end at or after id / fps
    const double nominal = frames[i].id / 25.0;
    EXPECT_GE(frames[i].time_s, nominal - 1e-9);
    EXPECT_LT(frames[i].time_s, nominal + 0.002 + 1e-9);
  }
  ASSERT_EQ(result.served.size(), 1u);
  const FrameCounters& counted = result.served[0].frames;
  EXPECT_LE(missing, counted.dropped + (counted.sent - static_cast<long>(frames.size())))
      << counted.sent << " sent, " << counted.dropped << " dropped, " << frames.size() << " received";
  const bridge::CameraClient::Frame& last = frames.back();
  ASSERT_TRUE(last.pose.valid);
  EXPECT_NEAR(last.pose.p_WC.z(), 1.0, 1e-12);
  // looking down: OpenCV z (forward) is world -z, x (right) is world +x
  const Eigen::Matrix3d r = last.pose.q_WC.toRotationMatrix();
  EXPECT_NEAR(r(2, 2), -1.0, 1e-9);
  EXPECT_NEAR(r(0, 0), 1.0, 1e-9);
  // the red box's pixels: centred where the pinhole model puts (0.1, 0, 0) seen from 1 m
  double su = 0, sv = 0, n = 0;
  for (int v = 0; v < last.height; ++v) {
    for (int u = 0; u < last.width; ++u) {
      const std::uint8_t* p = last.rgb.data() + 3 * (v * last.width + u);
      if (p[0] > p[1] + 60 && p[0] > p[2] + 60) {  // red (lit: about 255, 90, 90)
        su += u;
        sv += v;
        n += 1;
      }
    }
  }
  ASSERT_GT(n, 20);
  EXPECT_NEAR(su / n, f * 0.1 / 0.999 + 159.5, 1.0);
  EXPECT_NEAR(sv / n, 119.5, 1.0);
}

// In lockstep the lab waits at period 0 for a controller; a camera served
// beside the arm answers describe requests during that wait, so a controller
// may connect its cameras before it sends its first command.
TEST(CameraDeviceTest, AnswersDescribeRequestsWhileLockstepWaits) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "scene.xml", R"(
<mujoco>
  <visual><global offwidth="640" offheight="480"/></visual>
  <worldbody>
    <camera name="top" pos="0 0 1" fovy="45"/>
    <body name="link"><joint name="j" type="hinge" axis="0 1 0"/><geom type="capsule" size="0.02" fromto="0 0 0 0.3 0 0"/></body>
  </worldbody>
  <actuator><motor name="j" joint="j"/></actuator>
</mujoco>)");
  vlab::testing::WriteFile(dir / "s.yaml", R"(scene: scene.xml
duration: 0.1
control_period: 0.01
clock: lockstep
lockstep: {start_timeout: 30}
devices:
  - {name: arm, kind: arm, joints: [j], port: 0}
  - {name: webcam, kind: camera, camera: top, width: 64, height: 48, fps: 10, encoding: raw, port: 0}
)");
  std::unique_ptr<Lab> lab = Lab::Create(LoadScenario(dir / "s.yaml"));
  BridgeOptions bo;
  bo.ports = {{"arm", 0}, {"webcam", 0}};
  std::promise<std::vector<ServedDevice>> served;
  RunOptions ro;
  ro.serve = &bo;
  ro.on_serving = [&](const std::vector<ServedDevice>& d) { served.set_value(d); };
  RunResult result;
  std::thread run([&] { result = lab->Run(ro); });
  const std::vector<ServedDevice> devices = served.get_future().get();
  ASSERT_EQ(devices.size(), 2u);
  int camera_port = 0;
  for (const auto& d : devices) camera_port = d.kind == "camera" ? d.port : camera_port;
  bridge::CameraClientOptions co;
  co.timeout_s = 5;  // the lab is still waiting for the arm's first command
  bool connected = false;
  try {
    auto client = bridge::CameraClient::Connect("127.0.0.1", camera_port, co);
    connected = client.width() == 64;
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  EXPECT_TRUE(connected);
  EXPECT_EQ(result.periods, 0);  // not started: nobody has answered period 0 yet
  // now a controller answers: the run goes to its end
  auto arm = bridge::Arm::Connect("127.0.0.1", devices[0].kind == "arm" ? devices[0].port : devices[1].port, 5.0);
  bridge::Arm::State s = arm.Read(5.0);
  while (s.seq < 10) {
    arm.Write(bridge::ArmMode::kHold, Eigen::VectorXd::Zero(1), s.seq);
    s = arm.Read(5.0);
  }
  run.join();
  EXPECT_EQ(result.exit_code, 0) << result.failure;
  EXPECT_EQ(result.periods, 10);
}

TEST(CameraDeviceTest, BadBindingsNameTheDevice) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "scene.xml", kSceneXml);
  auto message = [&](const std::string& camera, int width) {
    vlab::testing::WriteFile(dir / "bad.yaml", Scenario(camera, width));
    try {
      Lab::Create(LoadScenario(dir / "bad.yaml"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string unknown = message("nope", 320);
  EXPECT_NE(unknown.find("no camera 'nope'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("device 'webcam'"), std::string::npos) << unknown;
  const std::string big = message("top", 1280);
  EXPECT_NE(big.find("device 'webcam'"), std::string::npos) << big;
  EXPECT_NE(big.find("offscreen buffer"), std::string::npos) << big;
}

TEST(CameraDeviceTest, ProfileIsDraftFastOrQuality) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "scene.xml", kSceneXml);
  const auto with_profile = [&](const std::string& profile) {
    std::string yaml = Scenario();
    yaml.replace(yaml.find("encoding: raw"), 13, "encoding: raw, profile: " + profile);
    vlab::testing::WriteFile(dir / "camera.yaml", yaml);
    return dir / "camera.yaml";
  };
  for (const auto& [name, profile] :
       {std::pair{"draft", render::Profile::kDraft}, std::pair{"fast", render::Profile::kFast},
        std::pair{"quality", render::Profile::kQuality}}) {
    const auto scenario = LoadScenario(with_profile(name));
    ASSERT_EQ(scenario.devices.size(), 1u);
    EXPECT_EQ(scenario.devices[0].ParamsAs<CameraParams>().profile, profile) << name;
  }
  try {
    LoadScenario(with_profile("drafty"));
    ADD_FAILURE() << "profile 'drafty' was taken";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("profile"), std::string::npos) << message;
    EXPECT_NE(message.find("must be draft, fast or quality"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace vlab::lab::camera_device_test
