// Image outputs allocate per frame, never per period: between two calls of
// the run's observer (one control period: image outputs, publishing, physics,
// log) the process makes no heap allocation unless a frame was due.
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdlib>

#include <gtest/gtest.h>

#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

// Counts heap allocations (operator new ends in malloc) process-wide.
namespace {
std::atomic<long> g_allocations{0};
}
extern "C" void* __libc_malloc(size_t size);
extern "C" void* malloc(size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}

namespace vlab::lab {
namespace {

using vlab::testing::TempDir;

TEST(RenderAllocTest, ImageOutputsDoNotAllocateBetweenFrames) {
  TempDir dir;
  vlab::testing::WriteFile(dir / "images.yaml",
                           "name: images\nscene: " VLAB_SOURCE_DIR
                           "/scenes/pa10.xml\nduration: 0.3\n"
                           "devices:\n  - {name: pa10, kind: arm, joints: [S1, S2, S3, E1, E2, W1, W2]}\n"
                           "outputs:\n  images:\n"
                           "    - {camera: overview, every: 0.1, width: 160, height: 120, depth: true,\n"
                           "       segmentation: true, video: overview.mp4, profile: fast}\n");
  Scenario scenario = LoadScenario(dir / "images.yaml");
  std::unique_ptr<Lab> lab = Lab::Create(scenario);
  // the observer runs before the image outputs at each period end: the window from one call
  // to the next holds the image outputs of the first call's time
  long last = 0, with_frame = 0, without_frame = 0, allocating = 0, frame_allocating = 0;
  double last_t = -1;
  RunOptions options;
  options.out_dir = dir / "run";
  options.observe = [&](double t, const mjModel*, mjData*) {
    const long now = g_allocations.load();
    if (last_t >= 0) {
      const double frames = last_t / 0.1;
      const bool frame = std::abs(frames - std::round(frames)) < 1e-6;
      (frame ? with_frame : without_frame) += 1;
      if (!frame && now != last) ++allocating;
      if (frame && now != last) ++frame_allocating;
    }
    last_t = t;
    last = g_allocations.load();
  };
  const RunResult r = lab->Run(options);
  ASSERT_EQ(r.exit_code, 0) << r.failure;
  EXPECT_EQ(with_frame, 3);  // t = 0, 0.1, 0.2 (0.3: the last call, no window after it)
  EXPECT_EQ(without_frame, 147);
  EXPECT_EQ(frame_allocating, 3) << "the counter should see a frame's allocations";
  EXPECT_EQ(allocating, 0) << "periods without a frame allocated";
}

}  // namespace
}  // namespace vlab::lab
