// SIGINT and SIGTERM as a stop request for a server program's loop (vlab-kinsim,
// vlab-yoyosim): the handler only sets a flag the loop reads.
#pragma once

#include <signal.h>

#include <csignal>

namespace vlab {

/// Set to 1 by SIGINT or SIGTERM once InstallStopSignals() ran.
inline volatile std::sig_atomic_t g_stop_requested = 0;

/// SIGINT and SIGTERM set g_stop_requested. Without SA_RESTART: the signal also
/// interrupts a blocking wait (a period's sleep, a receive), so the loop ends at once.
inline void InstallStopSignals() {
  struct sigaction action {};
  action.sa_handler = [](int) { g_stop_requested = 1; };
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

}  // namespace vlab
