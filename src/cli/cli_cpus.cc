#include "cli/cli_cpus.h"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/core_realtime.h"

namespace vlab::cli {

std::vector<int> StartCpuHogs(int n, bool paused) {
  std::vector<int> pids;
  for (int i = 0; i < n; ++i) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      // normal priority whatever the parent runs at (a realtime parent's children inherit it)
      SetThreadNormal();
      volatile unsigned long spin = 0;
      for (;;) spin = spin + 1;
    }
    if (pid <= 0) continue;
    if (paused) ::kill(pid, SIGSTOP);  // (a SIGCONT sent after it cannot overtake it)
    pids.push_back(pid);
  }
  return pids;
}

void ResumeCpuHogs(const std::vector<int>& pids) {
  for (int pid : pids) ::kill(pid, SIGCONT);
}

void StopCpuHogs(const std::vector<int>& pids) {
  for (int pid : pids) ::kill(pid, SIGKILL);
  for (int pid : pids) ::waitpid(pid, nullptr, 0);
}

}  // namespace vlab::cli
