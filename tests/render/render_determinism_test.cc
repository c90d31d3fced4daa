// Rendering does not change the trajectory: scenes/pa10_reach run with and
// without rendering (RGB, depth, segmentation) at every period end gives
// byte-identical logs.
#include <gtest/gtest.h>

#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "render/renderer.h"
#include "test_util.h"

namespace vlab::render {
namespace {

using vlab::testing::ReadFile;
using vlab::testing::TempDir;

TEST(RenderDeterminism, RenderingEveryPeriodLeavesTheLogIdentical) {
  lab::Scenario scenario = lab::LoadScenario(VLAB_SOURCE_DIR "/scenes/pa10_reach.yaml");
  scenario.duration_s = 0.6;  // 300 periods, the arm moving from t = 0.5 s
  scenario.checks.clear();    // they judge the whole 13 s path
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  TempDir dir;

  lab::RunOptions plain;
  plain.out_dir = dir / "plain";
  ASSERT_EQ(lab->Run(plain).exit_code, 0);
  const std::vector<double> plain_qpos = lab->FinalQpos();

  Renderer::Options options;
  options.width = 160;
  options.height = 120;
  options.profile = Profile::kFast;
  options.log_renderer = false;
  auto renderer = Renderer::Create(lab->model(), options);
  const int cam = CameraId(lab->model(), "overview");
  RgbImage rgb;
  DepthImage depth;
  SegmentationImage seg;
  long frames = 0;
  lab::RunOptions rendering;
  rendering.out_dir = dir / "rendered";
  rendering.observe = [&](double, const mjModel*, mjData* d) {
    renderer->Render(d, cam, &rgb, &depth);
    renderer->RenderSegmentation(d, cam, &seg);
    ++frames;
  };
  const lab::RunResult r = lab->Run(rendering);
  ASSERT_EQ(r.exit_code, 0) << r.failure;
  EXPECT_EQ(frames, r.periods + 1);

  const std::string a = ReadFile(dir / "plain/log.csv"), b = ReadFile(dir / "rendered/log.csv");
  ASSERT_GT(a.size(), 10000u);
  EXPECT_TRUE(a == b) << "log.csv differs when rendering";
  EXPECT_EQ(plain_qpos, lab->FinalQpos());
}

}  // namespace
}  // namespace vlab::render
