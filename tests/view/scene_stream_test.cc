// Tests the scene stream (src/lab/devices/device_scene.cc) over the real wire:
// `vlab serve` runs a passive pendulum (a rod and a ball on a hinge, no
// controller) with a scene device at 50 Hz; a client subscribes like a viewer.
//   - the describe reply names the one moving visual body and its geoms, the
//     static floor with body -1;
//   - frames come at the configured rate: consecutive frames are exactly
//     1 / 50 s of simulated time and 10 control periods (0.02 / 0.002) apart;
//   - the pose of the bob in every frame equals MuJoCo's xpos / xquat of the
//     same model stepped here to the frame's time, to float32 precision
//     (2^-23 relative; the browser draws float32), which an independent
//     mj_step of a deterministic passive model must give;
//   - the same through `vlab view` attached to the device: the frames of its
//     WebSocket (what the page reads: float32 poses) carry the same poses, at
//     times that are whole multiples of 1 / 50 s (a client may skip frames:
//     newest wins), and keep coming for 0.5 s of simulated time after the
//     first; the view attaches whenever its start lets it (a realtime run
//     does not wait for a viewer), so the run is long and the test ends it
//     (SIGINT) once it has what it compares;
//   - the log of that served run, with both attached, is byte-identical
//     to the log of the same scenario under `vlab run` (fast, no viewer) and
//     to the log of the scenario without the scene device at all, both run
//     for the periods the served run ran.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client_device.h"
#include "test_process.h"
#include "test_run_output.h"
#include "test_util.h"
#include "view_clients.h"

namespace vlab {
namespace {

using testing::ReadFile;
using testing::TempDir;
using testing::TestProcess;
using testing::WriteFile;

constexpr double kRateHz = 50;                // the scene device's rate
constexpr double kPeriod_s = 0.002;           // the scenario's control period
constexpr double kFloat32 = 1.0 / (1 << 23);  // float32's relative precision

constexpr const char* kXml = R"(<mujoco>
  <option timestep="0.001"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1" rgba="0.8 0.8 0.8 1"/>
    <body name="bob" pos="0 0 1">
      <joint name="swing" type="hinge" axis="0 1 0"/>
      <geom name="rod" type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" rgba="1 0 0 1"/>
      <geom name="ball" type="sphere" pos="0.5 0 0" size="0.05" rgba="0 0 1 1"/>
      <geom name="hidden" type="sphere" size="0.01" group="3"/>
    </body>
  </worldbody>
</mujoco>
)";

std::string Scenario(bool with_scene) {
  std::string s =
      "name: pendulum\nscene: pendulum.xml\nduration: 60.0\ncontrol_period: 0.002\nclock: realtime\n"
      "devices:\n";
  if (with_scene) return s + "  - {name: scene, kind: scene, port: 50990, rate: 50}\n";
  return s + "  []\n";
}

// the port of "LABEL ADDRESS:PORT" in vlab serve's start line (0: not there)
int PortOf(const std::string& line, const std::string& label) {
  const std::size_t at = line.find(label);
  const std::size_t colon = at == std::string::npos ? at : line.find(':', at + label.size());
  return colon == std::string::npos ? 0 : std::atoi(line.c_str() + colon + 1);
}

class SceneStreamTest : public ::testing::Test {
 protected:
  struct WsFrame {
    double time = 0;
    float pose[7] = {};
  };
  std::vector<WsFrame> ws_frames_;
  void SetUp() override {
    WriteFile(dir_ / "pendulum.xml", kXml);
    WriteFile(dir_ / "with.yaml", Scenario(true));
    WriteFile(dir_ / "without.yaml", Scenario(false));
  }
  TempDir dir_;
};

TEST_F(SceneStreamTest, PosesEqualMujocosAtTheRateAndTheLogIsUntouched) {
  TestProcess serve(
      {VLAB_BINARY_DIR "/vlab", "serve", dir_ / "with.yaml", "--port", "scene=0", "--out", dir_ / "served", "-q"});
  const int port = PortOf(serve.start_line(), "scene (scene)");
  ASSERT_GT(port, 0) << serve.start_line();
  bridge::Device scene = bridge::Device::Connect(bridge::DeviceKind::kScene, "127.0.0.1", port, 5.0);

  // the describe reply: one streamed body, its two visible geoms and the world's floor
  const nlohmann::json& describe = scene.describe();
  ASSERT_EQ(describe["bodies"], nlohmann::json::array({"bob"}));
  ASSERT_EQ(describe["geoms"].size(), 3u);  // the group-3 geom is not drawn
  EXPECT_EQ(describe["geoms"][0]["name"], "floor");
  EXPECT_EQ(describe["geoms"][0]["body"], -1);
  EXPECT_EQ(describe["geoms"][2]["type"], "sphere");
  EXPECT_EQ(describe["geoms"][2]["rgba"], nlohmann::json::array({0, 0, 1, 1}));
  EXPECT_DOUBLE_EQ(describe["rate_hz"].get<double>(), kRateHz);
  EXPECT_EQ(scene.state_length(), 7);

  // vlab view on the same device, and a WebSocket client of its page's stream
  TestProcess view(
      {VLAB_BINARY_DIR "/vlab", "view", "--scene", "127.0.0.1:" + std::to_string(port), "--http", "0", "-q"});
  const int http_port = PortOf(view.start_line(), "http://127.0.0.1");
  ASSERT_GT(http_port, 0) << view.start_line();
  view::view_test::WsOptions options = view::view_test::ViewerOptions("/ws");
  options.read_timeout = std::chrono::seconds(20);  // a stream that stops is a failure, not a hang
  view::view_test::WsClient ws(http_port, options);
  std::atomic<bool> ws_done{false};
  bool ws_went_on = false;  // frames came for 0.5 s of simulated time after the first
  std::thread reader([&ws, &ws_done, &ws_went_on, this] {
    // the page's frames: float64 time, float64 seq, 7 float32 (lab_poses.h)
    for (;;) {
      std::string m;
      if (!ws.TryRead(&m)) break;
      if (m.size() != 16 + 28) continue;
      WsFrame f;
      std::memcpy(&f.time, m.data(), 8);
      std::memcpy(f.pose, m.data() + 16, 28);
      ws_frames_.push_back(f);
      if (f.time >= ws_frames_.front().time + 0.5) {
        ws_went_on = true;
        break;
      }
    }
    ws_done.store(true, std::memory_order_release);
  });

  // frames for at least 1 s of simulated time, and until those the view sent are all here
  std::vector<bridge::Device::State> frames;
  auto have_all = [&frames, &ws_done, this] {
    if (frames.empty() || frames.back().time < 1.0 || !ws_done.load(std::memory_order_acquire)) return false;
    return ws_frames_.empty() || frames.back().time >= ws_frames_.back().time;
  };
  try {
    while (!have_all()) {
      frames.push_back(scene.Read(5.0));
      if (frames.size() % 50 == 0) scene.KeepAlive();  // a passive subscriber renews (protocol.md)
    }
  } catch (...) {
    reader.join();  // (it ends with the stream or at its read timeout)
    throw;
  }
  reader.join();
  // the served run ends here: every period that ran is written, as the log of that many periods
  ASSERT_EQ(serve.Stop(20), 1) << serve.output();
  const long periods = testing::ExpectInterruptedOutput(dir_ / "served", "SIGINT", kPeriod_s);
  ASSERT_GE(static_cast<double>(periods) * kPeriod_s, frames.back().time - 1e-9) << "the run ended before its frames";
  view.Stop();
  ASSERT_GE(frames.size(), 40u);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_NEAR(frames[i].time - frames[i - 1].time, 1.0 / kRateHz, 1e-9) << "frame " << i;
    EXPECT_EQ(frames[i].seq - frames[i - 1].seq, static_cast<std::int64_t>(std::lround(1 / kRateHz / kPeriod_s)));
  }

  // the same model stepped here: the bob's pose at every frame's time
  char error[512] = "";
  mjModel* m = mj_loadXML((dir_ / "pendulum.xml").c_str(), nullptr, error, sizeof(error));
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  const int bob = mj_name2id(m, mjOBJ_BODY, "bob");
  double moved = 0;
  for (const bridge::Device::State& f : frames) {
    while (d->time < f.time - 1e-9) mj_step(m, d);
    ASSERT_NEAR(d->time, f.time, 1e-9);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f.values[i], d->xpos[3 * bob + i], kFloat32 * 1.0) << "t " << f.time;
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(f.values[3 + i], d->xquat[4 * bob + i], kFloat32) << "t " << f.time;
    moved = std::max(moved, std::abs(f.values[3] - 1.0));
  }
  EXPECT_GT(moved, 0.01) << "the pendulum must swing, or the comparison shows nothing";

  // the WebSocket's frames: the poses of the UDP frames of the same time, as float32
  // the view sends a reader that lags the newest frame and drops the ones it did not take
  // (latest only: it never holds the run up), so how many of the 25 frames of its 0.5 s arrive
  // depends on the CPU the reader gets; but the stream goes on reaching it
  ASSERT_GE(ws_frames_.size(), 2u);
  EXPECT_TRUE(ws_went_on) << "the stream stopped at t = " << ws_frames_.back().time << " s, "
                          << ws_frames_.back().time - ws_frames_.front().time << " s after the reader's first frame";
  for (const WsFrame& w : ws_frames_) {
    const double k = w.time * kRateHz;
    EXPECT_NEAR(k, std::round(k), 1e-6) << "t " << w.time << " is not a frame time";
    const bridge::Device::State* same = nullptr;
    for (const auto& f : frames) {
      if (std::abs(f.time - w.time) < 1e-9) same = &f;
    }
    ASSERT_NE(same, nullptr) << "t " << w.time;
    for (int i = 0; i < 7; ++i) EXPECT_EQ(w.pose[i], static_cast<float>(same->values[i])) << "t " << w.time;
  }
  mj_deleteData(d);
  mj_deleteModel(m);

  // the log: served with a viewer attached == run fast without one == without the device
  const std::string ran = " --duration " + testing::DurationOfPeriods(periods, kPeriod_s);
  const testing::ProcessResult fast =
      testing::RunVlab("run " + (dir_ / "with.yaml") + " --out " + (dir_ / "fast") + ran);
  ASSERT_EQ(fast.exit_code, 0) << fast.err;
  const testing::ProcessResult none =
      testing::RunVlab("run " + (dir_ / "without.yaml") + " --out " + (dir_ / "none") + ran);
  ASSERT_EQ(none.exit_code, 0) << none.err;
  const std::string served = ReadFile(dir_ / "served/log.csv");
  ASSERT_GT(served.size(), 1000u);
  EXPECT_TRUE(served == ReadFile(dir_ / "fast/log.csv")) << "served log differs from the fast run's";
  EXPECT_TRUE(served == ReadFile(dir_ / "none/log.csv")) << "the scene device changed the log";
}

}  // namespace
}  // namespace vlab
