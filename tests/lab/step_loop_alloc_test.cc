// The period path allocates nothing (STYLE.md: "No allocation in the step
// loop"): a heap allocation on a realtime control thread can take the
// allocator's lock, call into the kernel for memory and fault on it, and each
// of those is a stall the lab causes. This binary counts the allocations of
// the thread that runs the lab (malloc, calloc, realloc, aligned forms and
// every operator new go through the counters below) and runs shipped scenarios
// in process with their log written; between two observe calls (one control
// period: commands, physics, sensors, log row, checks, publish) the count must
// not move once the run has started (a warm-up of a few periods lets lazily
// sized buffers take their size).
#include <dlfcn.h>
#include <malloc.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <future>
#include <new>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_client.h"
#include "bridge/bridge_errors.h"
#include "lab/run/lab_bridge.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "test_util.h"

namespace {

// allocations made by the thread while counting is on
thread_local bool t_counting = false;
thread_local std::uint64_t t_allocations = 0;

void Count() {
  if (t_counting) ++t_allocations;
}

}  // namespace

// glibc's own entry points, which these wrappers call after counting
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  Count();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  Count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  Count();
  return __libc_realloc(p, n);
}
void* memalign(std::size_t alignment, std::size_t n) {
  Count();
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) {
  Count();
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** p, std::size_t alignment, std::size_t n) {
  Count();
  *p = __libc_memalign(alignment, n);
  return *p ? 0 : ENOMEM;
}
void free(void* p) { __libc_free(p); }
}

namespace vlab::lab {
namespace {

// the allocations of the thread that runs the lab, read at each observe call (one a period)
class PeriodCounts {
 public:
  PeriodCounts() { counts_.reserve(100000); }
  /// An observe callback for RunOptions.
  std::function<void(double, const mjModel*, mjData*)> Observer() {
    return [this](double, const mjModel*, mjData*) {
      t_counting = false;
      counts_.push_back(t_allocations);
      t_counting = true;
    };
  }
  /// Runs `run` on this thread with the counters on.
  template <typename F>
  void Count(F run) {
    t_allocations = 0;
    t_counting = true;
    run();
    t_counting = false;
  }
  /// No period after the first kWarmUp (buffers may still take their size) allocated.
  void ExpectNone(const std::string& what, std::size_t min_periods) const {
    constexpr std::size_t kWarmUp = 5;
    ASSERT_GT(counts_.size(), min_periods) << what;
    ASSERT_GT(counts_.front(), 0u) << what << ": the counters see the run's thread (its set-up allocates)";
    for (std::size_t k = kWarmUp + 1; k < counts_.size(); ++k) {
      ASSERT_EQ(counts_[k] - counts_[k - 1], 0u)
          << what << ": period " << k << " allocated " << counts_[k] - counts_[k - 1] << " times";
    }
  }

 private:
  std::vector<std::uint64_t> counts_;
};

struct Case {
  const char* scenario;  // under the source tree
  double duration_s;     // enough periods to cover the controller's phases, short for the suite
  bool outputs;          // with the log and the other files written
};

// the case as gtest (and ctest's test name) shows it
void PrintTo(const Case& c, std::ostream* os) { *os << c.scenario << (c.outputs ? "+outputs" : ""); }

class PeriodAllocation : public ::testing::TestWithParam<Case> {};

TEST_P(PeriodAllocation, NoPeriodAllocatesAfterTheFirstFew) {
  const Case c = GetParam();
  Scenario scenario = LoadScenario(std::string(VLAB_SOURCE_DIR) + "/" + c.scenario);
  scenario.duration_s = c.duration_s;
  std::unique_ptr<Lab> lab = Lab::Create(scenario);
  vlab::testing::TempDir dir;
  RunOptions options;
  if (c.outputs) options.out_dir = dir.path() + "/out";
  options.clock = ClockMode::kFast;
  PeriodCounts counts;
  options.observe = counts.Observer();
  RunResult result;
  counts.Count([&] { result = lab->Run(options); });
  EXPECT_TRUE(result.failure.find("diverged") == std::string::npos) << result.failure;
  counts.ExpectNone(c.scenario, 15);
}

// the served path too: pa10_serve with a controller on another thread (its
// allocations are its own), lockstep and realtime (the realtime clock's stall
// probe, the bridge's receive, refuse and publish paths)
class ServedPeriodAllocation : public ::testing::TestWithParam<ClockMode> {};

TEST_P(ServedPeriodAllocation, NoPeriodAllocatesAfterTheFirstFew) {
  Scenario scenario = LoadScenario(std::string(VLAB_SOURCE_DIR) + "/scenes/pa10_serve.yaml");
  scenario.duration_s = 0.5;  // 250 periods at 500 Hz
  std::unique_ptr<Lab> lab = Lab::Create(scenario);
  vlab::testing::TempDir dir;
  BridgeOptions serve;
  serve.ports = {{"pa10", 0}, {"jr3", 0}, {"sim", 0}};
  std::promise<int> arm_port;
  RunOptions options;
  options.out_dir = dir.path() + "/out";
  options.clock = GetParam();
  options.serve = &serve;
  options.on_serving = [&](const std::vector<ServedDevice>& devices) {
    for (const ServedDevice& d : devices) {
      if (d.name == "pa10") arm_port.set_value(d.port);
    }
  };
  PeriodCounts counts;
  options.observe = counts.Observer();
  std::future<int> port = arm_port.get_future();
  RunResult result;
  std::thread run([&] { counts.Count([&] { result = lab->Run(options); }); });
  // the controller: answers every state with the position it reads, until the lab stops publishing
  auto arm = bridge::Arm::Connect("127.0.0.1", port.get(), 5.0);
  bridge::Arm::State state;
  try {
    for (;;) {
      arm.Read(1.0, &state);
      arm.Write(bridge::ArmMode::kPosition, state.q, state.seq);
    }
  } catch (const bridge::TimeoutError&) {
    // the run ended
  }
  run.join();
  ASSERT_EQ(result.exit_code, 0) << result.failure;
  counts.ExpectNone(ClockModeName(GetParam()), 200);
}

INSTANTIATE_TEST_SUITE_P(Clocks, ServedPeriodAllocation, ::testing::Values(ClockMode::kLockstep, ClockMode::kRealtime),
                         [](const ::testing::TestParamInfo<ClockMode>& info) { return ClockModeName(info.param); });

INSTANTIATE_TEST_SUITE_P(ShippedScenarios, PeriodAllocation,
                         ::testing::Values(Case{"scenes/pa10_reach.yaml", 1.0, true},
                                           Case{"scenes/pa10_reach.yaml", 1.0, false},
                                           Case{"scenes/pa10_joint_pd.yaml", 1.0, true},
                                           Case{"scenes/pa10_cubes.yaml", 0.5, true},
                                           Case{"scenes/pa10_view.yaml", 1.0, true}),
                         [](const ::testing::TestParamInfo<Case>& info) { return std::to_string(info.index); });

}  // namespace
}  // namespace vlab::lab
