// Browser tests of the view's replay and panels: headless Chromium
// (SwiftShader WebGL) opens the page of `vlab view`.
// Replay (`vlab view --replay RUN --plot pa10.q.S1`, the page's clock driven
// by the test: ?clock=manual, vlabView.tick(ms) advances the replay as one
// animation frame of that length would):
//   - moving the time slider (its value set, an input event sent: what a
//     user's drag does) shows the recorded frame at or before the chosen
//     time, the last one not after it: the clock and every body's pose equal
//     poses.bin's frame exactly (float32 in both);
//   - speed control: at speed s, n ticks of d ms move the replay's own frame
//     timestamps by s * n * d / 1000 s, within one recording interval (1/30 s),
//     and the frame shown then is that recorded frame; measured at 0.5x, 1x
//     and 5x;
//   - the plot panel: plots.bin holds log.csv's time and pa10.q.S1 exactly,
//     and its canvas shows the signal's colour;
//   - `vlab view --bind`: an IPv6 address printed in brackets, a warning on
//     stderr when bound beyond loopback (0.0.0.0), none on loopback;
//   - paused, the plot still follows the slider (its window ends at the
//     slider's time), and Space pauses and resumes after a click on the pause
//     button, and with the button focused (a focused button would take Space
//     as a second click and undo the toggle).
// Live panels (a served scenario with a webcam: `vlab view --scene --camera
// --plot`, the scene device sending the signals): the camera panel's image decodes to the camera's size
// and is not blank, and the plot canvas shows its signals' colours; with
// room for two WebSockets (--max-connections 2), the page shows the server's
// "server full" reason for its third.
// Both fail, never skip, without Chromium (tools/setup.sh installs it for tests).
// With $VLAB_VIEW_PANELS_SCREENSHOT set, the live test also writes its page's
// screenshot there (docs/view_panels.png is one).
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cdp_client.h"
#include "scene/scene_csv.h"
#include "test_process.h"
#include "test_util.h"

namespace vlab {
namespace {

using testing::TempDir;
using testing::TestProcess;

constexpr double kPoseRateHz = 30;  // outputs.poses.rate
constexpr int kWidth = 640, kHeight = 480;

std::string Scenario(bool served) {
  std::string s = std::string("name: replay\nscene: ") + VLAB_SOURCE_DIR +
                  "/scenes/pa10.xml\nduration: " + std::string(served ? "20.0" : "3.0") +
                  "\ncontrol_period: 0.002\nseed: 1\nclock: " + (served ? "realtime" : "fast") +
                  "\ndevices:\n"
                  "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2],"
                  " initial: [0, 0.523599, 0, 1.047198, 0, 1.570796, 0]}\n";
  if (served) {
    s += "  - {name: scene, kind: scene, port: 50990, rate: 30, signals: [pa10.q.S1, pa10.qd.E1, pa10.q.E1]}\n"
         "  - {name: webcam, kind: camera, port: 50991, camera: overview, width: 160, height: 120, fps: 15,"
         " encoding: jpeg, jpeg_quality: 80, profile: fast}\n";
  }
  s += "controller:\n  type: joint_pd\n  arm: pa10\n  tip_site: tool\n  gains: {bandwidth_hz: 5}\n"
       "  timing: quintic\n  start: 0.0\n  waypoints:\n"
       "    - {q: [1.2, 0.523599, 0, 0.3, 0, 1.570796, 0], duration: 1.5}\n"
       "    - {q: [-1.2, 0.523599, 0, 1.6, 0, 1.570796, 0], duration: 1.5}\n";
  if (!served) s += "outputs:\n  log: true\n  poses: {rate: 30}\n";
  return s;
}

int PortOf(const std::string& line, const std::string& label) {
  const std::size_t at = line.find(label);
  const std::size_t colon = at == std::string::npos ? at : line.find(':', at + label.size());
  return colon == std::string::npos ? 0 : std::atoi(line.c_str() + colon + 1);
}

// poses.bin: per frame float64 time, float64 period, 7 float32 per body
struct Recording {
  std::vector<double> times;
  std::vector<std::vector<float>> poses;
};
Recording ReadPoses(const std::string& path, int bodies) {
  const std::string bytes = testing::ReadFile(path);
  const std::size_t size = 16 + 28 * static_cast<std::size_t>(bodies);
  Recording r;
  for (std::size_t at = 0; at + size <= bytes.size(); at += size) {
    double t;
    std::memcpy(&t, bytes.data() + at, 8);
    std::vector<float> p(7 * bodies);
    std::memcpy(p.data(), bytes.data() + at + 16, 28 * bodies);
    r.times.push_back(t);
    r.poses.push_back(p);
  }
  return r;
}

nlohmann::json WaitFor(testing::Chromium& chromium, const std::string& condition, double timeout_s = 20) {
  for (int i = 0; i < timeout_s * 20; ++i) {
    const nlohmann::json v = nlohmann::json::parse(
        chromium.Evaluate("JSON.stringify(Object.assign({ok: !!(" + condition + ")}, window.vlabView || {}))")
            .get<std::string>());
    if (!v.value("error", std::string()).empty()) throw std::runtime_error("page: " + v["error"].get<std::string>());
    if (v["ok"].get<bool>()) return v;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  throw std::runtime_error("page: no " + condition + " within " + std::to_string(timeout_s) +
                           " s: " + chromium.Evaluate("JSON.stringify(window.vlabView)").dump());
}

// lets the page draw twice
void TwoFrames(testing::Chromium& chromium) {
  chromium.Evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(true))))");
}

// a double as JavaScript reads it back exactly
std::string Exact(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", v);
  return text;
}

// pixels of the plot canvas near colour (r, g, b) (a signal's line)
int ColourPixels(testing::Chromium& chromium, const std::string& canvas, int r, int g, int b) {
  return chromium
      .Evaluate("(function () { var c = document.getElementById('" + canvas +
                "'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data, n = 0;"
                " for (var i = 0; i < d.length; i += 4) if (Math.abs(d[i] - " +
                std::to_string(r) + ") < 40 && Math.abs(d[i + 1] - " + std::to_string(g) +
                ") < 40 && Math.abs(d[i + 2] - " + std::to_string(b) + ") < 40) ++n; return n; })()")
      .get<int>();
}

// `vlab view --replay DIR/run` plotting pa10.q.S1, and a Chromium to load its page (manual clock)
struct ReplayPage {
  explicit ReplayPage(const testing::TempDir& dir)
      : view({VLAB_BINARY_DIR "/vlab", "view", "--replay", dir / "run", "--plot", "pa10.q.S1", "--http", "0", "-q"}),
        http_port(PortOf(view.start_line(), "http://127.0.0.1")), chromium(dir / "profile", kWidth, kHeight) {}
  /// Opens the page and waits until its replay and plot data are in.
  void Load() {
    chromium.Call("Page.enable");
    chromium.Call("Page.navigate", {{"url", "http://127.0.0.1:" + std::to_string(http_port) + "/?clock=manual"}});
    WaitFor(chromium, "window.vlabView && vlabView.replayFrames && vlabView.plotSamples");
  }
  TestProcess view;
  int http_port;
  testing::Chromium chromium;
};

TEST(ViewReplayBrowserTest, SliderSeeksToTheRecordedFrameAndSpeedScalesPlayback) {
  TempDir dir;
  testing::WriteFile(dir / "replay.yaml", Scenario(false));
  const testing::ProcessResult run =
      testing::RunVlab("run " + (dir / "replay.yaml") + " --out " + (dir / "run") + " -q");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json scene = nlohmann::json::parse(testing::ReadFile(dir / "run/scene.json"));
  const int bodies = static_cast<int>(scene["bodies"].size());
  const Recording rec = ReadPoses(dir / "run/poses.bin", bodies);
  ASSERT_GE(rec.times.size(), 85u) << "3 s at 30 Hz";

  ReplayPage page(dir);
  ASSERT_GT(page.http_port, 0) << page.view.start_line();
  testing::Chromium& chromium = page.chromium;
  page.Load();

  // the slider: times between frames, at a frame, at the ends
  auto seek = [&](double t) {
    chromium.Evaluate("(function () { var s = document.getElementById('slider'); s.value = '" + Exact(t) + "'" +
                      "; s.dispatchEvent(new Event('input')); })()");
  };
  const std::size_t n = rec.times.size();
  for (const double t : {rec.times[0], rec.times[10] + 0.5 / kPoseRateHz, rec.times[40], rec.times[41] - 1e-4,
                         rec.times[n / 2] + 0.9 / kPoseRateHz, rec.times[n - 1]}) {
    seek(t);
    std::size_t k = 0;  // the last frame not after t
    while (k + 1 < n && rec.times[k + 1] <= t) ++k;
    const nlohmann::json shown = nlohmann::json::parse(
        chromium
            .Evaluate("JSON.stringify({time: vlabView.time, poses: Array.from({length: " + std::to_string(bodies) +
                      "}, (_, i) => vlabView.pose(i))})")
            .get<std::string>());
    EXPECT_EQ(shown["time"].get<double>(), rec.times[k]) << "slider at " << t;
    for (int b = 0; b < bodies; ++b) {
      for (int v = 0; v < 7; ++v) {
        EXPECT_EQ(shown["poses"][b][v].get<double>(), static_cast<double>(rec.poses[k][7 * b + v]))
            << "slider at " << t << ", body " << scene["bodies"][b] << ", value " << v;
      }
    }
  }
  // the recording moves: the comparisons above are not of one still pose
  double moved = 0;
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t v = 0; v < rec.poses[k].size(); ++v) {
      moved = std::max(moved, static_cast<double>(std::abs(rec.poses[k][v] - rec.poses[0][v])));
    }
  }
  EXPECT_GT(moved, 0.01);

  // speed: ticks of 40 ms each from t = 0.5 s, at 0.5x, 1x and 5x (20, 20, 10 ticks: within the 3 s recorded)
  for (const double speed : {0.5, 1.0, 5.0}) {
    chromium.Evaluate("(function () { var s = document.getElementById('speed'); s.value = '" +
                      (speed == 0.5   ? std::string("0.5")
                       : speed == 1.0 ? std::string("1")
                                      : std::string("5")) +
                      "'; s.dispatchEvent(new Event('change')); })()");
    const int ticks = speed == 5.0 ? 10 : 20;
    seek(0.5);
    const double t0 = chromium.Evaluate("vlabView.time").get<double>();
    double t = t0;
    for (int i = 0; i < ticks; ++i) t = chromium.Evaluate("vlabView.tick(40)").get<double>();
    const double expected = 0.5 + speed * ticks * 0.040;
    EXPECT_LE(t, expected + 1e-9) << "speed " << speed;
    EXPECT_GT(t, expected - 1 / kPoseRateHz - 1e-9) << "speed " << speed;
    // and what is shown then is that recorded frame, pose for pose
    std::size_t k = 0;
    while (k + 1 < n && rec.times[k] < t) ++k;
    ASSERT_EQ(rec.times[k], t) << "speed " << speed << ": t " << t << " is not a recorded frame's time";
    const nlohmann::json pose = chromium.Evaluate("vlabView.pose(" + std::to_string(bodies - 1) + ")");
    for (int v = 0; v < 7; ++v) {
      EXPECT_EQ(pose[v].get<double>(), static_cast<double>(rec.poses[k][7 * (bodies - 1) + v])) << "speed " << speed;
    }
    const double rate = (t - t0) / (ticks * 0.040);
    std::printf("speed %.1fx: %d ticks of 40 ms moved the replay from %.4f to %.4f s: %.3fx\n", speed, ticks, t0, t,
                rate);
  }

  // the plot: log.csv's time and pa10.q.S1, and its line on the canvas
  const nlohmann::json plots =
      chromium.Evaluate("fetch('plots.bin').then(r => r.arrayBuffer()).then(b => Array.from(new Float64Array(b)))");
  const scene::CsvTable log = scene::ReadCsvTable(dir / "run/log.csv");
  ASSERT_EQ(plots.size(), 2 * log.rows.size());
  const int time_col = log.Column("time"), q_col = log.Column("pa10.q.S1");
  for (std::size_t k = 0; k < log.rows.size(); ++k) {
    ASSERT_EQ(plots[2 * k].get<double>(), log.rows[k][time_col]) << "row " << k;
    ASSERT_EQ(plots[2 * k + 1].get<double>(), log.rows[k][q_col]) << "row " << k;
  }
  seek(rec.times[n - 1]);
  TwoFrames(chromium);
  EXPECT_GT(ColourPixels(chromium, "plot", 0xff, 0x6b, 0x6b), 50) << "the first signal's line (#ff6b6b)";
  page.view.Stop();
}

// a key press as Chromium's input pipeline delivers a user's (keydown, keypress, keyup)
void PressSpace(testing::Chromium& chromium) {
  for (const char* type : {"keyDown", "keyUp"}) {
    nlohmann::json key = {
        {"type", type}, {"key", " "}, {"code", "Space"}, {"windowsVirtualKeyCode", 32}, {"nativeVirtualKeyCode", 32}};
    if (std::string(type) == "keyDown") key["text"] = " ";
    chromium.Call("Input.dispatchKeyEvent", key);
  }
}

TEST(ViewReplayBrowserTest, PausedPlotFollowsTheSliderAndSpaceTogglesAfterTheButton) {
  TempDir dir;
  testing::WriteFile(dir / "replay.yaml", Scenario(false));
  const testing::ProcessResult run =
      testing::RunVlab("run " + (dir / "replay.yaml") + " --out " + (dir / "run") + " -q");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // the address it prints: IPv6 in brackets; beyond loopback, a warning that anyone can watch
  for (const std::string bind : {"::1", "127.0.0.1", "0.0.0.0"}) {
    const testing::ProcessResult v =
        testing::RunVlab("view --replay " + (dir / "run") + " --bind " + bind + " --http 0 --duration 0.1 -q");
    EXPECT_EQ(v.exit_code, 0) << v.err;
    EXPECT_NE(v.out.find(bind == "::1" ? "http://[::1]:" : "http://" + bind + ":"), std::string::npos) << v.out;
    EXPECT_EQ(v.err.find("beyond loopback: anyone who can reach port") != std::string::npos, bind == "0.0.0.0")
        << bind << ": " << v.err;
  }
  ReplayPage page(dir);
  ASSERT_GT(page.http_port, 0) << page.view.start_line();
  testing::Chromium& chromium = page.chromium;
  page.Load();
  auto paused = [&] { return chromium.Evaluate("vlabView.paused").get<bool>(); };

  // a mouse click on the pause button (it takes the focus, as a user's click does)
  const nlohmann::json at = nlohmann::json::parse(
      chromium
          .Evaluate("(function () { var r = document.getElementById('pause').getBoundingClientRect();"
                    " return JSON.stringify({x: r.left + r.width / 2, y: r.top + r.height / 2}); })()")
          .get<std::string>());
  for (const char* type : {"mousePressed", "mouseReleased"}) {
    chromium.Call("Input.dispatchMouseEvent",
                  {{"type", type}, {"x", at["x"]}, {"y", at["y"]}, {"button", "left"}, {"clickCount", 1}});
  }
  ASSERT_TRUE(paused()) << "the click paused";
  PressSpace(chromium);
  EXPECT_FALSE(paused()) << "Space after the click resumes";
  PressSpace(chromium);
  EXPECT_TRUE(paused()) << "and pauses again";
  chromium.Evaluate("document.getElementById('pause').focus()");  // keyboard users reach the button by Tab
  PressSpace(chromium);
  EXPECT_FALSE(paused()) << "Space with the button focused resumes, once";
  PressSpace(chromium);
  ASSERT_TRUE(paused());

  // paused: each slider position moves the plot's window to end there, as it moves the arm and the clock
  for (const double t : {1.0, 2.5, 0.4}) {
    chromium.Evaluate("(function () { var s = document.getElementById('slider'); s.value = '" + Exact(t) +
                      "'; s.dispatchEvent(new Event('input')); })()");
    TwoFrames(chromium);
    const nlohmann::json shown = nlohmann::json::parse(
        chromium.Evaluate("JSON.stringify({end: vlabView.plotEnd, replay: vlabView.replayTime})").get<std::string>());
    EXPECT_EQ(shown["replay"].get<double>(), t);
    ASSERT_TRUE(shown["end"].is_number()) << shown.dump();
    EXPECT_EQ(shown["end"].get<double>(), t) << "the plot did not follow the slider while paused";
  }
  EXPECT_TRUE(paused());
  page.view.Stop();
}

TEST(ViewReplayBrowserTest, LivePanelsShowTheCameraAndThePlots) {
  TempDir dir;
  testing::WriteFile(dir / "served.yaml", Scenario(true));
  TestProcess serve({VLAB_BINARY_DIR "/vlab", "serve", dir / "served.yaml", "--port", "scene=0", "--port", "webcam=0",
                     "--out", dir / "run", "-q"});
  auto address = [&](const std::string& label) {
    return "127.0.0.1:" + std::to_string(PortOf(serve.start_line(), label));
  };
  TestProcess view({VLAB_BINARY_DIR "/vlab", "view", "--scene", address("scene (scene)"), "--camera",
                    address("webcam (camera)"), "--plot", "pa10.q.S1,pa10.q.E1", "--http", "0", "-q"});
  const int http_port = PortOf(view.start_line(), "http://127.0.0.1");
  ASSERT_GT(http_port, 0) << view.start_line() << serve.start_line();
  testing::Chromium chromium(dir / "profile", kWidth, kHeight);
  chromium.Call("Page.enable");
  chromium.Call("Page.navigate", {{"url", "http://127.0.0.1:" + std::to_string(http_port) + "/"}});
  const nlohmann::json s = WaitFor(chromium,
                                   "window.vlabView && vlabView.cameraFrames >= 3 && vlabView.plotSamples >= 10"
                                   " && vlabView.plotDrawn > 0");
  chromium.Evaluate("vlabView.paused = true");
  TwoFrames(chromium);
  // the picture: the camera's size, and not one flat colour (the scene, drawn)
  const nlohmann::json image = nlohmann::json::parse(
      chromium
          .Evaluate(
              "(function () { var img = document.getElementById('camera'), c = document.createElement('canvas');"
              " c.width = img.naturalWidth; c.height = img.naturalHeight; var g = c.getContext('2d');"
              " g.drawImage(img, 0, 0); var d = g.getImageData(0, 0, c.width, c.height).data, lo = 255, hi = 0;"
              " for (var i = 0; i < d.length; i += 4) { lo = Math.min(lo, d[i + 1]); hi = Math.max(hi, d[i + 1]); }"
              " var r = img.getBoundingClientRect();"
              " return JSON.stringify({w: img.naturalWidth, h: img.naturalHeight, lo: lo, hi: hi,"
              " shown: r.width * r.height}); })()")
          .get<std::string>());
  EXPECT_EQ(image["w"], 160) << image.dump();
  EXPECT_EQ(image["h"], 120) << image.dump();
  EXPECT_GT(image["hi"].get<int>() - image["lo"].get<int>(), 50) << "a blank picture: " << image.dump();
  EXPECT_GT(image["shown"].get<double>(), 1000.0) << "the panel is not on the page: " << image.dump();
  EXPECT_GT(ColourPixels(chromium, "plot", 0xff, 0x6b, 0x6b), 50) << "pa10.q.S1's line (#ff6b6b)";
  EXPECT_GT(ColourPixels(chromium, "plot", 0x4d, 0xab, 0xf7), 50) << "pa10.q.E1's line (#4dabf7)";
  if (const char* out = std::getenv("VLAB_VIEW_PANELS_SCREENSHOT"); out && *out) {
    std::ofstream(out, std::ios::binary) << chromium.Screenshot();  // docs/view_panels.png is one
  }
  std::printf("live panels: %d camera pictures (frame %.0f), %d plot samples\n", s["cameraFrames"].get<int>(),
              s["cameraId"].get<double>(), s["plotSamples"].get<int>());
  view.Stop();

  // a view with room for two WebSockets: the page's third (poses, camera, plot) is refused, and the page says why
  TestProcess full({VLAB_BINARY_DIR "/vlab", "view", "--scene", address("scene (scene)"), "--camera",
                    address("webcam (camera)"), "--plot", "pa10.q.S1", "--http", "0", "--max-connections", "2", "-q"});
  const int full_port = PortOf(full.start_line(), "http://127.0.0.1");
  ASSERT_GT(full_port, 0) << full.start_line();
  chromium.Call("Page.navigate", {{"url", "http://127.0.0.1:" + std::to_string(full_port) + "/"}});
  WaitFor(chromium,
          "window.vlabView && vlabView.refused && document.getElementById('status').textContent.indexOf("
          "'server full: 2 sessions open') >= 0");
  std::printf("refused: the page shows '%s'\n",
              chromium.Evaluate("document.getElementById('status').textContent").get<std::string>().c_str());
  full.Stop();
  serve.Stop();  // 20 s are room for a slow start: the test is done
}

}  // namespace
}  // namespace vlab
