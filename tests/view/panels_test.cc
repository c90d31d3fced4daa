// Tests the view's panels over the real wire: `vlab serve` runs the PA10
// swinging through joint waypoints in real time with a scene device and a
// simulated webcam (JPEG, MJCF camera "overview"); `vlab view --scene ...
// --camera ... --plot pa10.q.S1,pa10.qd.E1` relays them (the scene device
// sends log signals after the poses: signals: [...]), and
// WebSocket clients read its /camera and /plot channels while the test
// subscribes to the camera directly.
//   - /camera: every message's picture is, byte for byte, the JPEG the camera
//     sent for the same frame id (the test's own subscription got the same
//     frames), with the frame's stamp, width and height in the header; it
//     decodes to width x height;
//   - /plot: every sample equals the log.csv row of the same time exactly
//     (the scene device copies the period's log row; the log writes shortest
//     round-trip decimals), samples come at the scene device's rate (30 Hz:
//     times 1/30 s apart, give or take a control period) and they move;
//   - the served log is byte-identical to the same scenario run fast for the
//     periods it ran: the view attaches whenever its start lets it (a realtime
//     run does not wait for a viewer), so the arm swings for up to 60 s and the
//     test ends the run (SIGINT) once it has 3 s of frames and samples;
//   - a raw RGB8 frame goes out as PNG that decodes to the same pixels;
//   - bad --plot and scene `signals:` are refused with exit 2 and a message
//     naming the option or the scenario entry.
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_camera_client.h"
#include "render/image_codec.h"
#include "scene/scene_csv.h"
#include "test_process.h"
#include "test_run_output.h"
#include "test_util.h"
#include "view/view_panels.h"
#include "view_clients.h"

namespace vlab {
namespace {

using testing::TempDir;
using testing::TestProcess;

constexpr double kPlotRateHz = 30;   // the scene device's rate
constexpr double kPeriod_s = 0.002;  // the scenario's control period
constexpr int kCameraWidth = 160, kCameraHeight = 120;

std::string Scenario() {
  std::string text =
      std::string("name: panels\nscene: ") + VLAB_SOURCE_DIR +
      "/scenes/pa10.xml\nduration: 60.0\ncontrol_period: 0.002\nseed: 1\nclock: realtime\n"
      "devices:\n"
      "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2],"
      " initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0]}\n"
      "  - {name: scene, kind: scene, port: 50990, rate: 30, signals: [pa10.q.S1, pa10.qd.E1, pa10.q.E1]}\n"
      "  - {name: webcam, kind: camera, port: 50991, camera: overview, width: 160, height: 120, fps: 15,"
      " encoding: jpeg, jpeg_quality: 80, profile: fast}\n"
      "controller:\n  type: joint_pd\n  arm: pa10\n  tip_site: tool\n  gains: {bandwidth_hz: 5}\n"
      "  timing: quintic\n  start: 0.0\n  waypoints:\n";
  for (int leg = 0; leg < 40; ++leg) {  // S1 from 1.2 to -1.2 rad and back, 1.5 s a leg, for the 60 s
    text += leg % 2 == 0 ? "    - {q: [1.2, 0.523599, 0, 0.3, 0, 1.570796, 0], duration: 1.5}\n"
                         : "    - {q: [-1.2, 0.523599, 0, 1.6, 0, 1.570796, 0], duration: 1.5}\n";
  }
  return text;
}

int PortOf(const std::string& line, const std::string& label) {
  const std::size_t at = line.find(label);
  const std::size_t colon = at == std::string::npos ? at : line.find(':', at + label.size());
  return colon == std::string::npos ? 0 : std::atoi(line.c_str() + colon + 1);
}

// a WebSocket client of one channel of the view, reading on its own thread until the view goes
class ChannelReader {
 public:
  ChannelReader(int port, const std::string& path) : ws_(port, view::view_test::ViewerOptions(path)) {
    thread_ = std::thread([this] {
      for (;;) {
        std::string m;
        if (!ws_.TryRead(&m)) return;
        std::lock_guard<std::mutex> lock(mutex_);
        messages_.push_back(std::move(m));
      }
    });
  }
  ~ChannelReader() { Join(); }
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  std::vector<std::string> messages() {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }

 private:
  view::view_test::WsClient ws_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<std::string> messages_;
};

template <typename T>
T At(const std::string& m, std::size_t offset) {
  T v;
  std::memcpy(&v, m.data() + offset, sizeof(T));
  return v;
}

TEST(ViewPanelsTest, CameraBytesRelayedUnchangedAndPlotSamplesEqualTheLog) {
  TempDir dir;
  testing::WriteFile(dir / "panels.yaml", Scenario());
  TestProcess serve({VLAB_BINARY_DIR "/vlab", "serve", dir / "panels.yaml", "--port", "scene=0", "--port", "webcam=0",
                     "--out", dir / "run", "-q"});
  const int scene_port = PortOf(serve.start_line(), "scene (scene)");
  const int camera_port = PortOf(serve.start_line(), "webcam (camera)");
  ASSERT_GT(scene_port, 0) << serve.start_line();
  ASSERT_GT(camera_port, 0) << serve.start_line();
  auto address = [](int port) { return "127.0.0.1:" + std::to_string(port); };
  TestProcess view({VLAB_BINARY_DIR "/vlab", "view", "--scene", address(scene_port), "--camera", address(camera_port),
                    "--plot", "pa10.q.S1,pa10.qd.E1", "--http", "0", "-q"});
  const int http_port = PortOf(view.start_line(), "http://127.0.0.1");
  ASSERT_GT(http_port, 0) << view.start_line();
  ChannelReader camera_channel(http_port, "/camera"), plot_channel(http_port, "/plot");

  // the camera's frames as it sends them, by id, for 3 s (45 frames), and until the plot's
  // samples span 3 s; then the run ends
  bridge::CameraClientOptions options;
  options.decode = false;
  bridge::CameraClient camera = bridge::CameraClient::Connect("127.0.0.1", camera_port, options);
  std::map<std::int64_t, bridge::CameraFrame> sent;
  auto plot_span = [&plot_channel] {
    const std::vector<std::string> m = plot_channel.messages();
    return m.size() < 2 || m.front().size() < 8 || m.back().size() < 8
               ? 0.0
               : At<double>(m.back(), 0) - At<double>(m.front(), 0);
  };
  try {
    while (sent.size() < 45 || plot_span() < 3.0) {
      bridge::CameraClient::Frame f = camera.Receive(5.0);
      sent[f.id] = f;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the frames stopped (" << sent.size() << " camera frames, plot span " << plot_span()
                  << " s): " << e.what();
  }
  const int serve_exit = serve.Stop(30);
  const int view_exit = view.Stop();
  camera_channel.Join();
  plot_channel.Join();
  ASSERT_EQ(serve_exit, 1) << serve.output();
  ASSERT_EQ(view_exit, 0) << view.output();
  const long periods = testing::ExpectInterruptedOutput(dir / "run", "SIGINT", kPeriod_s);
  ASSERT_GT(periods, 0);

  // /camera: the JPEG bytes of the same frame, unchanged
  const std::vector<std::string> pictures = camera_channel.messages();
  ASSERT_GE(sent.size(), 45u) << "15 fps for 3 s";
  int matched = 0;
  for (const std::string& m : pictures) {
    ASSERT_GT(m.size(), static_cast<std::size_t>(view::kCameraHeaderBytes));
    const auto id = static_cast<std::int64_t>(At<double>(m, 8));
    auto f = sent.find(id);
    if (f == sent.end()) continue;  // a frame the test's subscription missed
    ++matched;
    EXPECT_EQ(At<double>(m, 0), f->second.time_s) << "frame " << id;
    EXPECT_EQ(At<std::uint32_t>(m, 16), static_cast<std::uint32_t>(kCameraWidth));
    EXPECT_EQ(At<std::uint32_t>(m, 20), static_cast<std::uint32_t>(kCameraHeight));
    const std::string picture = m.substr(view::kCameraHeaderBytes);
    EXPECT_TRUE(picture == std::string(f->second.data.begin(), f->second.data.end())) << "frame " << id;
    const render::Image image =
        render::DecodeImage(std::vector<std::uint8_t>(picture.begin(), picture.end()), render::DecodeMode::kColor);
    EXPECT_EQ(image.width, kCameraWidth);
    EXPECT_EQ(image.height, kCameraHeight);
  }
  // newest wins: a client reading at once on loopback gets most frames
  EXPECT_GE(matched, static_cast<int>(sent.size() / 2)) << pictures.size() << " pictures relayed";

  // /plot: each sample is the log row of its time
  const scene::CsvTable log = scene::ReadCsvTable(dir / "run/log.csv");
  const int time_col = log.Column("time"), q_col = log.Column("pa10.q.S1"), qd_col = log.Column("pa10.qd.E1");
  ASSERT_GE(q_col, 0);
  ASSERT_GE(qd_col, 0);
  std::map<long, const std::vector<double>*> rows;  // by period
  for (const auto& row : log.rows) rows[std::lround(row[time_col] / kPeriod_s)] = &row;
  const std::vector<std::string> samples = plot_channel.messages();
  ASSERT_GE(samples.size(), 45u) << "30 Hz over 3 s: a reader at once on loopback gets at least half";
  double last_time = -1, q_min = 1e9, q_max = -1e9;
  for (const std::string& m : samples) {
    ASSERT_EQ(m.size(), 32u);
    const double t = At<double>(m, 0);
    auto row = rows.find(std::lround(t / kPeriod_s));
    ASSERT_NE(row, rows.end()) << "no log row at t = " << t;
    EXPECT_EQ((*row->second)[time_col], t);
    EXPECT_EQ((*row->second)[q_col], At<double>(m, 16)) << "pa10.q.S1 at t = " << t;
    EXPECT_EQ((*row->second)[qd_col], At<double>(m, 24)) << "pa10.qd.E1 at t = " << t;
    if (last_time >= 0) {
      EXPECT_GE(t - last_time, 1 / kPlotRateHz - kPeriod_s - 1e-9) << "t = " << t;
      const double frames = (t - last_time) * kPlotRateHz;  // whole frames apart (a slow reader skips some)
      EXPECT_NEAR(frames, std::round(frames), kPeriod_s * kPlotRateHz + 1e-9) << "t = " << t;
    }
    last_time = t;
    q_min = std::min(q_min, At<double>(m, 16));
    q_max = std::max(q_max, At<double>(m, 16));
  }
  EXPECT_GT(q_max - q_min, 1.0) << "S1 swings from 0 to 1.2 to -1.2 rad: the plot must show it";
  std::printf("camera: %zu frames sent, %zu relayed, %d compared; plot: %zu samples\n", sent.size(), pictures.size(),
              matched, samples.size());

  // the signals only read the log row: the served log (signals, view, camera) is the fast run's
  // of the same periods
  const testing::ProcessResult fast =
      testing::RunVlab("run " + (dir / "panels.yaml") + " --out " + (dir / "fast") + " -q --duration " +
                       testing::DurationOfPeriods(periods, kPeriod_s));
  ASSERT_EQ(fast.exit_code, 0) << fast.err;
  EXPECT_TRUE(testing::ReadFile(dir / "run/log.csv") == testing::ReadFile(dir / "fast/log.csv"))
      << "the served log differs from the fast run's";
}

TEST(ViewPanelsTest, ARawFrameGoesOutAsPngOfTheSamePixels) {
  bridge::CameraFrame f;
  f.id = 42;
  f.time_s = 1.25;
  f.width = 7;
  f.height = 5;
  f.encoding = bridge::CameraEncoding::kRaw;
  for (int i = 0; i < 7 * 5 * 3; ++i) f.data.push_back(static_cast<std::uint8_t>(i * 37 % 256));
  const std::string m = view::EncodeCameraMessage(f);
  EXPECT_EQ(At<double>(m, 0), 1.25);
  EXPECT_EQ(At<double>(m, 8), 42.0);
  const std::string png = m.substr(view::kCameraHeaderBytes);
  ASSERT_EQ(png.substr(1, 3), "PNG");
  const render::Image rgb =
      render::DecodeImage(std::vector<std::uint8_t>(png.begin(), png.end()), render::DecodeMode::kColor);
  ASSERT_EQ(rgb.width, 7);
  ASSERT_EQ(rgb.height, 5);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 7; ++u) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(rgb.bytes[3 * (v * 7 + u) + c], f.data[3 * (v * 7 + u) + c]) << u << "," << v << " channel " << c;
      }
    }
  }
}

TEST(ViewPanelsTest, BadPlotOptionsAndSignalsAreRefused) {
  struct Case {
    const char* args;
    const char* message;
  } cases[] = {
      {"view --scene 127.0.0.1:9 --plot pa10.q.S1,", "expected signal names"},
      {"view --scene 127.0.0.1:9 --plot a,b,c,d,e,f,g,h,i", "at most 8 signals"},
      {"view --replay nowhere --camera 127.0.0.1:9", "--camera is for live views"},
      {"run SCENARIO", "signals: the log has no column 'pa10.q.S9'"},
  };
  TempDir dir;
  std::string scenario = Scenario();
  scenario.replace(scenario.find("pa10.qd.E1"), 10, "pa10.q.S9");
  testing::WriteFile(dir / "bad.yaml", scenario);
  for (const Case& c : cases) {
    std::string args = c.args;
    if (args.find("SCENARIO") != std::string::npos) args.replace(args.find("SCENARIO"), 8, dir / "bad.yaml");
    const testing::ProcessResult r = testing::RunVlab(args + (args.compare(0, 4, "view") == 0 ? " --http 0" : ""));
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace vlab
