#include "lab/lab_clock.h"

#include "lab/lab_errors.h"

namespace vlab::lab {

namespace {

// fast: never waits.
class FastClock final : public Clock {
 public:
  const char* name() const override { return "fast"; }
  void BeginPeriod(std::int64_t, double) override { ++stats_.periods; }
  void EndPeriod(std::int64_t) override {}
  ClockStats stats() const override { return stats_; }

 private:
  ClockStats stats_;
};

}  // namespace

std::unique_ptr<Clock> MakeClock(const std::string& mode, double /*control_period_s*/) {
  if (mode == "fast") return std::make_unique<FastClock>();
  throw InputError("unknown clock '" + mode + "' (known: fast)");
}

}  // namespace vlab::lab
