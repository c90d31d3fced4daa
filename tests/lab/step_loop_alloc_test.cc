// The step loop allocates nothing: a run of the default scenario (arm servo,
// JR3, task-space controller, log, checks) makes as many heap allocations over
// 2 s as over 1 s, so every allocation belongs to set-up, none to a period.
// Also checked for the joint-PD scenario.
#include <atomic>
#include <cstddef>
#include <cstdlib>

#include <gtest/gtest.h>

#include "lab/lab_runner.h"
#include "lab/lab_scenario.h"
#include "test_util.h"

// Counts heap allocations (operator new and Eigen end in malloc) process-wide.
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

// (a shortened run may fail checks that look at its end: only the count matters)
long AllocationsOfRun(const std::string& scenario_file, double duration_s, const std::string& out_dir) {
  Scenario scenario = LoadScenario(scenario_file);
  scenario.duration_s = duration_s;
  std::unique_ptr<Lab> lab = Lab::Create(scenario);
  RunOptions options;
  options.out_dir = out_dir;
  const long before = g_allocations.load();
  const RunResult r = lab->Run(options);
  const long count = g_allocations.load() - before;
  EXPECT_TRUE(r.failure.find("diverged") == std::string::npos) << r.failure;
  EXPECT_EQ(r.periods, std::lround(duration_s / scenario.control_period_s));
  return count;
}

TEST(StepLoopAllocTest, CounterSeesAllocations) {
  const long before = g_allocations.load();
  void* p = std::malloc(64);
  std::free(p);
  EXPECT_GT(g_allocations.load(), before);
}

TEST(StepLoopAllocTest, TaskSpaceScenarioLoopDoesNotAllocate) {
  const std::string file = VLAB_SOURCE_DIR "/scenes/pa10_reach.yaml";
  EXPECT_EQ(AllocationsOfRun(file, 2.0, ""), AllocationsOfRun(file, 1.0, "")) << "without outputs";
  vlab::testing::TempDir tmp;
  EXPECT_EQ(AllocationsOfRun(file, 2.0, tmp / "a"), AllocationsOfRun(file, 1.0, tmp / "b")) << "with outputs";
}

TEST(StepLoopAllocTest, JointPdScenarioLoopDoesNotAllocate) {
  const std::string file = VLAB_SOURCE_DIR "/scenes/pa10_joint_pd.yaml";
  EXPECT_EQ(AllocationsOfRun(file, 2.0, ""), AllocationsOfRun(file, 1.0, ""));
}

}  // namespace
}  // namespace vlab::lab
