// vlab bench log: the run log's formats side by side. Each round runs the
// scenario (default scenes/pa10_reach, 60 s simulated) once per format, CSV
// first, as `vlab run` does (in this process, the whole run: model, step loop,
// writer thread, output folder), and times each run's wall clock; the rounds
// interleave the formats, so that a machine's drift touches all alike. Printed
// per format: the log file's bytes and the fraction of CSV's (goal <= 1/5 for
// the binary formats), the median wall time and the median of the rounds'
// ratios to CSV's run (goal <= 1.03).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/cli_commands.h"
#include "cli/cli_cpus.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "core/core_realtime.h"
#include "lab/outputs/lab_log_formats.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kDefaultScenario = "scenes/pa10_reach";
constexpr double kDefaultDuration_s = 60;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

}  // namespace

int BenchLog(const BenchArgs& args) {
  return WithErrorReport([&args] {
    const std::string scenario = args.scenario.empty() ? kDefaultScenario : args.scenario;
    const double duration_s = args.duration_s > 0 ? args.duration_s : kDefaultDuration_s;
    const std::vector<int> cpus = ThreadCpus();
    std::printf("CPUs: %zu allowed (%s); %ld online\n", cpus.size(), CpuListText(cpus).c_str(),
                ::sysconf(_SC_NPROCESSORS_ONLN));
    const std::vector<std::string> formats = lab::LogFormatNames();  // csv first
    std::printf("log formats of %s, %.3g s simulated, %d rounds of %zu runs (one per format, interleaved)\n",
                scenario.c_str(), duration_s, args.repeat, formats.size());

    std::string work = (fs::temp_directory_path() / "vlab-bench-log-XXXXXX").string();
    if (!::mkdtemp(work.data())) throw std::runtime_error("cannot create a temporary folder");
    std::vector<std::vector<double>> wall(formats.size()), ratio(formats.size());
    std::vector<long long> bytes(formats.size(), 0);
    int failures = 0;
    try {
      for (int r = 0; r < args.repeat; ++r) {
        for (std::size_t f = 0; f < formats.size(); ++f) {
          RunArgs run;
          run.scenario = scenario;
          run.out_dir = work + "/" + formats[f] + "_" + std::to_string(r);
          run.quiet = true;
          run.duration_s = duration_s;
          run.sets = {"outputs.log={format: " + formats[f] + "}"};
          const double t0 = WallNow();
          failures += RunCommand(run) != 0;
          wall[f].push_back(WallNow() - t0);
          ratio[f].push_back(wall[f].back() / wall[0].back());
          const fs::path log = fs::path(run.out_dir) / lab::LogFileName(lab::ParseLogFormat(formats[f], "format"));
          std::error_code ec;
          bytes[f] = static_cast<long long>(fs::file_size(log, ec));
          if (ec) throw std::runtime_error("the run wrote no " + log.filename().string());
          fs::remove_all(run.out_dir);
        }
      }
    } catch (...) {
      fs::remove_all(work);
      throw;
    }
    fs::remove_all(work);
    for (std::size_t f = 0; f < formats.size(); ++f) {
      std::printf("%-5s %-8s %12lld B  %.3f of CSV   wall %.3f s (median)  ratio to CSV %.3f (median of %d)%s\n",
                  formats[f].c_str(), lab::LogFileName(lab::ParseLogFormat(formats[f], "format")), bytes[f],
                  static_cast<double>(bytes[f]) / static_cast<double>(bytes[0]), Median(wall[f]), Median(ratio[f]),
                  args.repeat, f == 0 ? "   (baseline)" : "");
    }
    std::printf("goals: binary formats <= 0.2 of CSV's bytes, wall time <= 1.03 x CSV's\n");
    if (failures) std::printf("note: %d runs did not pass their checks\n", failures);
    return 0;
  });
}

}  // namespace vlab::cli
