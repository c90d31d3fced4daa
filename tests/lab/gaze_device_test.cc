// Tests the gaze probe (src/lab/devices/device_gaze.cc) against closed forms: a
// camera on a turning body and a fixed camera in a general pose, targets on
// and off the optical axis, behind the camera and outside the image; the
// angle is atan of the lateral over the axial distance, the pixel the
// pinhole projection with fx = fy = (H/2) / tan(fovy/2), cx = W/2 - 0.5,
// cy = H/2 - 0.5. Then its scenario keys, its errors and its served layout.
#include <cmath>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "lab/devices/device_gaze.h"
#include "lab/devices/device_kinds.h"
#include "lab/run/lab_runner.h"
#include "mujoco_fixture.h"
#include "test_util.h"

namespace vlab::lab::gaze_device_test {
namespace {

constexpr double kDeg = M_PI / 180.0;

// the gaze probe's state payload (docs/protocol.md)
constexpr int kErrorDeg = bridge::StateIndex(bridge::DeviceKind::kGaze, "error_deg");
constexpr int kU = bridge::StateIndex(bridge::DeviceKind::kGaze, "u");
constexpr int kV = bridge::StateIndex(bridge::DeviceKind::kGaze, "v");
constexpr int kVisible = bridge::StateIndex(bridge::DeviceKind::kGaze, "visible");

// Camera `eye` 0.1 m in front of a hinge about world z at (0, 0, 1), looking
// along the body's +x (fovy 45 deg); body `ball` 2 m ahead at the same height;
// site `above` 0.5 m above it; site `behind` behind the camera. Camera `fixed`
// at (1, 2, 3) with x = (0.6, 0.8, 0), y = (-0.48, 0.36, 0.8), so it looks
// along -z = -(x cross y) = (-0.64, 0.48, -0.6), fovy 50 deg; site `probe` at
// (1, 2, 3) + 3 (-z) + 0.4 x - 0.3 y = (-0.536, 3.652, 0.96): OpenCV camera
// coordinates (0.4, 0.3, 3). A body and a site both named `post`.
constexpr const char* kXml = R"(
<mujoco>
  <option timestep="0.001" gravity="0 0 0"/>
  <worldbody>
    <camera name="fixed" pos="1 2 3" xyaxes="0.6 0.8 0 -0.48 0.36 0.8" fovy="50"/>
    <site name="probe" pos="-0.536 3.652 0.96"/>
    <site name="behind" pos="-1 0 1"/>
    <site name="post" pos="2 0 1.25"/>
    <body name="post" pos="5 5 5"/>
    <body name="pan" pos="0 0 1">
      <joint name="pan" type="hinge" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
      <camera name="eye" pos="0.1 0 0" xyaxes="0 -1 0 0 0 1" fovy="45"/>
    </body>
    <body name="ball" pos="2 0 1">
      <site name="above" pos="0 0 0.5"/>
    </body>
  </worldbody>
</mujoco>)";

DeviceConfig Gaze(const std::string& camera, const std::string& target, int width = 320, int height = 240) {
  DeviceConfig c;
  c.name = "gaze";
  c.kind = bridge::DeviceKind::kGaze;
  c.where = "test.yaml:1";
  c.EditParams<GazeParams>().camera = camera;
  c.EditParams<GazeParams>().target = target;
  c.EditParams<GazeParams>().width = width;
  c.EditParams<GazeParams>().height = height;
  return c;
}

struct Sample {
  double error_deg, u, v, visible;
};

// The scene, on a model and data the fixture owns.
struct Rig {
  mjModel* model;
  mjData* data;

  // The probe's output with the hinge at `pan` rad.
  Sample Probe(const DeviceConfig& c, double pan = 0.0) {
    data->qpos[0] = pan;
    mj_forward(model, data);
    auto device = MakeDevice({model, 0.002, 1, ""}, c);
    device->Sample(*data, 0.0);
    std::vector<double> state;
    device->State(&state);
    EXPECT_EQ(state.size(), 4u);
    std::vector<double> row(4);
    device->Row(*data, row.data());
    EXPECT_EQ(row, state);
    return {state[kErrorDeg], state[kU], state[kV], state[kVisible]};
  }
};

class GazeDeviceTest : public test::MujocoTest {
 protected:
  Rig NewRig() {
    mjModel* m = LoadModelFromString("gaze.xml", kXml);
    return {m, MakeData(m)};
  }
};

// focal length of a W x H image of a camera with vertical field of view fovy
double Focal(int height, double fovy_deg) { return 0.5 * height / std::tan(0.5 * fovy_deg * kDeg); }

TEST_F(GazeDeviceTest, TargetOnTheOpticalAxisIsAtThePrincipalPoint) {
  Rig rig = NewRig();
  const Sample s = rig.Probe(Gaze("eye", "ball"));
  EXPECT_NEAR(s.error_deg, 0.0, 1e-9);
  EXPECT_NEAR(s.u, 159.5, 1e-9);
  EXPECT_NEAR(s.v, 119.5, 1e-9);
  EXPECT_EQ(s.visible, 1.0);
}

TEST_F(GazeDeviceTest, TurnedCameraSeesTheTargetAtTheClosedFormAngleAndPixel) {
  // camera at (0.1 cos a, 0.1 sin a, 1) looking along (cos a, sin a, 0), its
  // image x axis (sin a, -cos a, 0): the ball at (2, 0, 1) has X = 2 sin a,
  // Y = 0, Z = 2 cos a - 0.1
  Rig rig = NewRig();
  const double f = Focal(240, 45);
  for (double a : {0.1, -0.25, 0.3}) {
    const double x = 2 * std::sin(a), z = 2 * std::cos(a) - 0.1;
    const Sample s = rig.Probe(Gaze("eye", "ball"), a);
    EXPECT_NEAR(s.error_deg, std::atan2(std::abs(x), z) / kDeg, 1e-9) << a;
    EXPECT_NEAR(s.u, 159.5 + f * x / z, 1e-9) << a;  // turned left (a > 0): the ball lies to the right
    EXPECT_NEAR(s.v, 119.5, 1e-9) << a;
    EXPECT_EQ(s.visible, 1.0) << a;
  }
}

TEST_F(GazeDeviceTest, TargetAboveTheAxisIsAboveTheImageCentre) {
  Rig rig = NewRig();
  const double f = Focal(240, 45);
  const Sample s = rig.Probe(Gaze("eye", "above"));  // X = 0, Y = -0.5 (up), Z = 1.9
  EXPECT_NEAR(s.error_deg, std::atan(0.5 / 1.9) / kDeg, 1e-9);
  EXPECT_NEAR(s.u, 159.5, 1e-9);
  EXPECT_NEAR(s.v, 119.5 - f * 0.5 / 1.9, 1e-9);
  EXPECT_EQ(s.visible, 1.0);
}

TEST_F(GazeDeviceTest, FixedCameraInAGeneralPose) {
  Rig rig = NewRig();
  const double f = Focal(480, 50);
  const Sample s = rig.Probe(Gaze("fixed", "probe", 640, 480));  // camera coordinates (0.4, 0.3, 3)
  EXPECT_NEAR(s.error_deg, std::atan(0.5 / 3.0) / kDeg, 1e-9);
  EXPECT_NEAR(s.u, 319.5 + f * 0.4 / 3.0, 1e-9);
  EXPECT_NEAR(s.v, 239.5 + f * 0.3 / 3.0, 1e-9);
  EXPECT_EQ(s.visible, 1.0);
}

TEST_F(GazeDeviceTest, SiteWinsOverABodyOfTheSameName) {
  Rig rig = NewRig();
  const Sample s = rig.Probe(Gaze("eye", "post"));  // the site: 0.25 m above the axis, 1.9 m ahead
  EXPECT_NEAR(s.error_deg, std::atan(0.25 / 1.9) / kDeg, 1e-9);
}

TEST_F(GazeDeviceTest, TargetBehindTheCameraIsNotVisible) {
  Rig rig = NewRig();
  const Sample s = rig.Probe(Gaze("eye", "behind"));  // straight behind: Z = -1.1
  EXPECT_NEAR(s.error_deg, 180.0, 1e-9);
  EXPECT_EQ(s.u, -1.0);
  EXPECT_EQ(s.v, -1.0);
  EXPECT_EQ(s.visible, 0.0);
}

TEST_F(GazeDeviceTest, VisibleOnlyInsideTheImage) {
  // turn the camera so that the ball projects to u: with k = (u - cx) / f,
  // 2 sin a / (2 cos a - 0.1) = k  <=>  a = atan(k) - asin(0.1 k / (2 sqrt(1 + k^2)))
  Rig rig = NewRig();
  const double f = Focal(240, 45);
  auto turn_to = [&](double u) {
    const double k = (u - 159.5) / f;
    return std::atan(k) - std::asin(0.1 * k / (2 * std::sqrt(1 + k * k)));
  };
  for (double u : {319.4, 319.6, -0.4, -0.6, 400.0}) {
    const Sample s = rig.Probe(Gaze("eye", "ball"), turn_to(u));
    EXPECT_NEAR(s.u, u, 1e-9);
    EXPECT_EQ(s.visible, u >= -0.5 && u < 319.5 ? 1.0 : 0.0) << u;
  }
}

TEST_F(GazeDeviceTest, ResetSamplesTheInitialStateAndDescribeGivesTheLayout) {
  Rig rig = NewRig();
  rig.data->qpos[0] = 0.1;
  mj_forward(rig.model, rig.data);
  auto device = MakeDevice({rig.model, 0.002, 1, ""}, Gaze("eye", "ball"));
  EXPECT_EQ(device->kind(), bridge::DeviceKind::kGaze);
  EXPECT_EQ(device->command_input(), nullptr);  // output only: no command input
  EXPECT_EQ(device->Columns(), (std::vector<std::string>{"gaze.error_deg", "gaze.u", "gaze.v", "gaze.visible"}));
  device->Reset(*rig.data);
  std::vector<double> row(4);
  device->Row(*rig.data, row.data());
  EXPECT_NEAR(row[0], std::atan2(2 * std::sin(0.1), 2 * std::cos(0.1) - 0.1) / kDeg, 1e-9);
  const nlohmann::json j = nlohmann::json::parse(device->DescribeFacts());
  EXPECT_EQ(j["layout"]["state"], nlohmann::json({"error_deg", "u", "v", "visible"}));
  EXPECT_EQ(j["target_type"], "body");
  EXPECT_NEAR(j["intrinsics"]["fy"].get<double>(), Focal(240, 45), 1e-9);
  EXPECT_EQ(j["intrinsics"]["cx"].get<double>(), 159.5);
}

TEST_F(GazeDeviceTest, UnknownCameraOrTargetIsNamed) {
  Rig rig = NewRig();
  auto message = [&](const DeviceConfig& c) {
    try {
      MakeDevice({rig.model, 0.002, 1, ""}, c);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(Gaze("nope", "ball")).find("device 'gaze': the scene has no camera 'nope'"), std::string::npos);
  EXPECT_NE(message(Gaze("eye", "nope")).find("no site or body 'nope'"), std::string::npos);
}

TEST(GazeScenarioTest, KeysAreReadAndCheckedAndTheProbeIsLoggedAndServed) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "gaze.xml", kXml);
  const std::string head = "scene: gaze.xml\nduration: 0.01\ndevices:\n";
  auto load = [&](const std::string& device) {
    vlab::testing::WriteFile(dir / "s.yaml", head + "  - " + device + "\n");
    return LoadScenario(dir / "s.yaml");
  };
  const Scenario s = load("{name: g, kind: gaze, camera: eye, target: ball, width: 320, height: 240, port: 0}");
  EXPECT_EQ(s.devices[0].ParamsAs<GazeParams>().camera, "eye");
  EXPECT_EQ(s.devices[0].ParamsAs<GazeParams>().target, "ball");
  EXPECT_EQ(s.devices[0].ParamsAs<GazeParams>().width, 320);
  EXPECT_EQ(load("{name: g, kind: gaze, camera: eye, target: ball}").devices[0].ParamsAs<GazeParams>().height, 480);
  auto error = [&](const std::string& device) {
    try {
      load(device);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("{name: g, kind: gaze, camera: eye}").find("target"), std::string::npos);
  EXPECT_NE(error("{name: g, kind: gaze, camera: eye, target: ball, width: 0}").find("width"), std::string::npos);
  EXPECT_NE(error("{name: g, kind: gaze, camera: eye, target: ball, fps: 3}").find("fps"), std::string::npos);

  // in a lab: the log's first row is the initial state's gaze; served, it describes itself
  std::unique_ptr<Lab> lab = Lab::Create(s);
  const std::vector<std::string> columns = lab->Columns();
  EXPECT_NE(std::find(columns.begin(), columns.end(), "g.visible"), columns.end());
  BridgeOptions bo;
  bo.ports = {{"g", 0}};
  const std::vector<ServedDevice> served = lab->Describe(bo, ClockMode::kLockstep);
  ASSERT_EQ(served.size(), 1u);
  EXPECT_EQ(served[0].kind, "gaze");
  const nlohmann::json d = nlohmann::json::parse(served[0].describe_json);
  EXPECT_EQ(d["kind"], "gaze");
  EXPECT_EQ(d["layout"]["state"].size(), 4u);
  RunOptions ro;
  ro.out_dir = dir / "out";
  EXPECT_EQ(lab->Run(ro).exit_code, 0);
  const auto lines = vlab::testing::Lines(vlab::testing::ReadFile(dir / "out/log.csv"));
  ASSERT_GE(lines.size(), 2u);
  const auto names = vlab::testing::SplitCsv(lines[0]);
  const auto first = vlab::testing::SplitCsv(lines[1]);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "g.u") {
      EXPECT_EQ(std::stod(first[i]), 159.5);
    } else if (names[i] == "g.visible") {
      EXPECT_EQ(std::stod(first[i]), 1.0);
    }
  }
}

}  // namespace
}  // namespace vlab::lab::gaze_device_test
