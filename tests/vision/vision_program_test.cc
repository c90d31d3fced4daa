// `vlab vision` end to end over UDP: this test serves a camera device
// (bridge::CameraServer, JPEG frames of a lettered cube rendered by
// vlab_render, with the camera's pose), runs the vision program as a
// separate process, describes markers to it over UDP with a MarkersClient, and
// checks the poses it serves against MuJoCo's ground truth, in the camera and
// in the world frame, frame by frame (seq = frame id, time = exposure time).
// Also: bad options exit 2 with one line, a missing camera fails cleanly.

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "bridge/bridge_camera_server.h"
#include "bridge/bridge_markers.h"
#include "render/renderer.h"
#include "sensors/sensor_random.h"
#include "test_process.h"
#include "vision/vision_detector.h"
#include "vision_test_scene.h"

namespace vlab::testing::vision_program_test {
namespace {

constexpr int kFrames = 24;

double Uniform(sensors::Xoshiro256pp& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

class VisionProgramTest : public CubeCameraScene {};

TEST_F(VisionProgramTest, ServesMarkerPosesOfACameraStreamInCameraAndWorldFrames) {
  // the camera device: JPEG frames of the scene's camera, with its pose in the world
  const render::Intrinsics k = render::CameraIntrinsics(m_, camera_, 640, 480);
  bridge::CameraServerConfig config;
  config.port = 0;
  config.description.name = "testcam";
  config.description.server = "vision_program_test";
  config.description.fx = k.fx;
  config.description.fy = k.fy;
  config.description.cx = k.cx;
  config.description.cy = k.cy;
  config.description.pose = "fixed";
  config.description.jpeg_quality = 95;
  auto camera = bridge::CameraServer::Create(config);
  // the camera's pose in a world of its own (the cube scene's webcam), sent with every frame
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = Eigen::Quaterniond(0.2, 0.9, -0.3, 0.25).normalized().toRotationMatrix();
  X_WC.translation() = Eigen::Vector3d(1.15, 0.0, 0.95);
  bridge::CameraPose pose;
  pose.valid = true;
  pose.p_WC = X_WC.translation();
  pose.q_WC = Eigen::Quaterniond(X_WC.linear());

  // the vision program knows cube A's faces 0-2 from the command line, 3-5 come over UDP
  TestProcess vision(
      {VLAB_BINARY_DIR "/vlab", "vision", "--camera", "127.0.0.1:" + std::to_string(camera->port()), "--port", "0",
       "--name", "eyes", "--marker", "4X4_50:0-2:0.025", "--frames", std::to_string(kFrames), "--duration", "20"},
      0);  // its start line comes once it has the camera: below
  for (int i = 0; i < 5000 && camera->subscribers() == 0; ++i) camera->Poll(0.002);
  ASSERT_EQ(camera->subscribers(), 1) << "vision did not subscribe to the camera";
  const std::string start = vision.WaitForStartLine(20);
  const std::size_t at = start.find("127.0.0.1:");
  ASSERT_NE(at, std::string::npos) << start;
  const int port = std::stoi(start.substr(at + 10));

  std::optional<bridge::MarkersClient> markers;
  markers.emplace(bridge::MarkersClient::Connect("127.0.0.1", port, 5.0));
  EXPECT_EQ(markers->name(), "eyes");
  EXPECT_EQ(markers->described_at_connect().size(), 3u);
  EXPECT_EQ(markers->describe()["camera"]["name"], "testcam");
  EXPECT_DOUBLE_EQ(markers->describe()["camera"]["intrinsics"]["fx"].get<double>(), k.fx);
  ASSERT_TRUE(markers->AddMarkers({{0, 3, 0.025}, {0, 4, 0.025}, {0, 5, 0.025}}));

  render::Renderer::Options options;
  options.log_renderer = false;
  auto renderer = render::Renderer::Create(m_, options);
  render::RgbImage rgb;
  sensors::Xoshiro256pp rng(77);
  int valid = 0, world_checked = 0;
  double worst_mm = 0, worst_deg = 0;
  bool saw_udp_described = false;
  for (int frame = 0; frame < kFrames; ++frame) {
    // a cube pose 0.3-0.45 m in front of the camera, turned to show 2-3 faces
    const double distance = 0.3 + 0.15 * Uniform(rng);
    const Eigen::Vector3d p(0.04 * (Uniform(rng) - 0.5), 0.04 * (Uniform(rng) - 0.5), -distance);
    const Eigen::Quaterniond q = Eigen::AngleAxisd(2 * M_PI * Uniform(rng), Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.6 + 0.5 * Uniform(rng), Eigen::Vector3d(1, 1, 0).normalized());
    PlaceCube(p, q);
    renderer->Render(d_, camera_, &rgb);
    const double exposure_s = 10.0 + frame / 30.0;
    camera->Poll(0);
    ASSERT_TRUE(camera->SendImage(frame, exposure_s, rgb.pixels.data(), pose)) << frame;

    // the state of this frame (earlier ones may still be queued)
    bridge::MarkersClient::State state;
    do {
      state = markers->Read(5.0);
    } while (state.seq < frame);
    ASSERT_EQ(state.seq, frame);
    EXPECT_DOUBLE_EQ(state.time, exposure_s);
    EXPECT_EQ(state.unknown, 0);
    saw_udp_described = saw_udp_described || state.described == 6;
    for (const bridge::MarkersClient::Marker& m : state.markers) {
      ASSERT_EQ(m.dictionary, 0);
      ASSERT_TRUE(m.id >= 0 && m.id < 6) << m.id;
      EXPECT_TRUE(m.world_valid);
      if (!m.valid) continue;
      ++valid;
      const Eigen::Isometry3d truth = X_camera_marker(m.id);
      const Eigen::Matrix4d T = m.T_camera_marker;
      EXPECT_LT((T.block<3, 1>(0, 3) - truth.translation()).norm(), 0.003) << "frame " << frame << " id " << m.id;
      EXPECT_LT(vision::RotationAngleDeg(T.block<3, 3>(0, 0), truth.linear()), 1.0) << frame << " " << m.id;
      worst_mm = std::max(worst_mm, 1000 * (T.block<3, 1>(0, 3) - truth.translation()).norm());
      worst_deg = std::max(worst_deg, vision::RotationAngleDeg(T.block<3, 3>(0, 0), truth.linear()));
      const Eigen::Isometry3d world_truth = X_WC * truth;
      const Eigen::Matrix4d W = m.T_world_marker;
      EXPECT_LT((W.block<3, 1>(0, 3) - world_truth.translation()).norm(), 0.003) << frame << " " << m.id;
      EXPECT_LT(vision::RotationAngleDeg(W.block<3, 3>(0, 0), world_truth.linear()), 1.0) << frame << " " << m.id;
      ++world_checked;
    }
  }
  std::printf("vlab vision over UDP: %d JPEG frames, %d valid marker poses, worst %.2f mm, %.3f deg\n", kFrames, valid,
              worst_mm, worst_deg);
  EXPECT_TRUE(saw_udp_described) << "the markers described over UDP never reached the table";
  EXPECT_GE(valid, kFrames);  // two faces or so per frame, most of them valid
  EXPECT_EQ(world_checked, valid);
  markers.reset();
  EXPECT_EQ(vision.Wait(), 0) << vision.output();
  const std::string& rest = vision.output();
  EXPECT_NE(rest.find("vlab vision: " + std::to_string(kFrames) + " frames"), std::string::npos) << rest;
}

TEST(VisionCommand, BadOptionsExitTwo) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--camera localhost", "--camera 'localhost': expected HOST:PORT"},
      {"--camera 127.0.0.1:70000", "expected HOST:PORT"},
      {"--camera 127.0.0.1:50013 --marker 4X4_50:3", "expected DICT:ID:SIDE"},
      {"--camera 127.0.0.1:50013 --marker 9X9_50:3:0.02", "unknown dictionary '9X9_50'"},
      {"--camera 127.0.0.1:50013 --marker 4X4_50:3-60:0.02", "ids must lie in 0..49 of 4X4_50"},
      {"--camera 127.0.0.1:50013 --marker 4X4_50:3:-1", "the side must be a length in m"},
      {"--camera 127.0.0.1:50013 --marker 4X4_50:x:0.02", "'x' is not a marker id"},
      {"--camera 127.0.0.1:50013 --frames -1", "--frames must be >= 0"},
      {"--camera 127.0.0.1:50013 --max-error 0", "--max-error must be > 0 px"},
  };
  for (const auto& [args, message] : cases) {
    const ProcessResult r = RunVlab("vision " + args, 30);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
  }
}

TEST(VisionCommand, NoCameraFailsWithOneLine) {
  // a port nobody serves: no describe reply within the connect timeout
  const auto socket = bridge::UdpSocket::Bind("127.0.0.1", 0);
  const int silent = socket->local_port();
  const ProcessResult r = RunVlab("vision --camera 127.0.0.1:" + std::to_string(silent) + " --connect-timeout 0.5", 30);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("no answer within 0.5 s"), std::string::npos) << r.err;
  EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
}

}  // namespace
}  // namespace vlab::testing::vision_program_test
