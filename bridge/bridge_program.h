// What every controller program beside the lab needs around its loop, in one place:
// HOST:PORT arguments, the stop flag that SIGTERM and SIGINT set (bridge_signals.h; vlab run
// ends an external controller with SIGTERM, docs/scenarios.md), reads in short slices so that
// the flag is seen soon, and a main() that turns a bridge error into exit status 2.
// Header only: a program links vlab_bridge and nothing else.
//
//   int main(int argc, char** argv) {
//     Options o;
//     if (!ParseOptions(argc, argv, &o)) return Usage(argv[0]);
//     return vlab::bridge::program::Main("my_control", [&] { return Run(o); });
//   }
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "bridge/bridge_errors.h"
#include "bridge/bridge_signals.h"

namespace vlab::bridge::program {

/// A device's address as given on a command line.
struct Address {
  std::string host;
  int port = 0;
};

/// Parses HOST:PORT ([V6]:PORT too, brackets dropped); false unless the host is not
/// empty and the port is 1 to 65535.
inline bool ParseAddress(const std::string& text, Address* a) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos) return false;
  a->host = text.substr(0, colon);
  if (a->host.size() > 2 && a->host.front() == '[' && a->host.back() == ']')
    a->host = a->host.substr(1, a->host.size() - 2);
  char* end = nullptr;
  const long port = std::strtol(text.c_str() + colon + 1, &end, 10);
  a->port = end && *end == '\0' && port > 0 && port < 65536 ? static_cast<int>(port) : 0;
  return !a->host.empty() && a->port > 0;
}

/// True once a stop signal came (the one stop handler, bridge_signals.h).
inline bool Stopped() { return StopRequested(); }

/// Reads block this long at a time, so a stop signal is seen within it.
inline constexpr double kPoll_s = 0.05;

/// The state of period `seq` or a later one (`c.Read` in slices); false when the device
/// was silent for `timeout_s` (any state, even an older one, restarts the wait) or a
/// stop signal came.
template <typename Client, typename State>
bool ReadUntil(Client& c, std::int64_t seq, double timeout_s, State* s) {
  for (double waited = 0; !Stopped() && waited < timeout_s; waited += kPoll_s) {
    try {
      *s = c.Read(kPoll_s);
      if (s->seq >= seq) return true;
      waited = 0;
    } catch (const TimeoutError&) {
    }
  }
  return false;
}

/// The next state (`c.ReadLatest`: in lockstep the next one, in realtime the newest);
/// false when none came within `timeout_s` or a stop signal came.
template <typename Client, typename State>
bool ReadNext(Client& c, double timeout_s, State* s) {
  for (double waited = 0; !Stopped() && waited < timeout_s; waited += kPoll_s) {
    try {
      c.ReadLatest(kPoll_s, s);
      return true;
    } catch (const TimeoutError&) {
    }
  }
  return false;
}

/// Installs the stop handler and returns `run()`; an exception it throws is printed
/// as "NAME: what" with exit status 2, or ends quietly with 0 when a stop signal came
/// first (the lab went away because the run ended).
template <typename Run>
int Main(const char* name, Run run) {
  InstallStopSignals();
  try {
    return run();
  } catch (const std::exception& e) {
    if (Stopped()) return 0;
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 2;
  }
}

}  // namespace vlab::bridge::program
