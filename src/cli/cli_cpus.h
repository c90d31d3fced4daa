// The CPUs a benchmark runs on: which are allowed and pinning to some of them
// (ThreadCpus, BindThread, CpuListText in core_realtime.h), so that a figure and its
// baseline are measured in the same layout; and a competing load.
#pragma once

#include <vector>

namespace vlab::cli {

/// Starts `n` processes that spin on the CPU at normal priority (a competing
/// load), ended with this process if it dies; StopCpuHogs ends and reaps them.
/// paused: they are stopped (SIGSTOP) until ResumeCpuHogs, so that they are
/// forked before the measured process locks its memory, and load only what is measured.
std::vector<int> StartCpuHogs(int n, bool paused = false);
void ResumeCpuHogs(const std::vector<int>& pids);
void StopCpuHogs(const std::vector<int>& pids);

}  // namespace vlab::cli
