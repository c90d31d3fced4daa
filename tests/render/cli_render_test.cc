// The real vlab binary: `vlab render` writes N readable PNGs of the right size
// and an MP4 of N frames; bad input is one line and exit 2 with nothing
// written; image outputs of `vlab run` (tests/data/render_outputs.yaml).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "render/image_codec.h"
#include "test_util.h"

namespace vlab::testing {
namespace {

namespace fs = std::filesystem;

int VideoFrames(const std::string& path, int width, int height) {
  cv::VideoCapture capture(path);
  if (!capture.isOpened()) return -1;
  int frames = 0;
  cv::Mat frame;
  while (capture.read(frame)) {
    if (frame.cols != width || frame.rows != height) return -2;
    ++frames;
  }
  return frames;
}

// a PNG file as it is stored, in a cv::Mat (which owns a copy)
cv::Mat ReadPng(const std::string& path) {
  render::Image image = render::ReadImageFile(path, render::DecodeMode::kUnchanged);
  const int type = CV_MAKETYPE(image.depth == 16 ? CV_16U : CV_8U, image.channels);
  return cv::Mat(image.height, image.width, type, image.bytes.data()).clone();
}

void ExpectPng(const std::string& path, int type, int width, int height) {
  const cv::Mat img = ReadPng(path);
  ASSERT_FALSE(img.empty()) << path;
  EXPECT_EQ(img.type(), type) << path;
  EXPECT_EQ(img.cols, width) << path;
  EXPECT_EQ(img.rows, height) << path;
}

TEST(CliRender, WritesFramesAndVideo) {
  TempDir dir;
  const ProcessResult r = RunVlab(
      "render scenes/pa10_reach --camera overview --frames 4 --every 0.05 --width 320 --height 240 "
      "--profile fast --depth --segmentation -q --out " +
      (dir / "frames") + " --video " + (dir / "v.mp4"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("4 frames 320x240 of camera 'overview' (fast)"), std::string::npos) << r.out;
  EXPECT_EQ(r.err, "");  // quiet: no renderer line
  for (int n = 0; n < 4; ++n) {
    char name[32];
    std::snprintf(name, sizeof(name), "_%06d.png", n);
    ExpectPng(dir / ("frames/rgb" + std::string(name)), CV_8UC3, 320, 240);
    ExpectPng(dir / ("frames/depth" + std::string(name)), CV_16UC1, 320, 240);
    ExpectPng(dir / ("frames/seg" + std::string(name)), CV_16UC1, 320, 240);
  }
  EXPECT_EQ(Entries(dir / "frames").size(), 4u * 3 + 3);  // + frames.csv, render.json, .vlab-output
  EXPECT_EQ(Lines(ReadFile(dir / "frames/frames.csv")),
            (std::vector<std::string>{"frame,time", "0,0", "1,0.05", "2,0.1", "3,0.15"}));
  const auto meta = nlohmann::json::parse(ReadFile(dir / "frames/render.json"));
  EXPECT_EQ(meta["frames"], 4);
  EXPECT_EQ(meta["camera"], "overview");
  EXPECT_NE(meta["gl_renderer"].get<std::string>(), "");
  EXPECT_EQ(VideoFrames(dir / "v.mp4", 320, 240), 4);
  // the depth image holds millimetres: the scene is metres away, the sky 0
  const cv::Mat mm = ReadPng(dir / "frames/depth_000000.png");
  double lo = 0, hi = 0;
  cv::minMaxLoc(mm, &lo, &hi);
  EXPECT_EQ(lo, 0);
  EXPECT_GT(hi, 1000);
}

// SIGINT: the frames rendered before it are kept, whole, with frames.csv, render.json saying
// so and the video closed; exit 1
TEST(CliRender, InterruptKeepsTheFramesRendered) {
  TempDir dir;
  // 1000 s at a frame per period: far more frames than the two seconds before the signal render
  WriteFile(dir / "s.yaml", std::string("scene: ") + VLAB_SOURCE_DIR +
                                "/scenes/pa10.xml\nduration: 1000\ncontrol_period: 0.002\ndevices:\n"
                                "  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2]}\n");
  const ProcessResult r = RunVlab("render " + (dir / "s.yaml") +
                                      " --camera overview --every 0.002 --width 64 "
                                      "--height 48 --profile fast -q --out " +
                                      (dir / "frames") + " --video " + (dir / "frames/v.mp4"),
                                  2, "INT");
  ASSERT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("vlab: interrupted by SIGINT at t = "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frames rendered before it are kept"), std::string::npos) << r.err;
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"s.yaml", "frames"})) << "no staging folder";
  const auto meta = nlohmann::json::parse(ReadFile(dir / "frames/render.json"));
  EXPECT_NE(meta.value("interrupted", "").find("interrupted by SIGINT"), std::string::npos) << meta.dump();
  const int frames = meta["frames"];
  ASSERT_GT(frames, 0);
  const std::vector<std::string> times = Lines(ReadFile(dir / "frames/frames.csv"));
  EXPECT_EQ(times.size(), static_cast<std::size_t>(frames) + 1);
  // every frame is there and readable, and the video holds them all
  std::size_t pngs = 0;
  for (const std::string& name : Entries(dir / "frames")) pngs += name.rfind("rgb_", 0) == 0 ? 1 : 0;
  EXPECT_EQ(pngs, static_cast<std::size_t>(frames));
  char last[32];
  std::snprintf(last, sizeof(last), "rgb_%06d.png", frames - 1);
  ExpectPng(dir / ("frames/" + std::string(last)), CV_8UC3, 64, 48);
  EXPECT_EQ(VideoFrames(dir / "frames/v.mp4", 64, 48), frames);
}

TEST(CliRender, ReplacesTheOutputFolderWhole) {
  TempDir dir;
  const std::string base =
      "render scenes/pa10_reach --camera overview --every 0.02 --width 160 --height 120 "
      "--profile fast -q --out " +
      (dir / "frames");
  ASSERT_EQ(RunVlab(base + " --frames 3").exit_code, 0);
  ASSERT_EQ(RunVlab(base + " --frames 2").exit_code, 0);
  EXPECT_EQ(Entries(dir / "frames"),
            (std::set<std::string>{"rgb_000000.png", "rgb_000001.png", "frames.csv", "render.json", ".vlab-output"}));
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"frames"}));  // no staging folder left
}

// a video named inside the output folder moves into place with the frames
TEST(CliRender, VideoInsideTheOutputFolderIsKept) {
  TempDir dir;
  const ProcessResult r = RunVlab(
      "render scenes/pa10_reach --camera overview --frames 3 --width 160 --height 120 --profile fast -q --out " +
      (dir / "frames") + " --video " + (dir / "frames/clip.mp4"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(VideoFrames(dir / "frames/clip.mp4", 160, 120), 3);
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"frames"}));  // nothing staged left beside it
}

TEST(CliRender, RendersWhatFitsTheScenario) {
  TempDir dir;
  const ProcessResult r = RunVlab(
      "render scenes/pa10_reach --camera overview --every 5 --frames 5 --width 160 "
      "--height 120 --profile fast --out " +
      (dir / "frames"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("3 of the 5 frames asked for fit"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("vlab: render: "), std::string::npos) << "the GL renderer is logged";
  EXPECT_EQ(Lines(ReadFile(dir / "frames/frames.csv")), (std::vector<std::string>{"frame,time", "0,0", "1,5", "2,10"}));
}

// a frame that cannot be written (here: larger than the file size limit, SIGXFSZ ignored, so
// the write fails with EFBIG as on a full disk) ends the rendering like SIGINT: an error naming
// the file, the frames written whole before it kept (none here), render.json saying so, exit 1
TEST(CliRender, AFrameThatCannotBeWrittenIsReportedAndNothingHalfWrittenIsLeft) {
  TempDir dir;
  const std::string cmd = "cd '" VLAB_SOURCE_DIR "' && trap '' XFSZ && ulimit -f 8 && '" VLAB_BINARY_DIR
                          "/vlab' render scenes/pa10_reach --camera overview --frames 3 --width 160 --height 120 "
                          "--profile fast -q --out '" +
                          (dir / "frames") + "' >'" + (dir / "out") + "' 2>'" + (dir / "err") + "' </dev/null";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  const std::string err = ReadFile(dir / "err");
  EXPECT_EQ(WEXITSTATUS(status), 1) << err;
  EXPECT_NE(err.find("rgb_000000.png': write failed: "), std::string::npos) << err;
  EXPECT_NE(err.find("the 0 frames written before it are kept"), std::string::npos) << err;
  EXPECT_EQ(Lines(err).size(), 1u) << err;
  // the folder is in place whole, without the frame that failed, and no staging folder is left
  EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"frames", "out", "err"}));
  EXPECT_EQ(Entries(dir / "frames"), (std::set<std::string>{"frames.csv", "render.json", ".vlab-output"}));
  EXPECT_EQ(Lines(ReadFile(dir / "frames/frames.csv")), (std::vector<std::string>{"frame,time"}));
  const auto meta = nlohmann::json::parse(ReadFile(dir / "frames/render.json"));
  EXPECT_EQ(meta["frames"], 0);
  EXPECT_NE(meta.value("failed", "").find("rgb_000000.png"), std::string::npos) << meta.dump();
}

struct BadInput {
  std::string args;
  std::string message;
};

TEST(CliRender, BadInputIsOneLineAndExitTwo) {
  const std::vector<BadInput> cases = {
      {"scenes/pa10_reach --camera nope", "no camera 'nope' in the scene (cameras: overview)"},
      {"scenes/pa10_reach --camera overview --width 2000", "offwidth"},
      {"scenes/pa10_reach --camera overview --height 1000", "pa10.xml"},
      {"scenes/pa10_reach --camera overview --fps 10 --every 0.1", "--fps and --every"},
      {"scenes/pa10_reach --camera overview --every 0", "--every must be > 0"},
      {"scenes/pa10_reach --camera overview --every -1", "--every must be > 0"},
      {"scenes/pa10_reach --camera overview --fps 0", "--fps must be > 0"},
      {"scenes/pa10_reach --camera overview --frames 0", "--frames must be >= 1"},
      {"scenes/pa10_reach --camera overview --width 0", "--width must be >= 1"},
      {"scenes/pa10_reach --camera overview --every 0.001", "shorter than the control period"},
      {"scenes/pa10_reach --camera overview --profile best", "unknown render profile 'best'"},
      {"scenes/pa10_reach --camera overview --video clip.avi", "must end in .mp4"},
      {"scenes/no_such_scenario --camera overview", "no_such_scenario"},
      {"scenes/pa10_reach", "--camera"},
  };
  for (const BadInput& c : cases) {
    TempDir dir;
    const ProcessResult r = RunVlab("render " + c.args + " --out " + (dir / "frames"));
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(Lines(r.err).size(), 1u) << c.args << "\n" << r.err;
    EXPECT_TRUE(Entries(dir.path()).empty()) << c.args << ": something was written";
  }
}

TEST(CliRun, ImageOutputsAreWritten) {
  TempDir dir;
  const ProcessResult r = RunVlab("run tests/data/render_outputs.yaml -q --out " + (dir / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::set<std::string> top = Entries(dir / "run");
  EXPECT_EQ(top, (std::set<std::string>{"log.csv", "summary.json", "overview", "overview.mp4", ".vlab-output"}));
  const std::set<std::string> frames = Entries(dir / "run/overview");
  EXPECT_EQ(frames.size(), 6u * 3 + 1);  // rgb, depth, seg per frame + frames.csv
  for (int n = 0; n < 6; ++n) {
    char name[32];
    std::snprintf(name, sizeof(name), "rgb_%06d.png", n);
    ExpectPng(dir / ("run/overview/" + std::string(name)), CV_8UC3, 320, 240);
  }
  EXPECT_EQ(Lines(ReadFile(dir / "run/overview/frames.csv")),
            (std::vector<std::string>{"frame,time", "0,0", "1,0.1", "2,0.2", "3,0.3", "4,0.4", "5,0.5"}));
  EXPECT_EQ(VideoFrames(dir / "run/overview.mp4", 320, 240), 6);
  const auto summary = nlohmann::json::parse(ReadFile(dir / "run/summary.json"));
  ASSERT_TRUE(summary.contains("images"));
  EXPECT_EQ(summary["images"]["outputs"][0]["frames"], 6);
  EXPECT_NE(summary["images"]["gl_renderer"].get<std::string>(), "");

  // the same scenario without its image outputs: the same log, byte for byte
  std::string text = ReadFile(VLAB_SOURCE_DIR "/tests/data/render_outputs.yaml");
  text = text.substr(0, text.find("  images:"));
  const std::string relative = "scene: ../../scenes/pa10.xml";
  text.replace(text.find(relative), relative.size(), "scene: " VLAB_SOURCE_DIR "/scenes/pa10.xml");
  WriteFile(dir / "plain.yaml", text);
  ASSERT_EQ(RunVlab("run " + (dir / "plain.yaml") + " -q --out " + (dir / "plain")).exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "plain/overview"));
  EXPECT_TRUE(ReadFile(dir / "plain/log.csv") == ReadFile(dir / "run/log.csv")) << "images changed the log";
}

TEST(CliRun, BadImageOutputsAreInputErrorsBeforeAnythingIsWritten) {
  const std::string scene = VLAB_SOURCE_DIR "/scenes/pa10.xml";
  const std::vector<BadInput> cases = {
      {"{camera: nope}", ":9: outputs.images[0].camera: scene '" + scene + "': no camera 'nope'"},
      {"{camera: overview, width: 1600}", ":9: outputs.images[0].width, height: 1600x480 exceeds the offscreen"},
      {"{camera: overview, every: 0.001}", ":9: outputs.images[0].every: 0.001 s is shorter than the control"},
  };
  for (const BadInput& c : cases) {
    TempDir dir;
    WriteFile(dir / "bad.yaml", "name: bad\nscene: " + scene +
                                    "\nduration: 0.1\ncontrol_period: 0.002\n"
                                    "devices:\n  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2]}\n"
                                    "outputs:\n  images:\n    - " +
                                    c.args + "\n");
    const ProcessResult r = RunVlab("run " + (dir / "bad.yaml") + " -q --out " + (dir / "run"));
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(Entries(dir.path()), (std::set<std::string>{"bad.yaml"})) << c.args << ": something was written";
  }
}

}  // namespace
}  // namespace vlab::testing
