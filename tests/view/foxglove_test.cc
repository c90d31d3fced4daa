// Tests `vlab view --foxglove` end to end with Foxglove's own client: `vlab
// serve` runs the PA10 swinging S1 in real time with a scene device (signals:
// three joint columns and a torque) and a simulated webcam (JPEG 160 x 120);
// `vlab view --scene ... --camera ... --foxglove 0 --allow-origin
// https://app.foxglove.dev` streams them, and tests/node/foxglove_client.mjs
// (@foxglove/ws-protocol's FoxgloveClient, @foxglove/rosmsg and
// rosmsg2-serialization; what each check is: the script's comment) connects,
// decodes and compares with the run's log.csv. Here:
//   - the script exits 0, and its line counts what it compared;
//   - the run lasts until the client has collected what it checks (it says
//     so on its first line), then is interrupted (SIGINT), which writes its
//     log; the script then compares and exits 0, and its line counts what it
//     compared;
//   - the view's counter line shows the refused Origin and the two refused
//     client writes (the stream stayed read-only);
//   - bad --foxglove and --allow-origin values are refused with exit 2.
#include <string>

#include <gtest/gtest.h>

#include "test_process.h"
#include "test_util.h"

namespace vlab {
namespace foxglove_test {

using testing::TempDir;
using testing::TestProcess;

std::string Scenario() {
  return std::string("name: foxglove\nscene: ") + VLAB_SOURCE_DIR +
         "/scenes/pa10.xml\nduration: 60.0\ncontrol_period: 0.002\nseed: 1\nclock: realtime\n"
         "devices:\n"
         "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2],"
         " initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0]}\n"
         "  - {name: scene, kind: scene, port: 50990, rate: 30,"
         " signals: [pa10.q.S1, pa10.q.S2, pa10.qd.E1, pa10.tau.S1]}\n"
         "  - {name: webcam, kind: camera, port: 50991, camera: overview, width: 160, height: 120, fps: 15,"
         " encoding: jpeg, jpeg_quality: 80, profile: fast}\n"
         "controller:\n  type: joint_pd\n  arm: pa10\n  tip_site: tool\n  gains: {bandwidth_hz: 5}\n"
         "  timing: quintic\n  start: 0.0\n  waypoints:\n"
         "    - {q: [1.2, 0.523599, 0, 0.3, 0, 1.570796, 0], duration: 1.5}\n"
         "    - {q: [-1.2, 0.523599, 0, 1.6, 0, 1.570796, 0], duration: 1.5}\n";
}

// the port after `label` ("http://127.0.0.1:") in a line (0: not there)
int PortAfter(const std::string& line, const std::string& label) {
  const std::size_t at = line.find(label);
  return at == std::string::npos ? 0 : std::atoi(line.c_str() + at + label.size());
}

TEST(FoxgloveTest, FoxgloveClientDecodesTheLogsJointStatesAnImageAndTheTransforms) {
  TempDir dir;
  testing::WriteFile(dir / "foxglove.yaml", Scenario());
  TestProcess serve({VLAB_BINARY_DIR "/vlab", "serve", dir / "foxglove.yaml", "--port", "scene=0", "--port", "webcam=0",
                     "--out", dir / "run", "-q"});
  const int scene_port = PortAfter(serve.start_line(), "scene (scene) 127.0.0.1:"),
            camera_port = PortAfter(serve.start_line(), "webcam (camera) 127.0.0.1:");
  ASSERT_GT(scene_port, 0) << serve.start_line();
  ASSERT_GT(camera_port, 0) << serve.start_line();
  auto address = [](int port) { return "127.0.0.1:" + std::to_string(port); };
  TestProcess view({VLAB_BINARY_DIR "/vlab", "view", "--scene", address(scene_port), "--camera", address(camera_port),
                    "--http", "0", "--foxglove", "0", "--allow-origin", "https://app.foxglove.dev", "-q"});
  const int http_port = PortAfter(view.start_line(), "http://127.0.0.1:");
  const int foxglove_port = PortAfter(view.start_line(), "foxglove ws://127.0.0.1:");
  ASSERT_GT(http_port, 0) << view.start_line();
  ASSERT_GT(foxglove_port, 0) << view.start_line();
  EXPECT_NE(view.start_line().find("(4 channels)"), std::string::npos) << "/tf, /scene, /pa10, /camera/webcam";

  TestProcess client(
      {VLAB_NODE, VLAB_SOURCE_DIR "/tests/node/foxglove_client.mjs", "--foxglove", std::to_string(foxglove_port),
       "--http", std::to_string(http_port), "--log", dir / "run/log.csv", "--device", "pa10", "--camera", "webcam",
       "--width", "160", "--height", "120", "--allowed-origin", "https://app.foxglove.dev"},
      0);
  // the run goes on until the client has what it came for (its first line), then is interrupted: its log is
  // written up to there
  EXPECT_NE(client.WaitForStartLine(60).find("foxglove_client: collected"), std::string::npos) << client.output();
  serve.Stop();
  EXPECT_EQ(client.Wait(60), 0) << client.output();
  std::printf("%s", client.output().c_str());
  EXPECT_NE(client.output().find("10 /pa10 messages (4 fields each, 40 values equal to the log)"), std::string::npos)
      << client.output();
  ASSERT_EQ(view.Stop(), 0) << view.output();
  EXPECT_NE(view.output().find("(1 refused for their Host or Origin"), std::string::npos) << view.output();
  EXPECT_NE(view.output().find("2 client writes refused (read-only), 0 malformed"), std::string::npos) << view.output();
}

TEST(FoxgloveTest, BadOptionsAreRefused) {
  TempDir dir;
  const testing::ProcessResult replay = testing::RunVlab("view --replay " + (dir / "none") + " --foxglove 0");
  EXPECT_EQ(replay.exit_code, 2);
  EXPECT_NE(replay.err.find("--foxglove is for live views"), std::string::npos) << replay.err;
  const testing::ProcessResult port = testing::RunVlab("view --scene 127.0.0.1:9 --foxglove 70000");
  EXPECT_EQ(port.exit_code, 2);
  EXPECT_NE(port.err.find("--foxglove must be 0 to 65535"), std::string::npos) << port.err;
  // (the forms --allow-origin refuses: FoxgloveProtocolTest.AllowOriginTakesWholeOrigins)
  const testing::ProcessResult origin =
      testing::RunVlab("view --scene 127.0.0.1:9 --foxglove 0 --allow-origin https://app.foxglove.dev/");
  EXPECT_EQ(origin.exit_code, 2);
  EXPECT_NE(origin.err.find("--allow-origin 'https://app.foxglove.dev/': expected a whole origin"), std::string::npos)
      << origin.err;
}

}  // namespace foxglove_test
}  // namespace vlab
