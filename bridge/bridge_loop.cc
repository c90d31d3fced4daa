#include "bridge/bridge_loop.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string>

namespace vlab::bridge {

namespace {
std::int64_t MonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}
}  // namespace

FixedRateLoop::FixedRateLoop(double rate_hz) : rate_hz_(rate_hz) {
  if (!(rate_hz > 0 && rate_hz <= 1e6)) {
    throw std::invalid_argument("FixedRateLoop: rate " + std::to_string(rate_hz) + " Hz out of range (0, 1e6]");
  }
  period_ns_ = static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
  Reset();
}

void FixedRateLoop::Reset() {
  start_ns_ = MonotonicNs();
  k_ = 0;
}

std::int64_t FixedRateLoop::Deadline(std::int64_t k) const {
  // from k, never accumulated: no drift
  return start_ns_ + static_cast<std::int64_t>(std::llround(static_cast<long double>(k) * 1e9L / rate_hz_));
}

bool FixedRateLoop::Wait() {
  ++iterations_;
  ++k_;
  const std::int64_t now = MonotonicNs();
  const std::int64_t deadline = Deadline(k_);
  if (deadline <= now) {
    // late: skip to the last deadline passed, so the next Wait aims at one ahead
    ++overruns_;
    const auto passed = static_cast<std::int64_t>(static_cast<long double>(now - start_ns_) * rate_hz_ / 1e9L);
    k_ = std::max(k_, passed);
    while (Deadline(k_ + 1) <= now) ++k_;
    return false;
  }
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline / 1000000000);
  ts.tv_nsec = static_cast<long>(deadline % 1000000000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
  return true;
}

}  // namespace vlab::bridge
