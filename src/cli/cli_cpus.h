// The CPUs a benchmark runs on: which are allowed, and pinning to some of them,
// so that a figure and its baseline are measured in the same layout.
#pragma once

#include <string>
#include <vector>

namespace vlab::cli {

/// The CPUs this process may run on (sched_getaffinity), ascending.
std::vector<int> AllowedCpus();
/// "0,1".
std::string CpuList(const std::vector<int>& cpus);
/// Pins the calling thread, and the threads and processes it starts later (a
/// log writer, a child), to `cpus` (empty: left as it is).
void PinTo(const std::vector<int>& cpus);
/// Starts `n` processes that spin on the CPU at normal priority (a competing
/// load), ended with this process if it dies; StopCpuHogs ends and reaps them.
std::vector<int> StartCpuHogs(int n);
void StopCpuHogs(const std::vector<int>& pids);

}  // namespace vlab::cli
