// `vlab vision --yoyo-port` end to end over UDP: this test serves a camera
// device (bridge::CameraServer, JPEG frames of scenes/pa10_yoyo.xml's webcam
// with the yo-yo at scripted depths, and the camera's pose), runs the vision
// program as a separate process and reads its yoyo device with the generic
// bridge::Device client, as a controller reads the lab's yoyo device: one
// state per frame (seq = frame id, time = exposure time), z against MuJoCo's
// ground truth, kYoyoNotSeen with the last values on frames without the yo-yo.

#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bridge/bridge_camera_server.h"
#include "bridge/bridge_client_device.h"
#include "bridge/bridge_yoyo.h"
#include "test_process.h"
#include "yoyo_test_scene.h"

namespace vlab::testing {
namespace {

constexpr int kFrames = 16;
constexpr std::int64_t kFirstId = 500;

class YoyoVisionProgramTest : public YoyoCameraScene {};

TEST_F(YoyoVisionProgramTest, ServesTheTrackedYoyoAsAYoyoDevice) {
  bridge::CameraServerConfig config;
  config.port = 0;
  config.description.name = "webcam";
  config.description.server = "yoyo_vision_program_test";
  config.description.fps = 25;
  config.description.fx = model_.fx;
  config.description.fy = model_.fy;
  config.description.cx = model_.cx;
  config.description.cy = model_.cy;
  config.description.pose = "fixed";
  config.description.jpeg_quality = 90;
  auto camera = bridge::CameraServer::Create(config);
  const Eigen::Isometry3d X_WC = X_world_camera();
  bridge::CameraPose pose;
  pose.valid = true;
  pose.p_WC = X_WC.translation();
  pose.q_WC = Eigen::Quaterniond(X_WC.linear());

  TestProcess vision(
      {VLAB_BINARY_DIR "/vlab", "vision", "--camera", "127.0.0.1:" + std::to_string(camera->port()), "--yoyo-port", "0",
       "--blob-color", "red", "--line", "0.725,0", "--frames", std::to_string(kFrames), "--duration", "30"},
      0);  // its start line comes once it has the camera: below
  for (int i = 0; i < 5000 && camera->subscribers() == 0; ++i) camera->Poll(0.002);
  ASSERT_EQ(camera->subscribers(), 1) << "vision did not subscribe to the camera";
  const std::string start = vision.WaitForStartLine(20);
  const std::size_t at = start.find("127.0.0.1:");
  ASSERT_NE(at, std::string::npos) << start;
  EXPECT_NE(start.find("(kind yoyo)"), std::string::npos) << start;
  const int port = std::stoi(start.substr(at + 10));

  std::optional<bridge::Device> yoyo;
  yoyo.emplace(bridge::Device::Connect(bridge::DeviceKind::kYoyo, "127.0.0.1", port, 5.0));
  EXPECT_EQ(yoyo->state_names(),
            (std::vector<std::string>(bridge::kYoyoStateLayout.begin(), bridge::kYoyoStateLayout.end())));
  EXPECT_EQ(yoyo->command_length(), 0);
  const nlohmann::json& describe = yoyo->describe();
  EXPECT_EQ(describe["kind"], "yoyo");
  EXPECT_EQ(describe["name"], "yoyo_vision");
  EXPECT_EQ(describe["server"], "vlab vision");
  EXPECT_EQ(describe["measures"], nlohmann::json({"x", "y", "z", "vz"}));
  EXPECT_EQ(describe["status_bits"]["not_seen"], bridge::kYoyoNotSeen);
  EXPECT_EQ(describe["camera"]["name"], "webcam");
  EXPECT_DOUBLE_EQ(describe["rates"]["control_hz"].get<double>(), 25.0);
  EXPECT_DOUBLE_EQ(describe["tracker"]["line"]["x"].get<double>(), 0.725);

  const std::vector<std::uint8_t> blank(640 * 480 * 3, 110);
  bridge::Device::State last;  // the last state that saw the yo-yo
  double worst_mm = 0;
  int seen = 0, not_seen = 0;
  for (int k = 0; k < kFrames; ++k) {
    const bool hidden = k % 5 == 4;  // frames without the yo-yo
    PlaceYoyo(0.1 + 0.85 * k / (kFrames - 1), 0.5 * k);
    Render();
    const std::int64_t id = kFirstId + k;
    const double exposure_s = 3.0 + k * 0.04;
    camera->Poll(0);
    ASSERT_TRUE(camera->SendImage(id, exposure_s, hidden ? blank.data() : rgb_.pixels.data(), pose)) << k;
    bridge::Device::State state;
    do {
      state = yoyo->Read(5.0);
    } while (state.seq < id);
    ASSERT_EQ(state.seq, id);
    EXPECT_DOUBLE_EQ(state.time, exposure_s);
    ASSERT_EQ(state.values.size(), 7u);
    const auto field = [&](const char* name) { return yoyo->Field(state, name); };
    if (hidden) {
      ++not_seen;
      EXPECT_EQ(field("status"), static_cast<double>(bridge::kYoyoNotSeen)) << k;
      for (const char* name : {"x", "y", "z", "vz", "string_force", "spin"}) {
        EXPECT_EQ(field(name), yoyo->Field(last, name)) << k << " " << name;
      }
      continue;
    }
    ++seen;
    EXPECT_EQ(field("status"), 0.0) << k;
    const double err_mm = 1000 * std::abs(field("z") - TrueCentre().z());
    EXPECT_LT(err_mm, 3.0) << k;  // JPEG q90: 0.3-1.2 mm, one frame 2.5 mm (rendered raw: <= 0.5 mm)
    EXPECT_NEAR(field("x"), 0.725, 0.002) << k;
    EXPECT_NEAR(field("y"), 0.0, 1e-9) << k;  // the plane facing a camera on -y is y = 0
    EXPECT_EQ(field("string_force"), 0.0);
    EXPECT_EQ(field("spin"), 0.0);
    worst_mm = std::max(worst_mm, err_mm);
    std::printf("  frame %d z %.3f err %.2f mm\n", k, TrueCentre().z(), 1000 * (field("z") - TrueCentre().z()));
    last = state;
  }
  std::printf("vlab vision --yoyo-port over UDP: %d JPEG frames, %d seen (worst z error %.2f mm), %d not seen\n",
              kFrames, seen, worst_mm, not_seen);
  yoyo.reset();
  EXPECT_EQ(vision.Wait(), 0) << vision.output();
  const std::string& rest = vision.output();
  EXPECT_NE(rest.find("vlab vision: " + std::to_string(kFrames) + " frames"), std::string::npos) << rest;
  EXPECT_NE(rest.find("yo-yo seen in " + std::to_string(seen) + ", no blob " + std::to_string(not_seen)),
            std::string::npos)
      << rest;
}

TEST(YoyoVisionCommand, BadOptionsExitTwo) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--camera 127.0.0.1:50013 --yoyo-port 0 --blob-color green", "--blob-color 'green'"},
      {"--camera 127.0.0.1:50013 --yoyo-port 0 --line 0.7", "--line '0.7': expected X,Y"},
      {"--camera 127.0.0.1:50013 --yoyo-port 0 --line 0.7,y", "expected X,Y"},
      {"--camera 127.0.0.1:50013 --yoyo-port 70000", "--yoyo-port 70000 outside 0..65535"},
      {"--camera 127.0.0.1:50013 --yoyo-port 0 --marker 4X4_50:1:0.02", "exclude each other"},
  };
  for (const auto& [args, message] : cases) {
    const ProcessResult r = RunVlab("vision " + args, 30);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(Lines(r.err).size(), 1u) << r.err;
  }
}

}  // namespace
}  // namespace vlab::testing
