// Waiting for an event in a test: poll its condition, with a generous limit against a hang.
#pragma once

#include <chrono>
#include <thread>

namespace vlab::testing {

/// Polls `done` every 2 ms until it holds or `timeout_s` of the wall clock pass; whether it
/// held. The limit guards against a hang: it is no bound on how soon the event comes, so
/// make it generous (a busy machine only makes the event later).
template <typename Done>
bool WaitUntil(Done done, double timeout_s = 20) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));  // polling a condition, with a limit
  }
  return true;
}

}  // namespace vlab::testing
