// vlab sweep SWEEP.yaml: the runs of a sweep file, listed (--list: one `vlab run`
// command per line, for GNU parallel, Slurm or any engine) or run here, N at a time.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>

#include <nlohmann/json.hpp>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_clock.h"
#include "core/core_errors.h"
#include "lab/sweep/lab_sweep.h"
#include "lab/sweep/lab_sweep_text.h"

namespace vlab::cli {

namespace {

namespace fs = std::filesystem;

struct SweepArgs {
  std::string file;
  std::string out_dir;  // "" = sweeps/NAME
  bool list = false;
  bool pending = false;  // --list: only the runs that are not current
  int jobs = 1;
  std::string vlab;  // program named in --list ("" = this binary)
};

std::string SelfPath() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? "vlab" : self.string();
}

std::string ResultOf(const std::string& run_dir) {
  std::ifstream in(run_dir + "/summary.json");
  const nlohmann::json s = nlohmann::json::parse(in, nullptr, false);
  return s.is_object() ? s.value("result", "?") : "?";
}

// Starts `program args` with stdout and stderr into `log`; returns its pid.
pid_t Start(const std::string& program, const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> argv = {program};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> raw;
  for (auto& a : argv) raw.push_back(a.data());
  raw.push_back(nullptr);
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(log + ": cannot create file");
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    const int null = ::open("/dev/null", O_RDONLY);
    if (null >= 0) ::dup2(null, 0);
    ::execv(raw[0], raw.data());
    ::_exit(127);
  }
  ::close(fd);
  if (pid < 0) throw std::runtime_error("fork failed");
  return pid;
}

std::string Duration(double s) {
  char buf[32];
  if (s < 90) {
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  } else if (s < 5400) {
    std::snprintf(buf, sizeof buf, "%.1f min", s / 60);
  } else {
    std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  }
  return buf;
}

// The runs of `sweep` that are not current in `out`; a line in `notes` for each
// stale one (finished, but not what the sweep runs now), and for each run folder
// in `out` that is no run of this sweep. Counts the current ones by result.
std::vector<std::size_t> RunsToDo(const lab::Sweep& sweep, const std::string& out, std::string& notes, int& pass,
                                  int& failed, int& current) {
  std::vector<std::size_t> todo;
  std::set<std::string> ids;
  for (std::size_t i = 0; i < sweep.runs.size(); ++i) {
    const lab::SweepRun& run = sweep.runs[i];
    ids.insert(run.id);
    const lab::RunState state = lab::CheckRun(sweep, run, out + "/" + run.id);
    if (state.current) {
      ++current;
      (state.result == "pass" ? pass : failed) += 1;
      continue;
    }
    todo.push_back(i);
    if (state.stale) {
      const std::string label = run.label.empty() ? "" : " (" + lab::Printable(run.label) + ")";
      notes += "  " + run.id + label + ": runs again: " + state.why + "\n";
    }
  }
  std::error_code ec;
  std::vector<std::string> others;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (!ids.count(name) && fs::is_regular_file(e.path() / "summary.json")) others.push_back(name);
  }
  std::sort(others.begin(), others.end());
  for (const std::string& name : others) {
    notes += "  " + lab::Printable(name) + ": not a run of this sweep (left as it is; vlab collect lists it)\n";
  }
  return todo;
}

}  // namespace

int RunSweepHere(const lab::Sweep& sweep, const std::string& out, int jobs, bool quiet) {
  fs::create_directories(out + "/logs");
  const std::string self = SelfPath();
  InstallStopSignals();
  int pass = 0, failed = 0, skipped = 0;
  std::string notes;
  const std::vector<std::size_t> todo = RunsToDo(sweep, out, notes, pass, failed, skipped);
  if (!quiet) {
    std::printf("sweep %s: %zu runs, %d complete already (skipped), %zu to run, %d at a time; output in %s/\n%s",
                sweep.name.c_str(), sweep.runs.size(), skipped, todo.size(), jobs, out.c_str(), notes.c_str());
    std::fflush(stdout);
  }
  const bool tty = !quiet && ::isatty(2);
  std::map<pid_t, std::pair<std::size_t, double>> running;  // pid -> run, start time
  std::size_t next = 0;
  int done = 0;
  double busy_s = 0;  // wall time of the runs done, summed
  bool forwarded = false;
  while (next < todo.size() || !running.empty()) {
    while (!g_stop_requested && next < todo.size() && static_cast<int>(running.size()) < jobs) {
      const lab::SweepRun& run = sweep.runs[todo[next++]];
      running[Start(self, lab::RunArguments(sweep, run, out), out + "/logs/" + run.id + ".txt")] = {todo[next - 1],
                                                                                                    WallNow()};
    }
    if (g_stop_requested && !forwarded) {
      for (const auto& r : running) ::kill(r.first, g_stop_requested);
      forwarded = true;
    }
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    auto it = running.find(pid);
    if (it == running.end()) continue;
    const lab::SweepRun& run = sweep.runs[it->second.first];
    const double wall = WallNow() - it->second.second;
    running.erase(it);
    ++done;
    busy_s += wall;
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    const std::string result = code == 0 ? "pass" : ResultOf(out + "/" + run.id);
    (code == 0 ? pass : failed) += 1;
    if (tty) std::fprintf(stderr, "\r%*s\r", 78, "");
    const std::string see = code == 0 ? "" : "; its output: " + out + "/logs/" + run.id + ".txt";
    if (!quiet) {
      std::printf("  %-16s %s (exit %d, %.1f s)%s\n", run.id.c_str(), result.c_str(), code, wall, see.c_str());
      std::fflush(stdout);
    }
    if (tty) {
      const std::size_t left = todo.size() - static_cast<std::size_t>(done);
      const double eta = left * (busy_s / done) / jobs;
      std::fprintf(stderr, "[sweep] %d/%zu done, %d failed, %zu running, about %s left", done, todo.size(), failed,
                   running.size(), Duration(eta).c_str());
      std::fflush(stderr);
    }
  }
  if (tty) std::fprintf(stderr, "\r%*s\r", 78, "");
  const std::size_t not_run = todo.size() - static_cast<std::size_t>(done);
  const std::string interrupted = not_run ? ", " + std::to_string(not_run) + " not run (interrupted)" : "";
  if (!quiet) {
    std::printf("sweep %s: %d pass, %d failed, %d skipped (complete already)%s; output in %s/\n", sweep.name.c_str(),
                pass, failed, skipped, interrupted.c_str(), out.c_str());
  }
  return failed == 0 && not_run == 0 && !g_stop_requested ? 0 : 1;
}

namespace {

int SweepMain(const SweepArgs& a) {
  if (a.jobs < 1 || a.jobs > 1024) throw InputError("-j must be 1 to 1024");
  const lab::Sweep sweep = lab::LoadSweep(a.file);
  const std::string out =
      fs::absolute(a.out_dir.empty() ? "sweeps/" + sweep.name : a.out_dir).lexically_normal().string();
  if (a.list) {
    lab::Sweep absolute = sweep;
    absolute.scenario = fs::absolute(sweep.scenario).lexically_normal().string();
    const std::string program = a.vlab.empty() ? SelfPath() : a.vlab;
    std::vector<std::size_t> runs;
    if (a.pending) {
      int pass = 0, failed = 0, current = 0;
      std::string notes;
      runs = RunsToDo(sweep, out, notes, pass, failed, current);
      std::fprintf(stderr, "sweep %s: %zu runs, %d complete already (not listed), %zu listed\n%s", sweep.name.c_str(),
                   sweep.runs.size(), current, runs.size(), notes.c_str());
    } else {
      for (std::size_t i = 0; i < sweep.runs.size(); ++i) runs.push_back(i);
    }
    // every line whole before any is printed: a refused path prints no partial list
    std::string lines;
    for (std::size_t i : runs) {
      std::vector<std::string> words = {program};
      for (const std::string& arg : lab::RunArguments(absolute, absolute.runs[i], out)) words.push_back(arg);
      lines += lab::JobLine(words) + "\n";
    }
    std::fputs(lines.c_str(), stdout);
    return 0;
  }
  return RunSweepHere(sweep, out, a.jobs, false);
}

}  // namespace

Subcommand AddSweepCommand(CLI::App& app) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "Run a scenario over seeds and a grid or list of --set overrides (SWEEP.yaml, docs/sweeps.md): "
      "--list prints one vlab run command per run for GNU parallel or Slurm; otherwise runs them here, "
      "skipping runs already complete whose record matches (a run whose scenario, seed, duration or vlab "
      "changed since is run again, and said so)");
  cmd->add_option("sweep", args->file, "Sweep file (YAML)")->required();
  cmd->add_flag("--list", args->list,
                "Print one vlab run command per run (absolute paths; each value one line of YAML, control characters "
                "escaped) and exit");
  cmd->add_flag(
      "--pending", args->pending,
      "--list: only the runs that are not complete and current (stderr names each finished run that changed since it "
      "ran, and why)");
  cmd->add_option("-j,--jobs", args->jobs, "Runs at a time, 1 to 1024 (default 1)");
  cmd->add_option("--out", args->out_dir, "Sweep folder: one run folder per run, ID = pNN_sSEED (default sweeps/NAME)");
  cmd->add_option("--vlab", args->vlab, "--list: the vlab program to name in each command (default: this one)");
  return {cmd, [args] { return WithErrorReport([&] { return SweepMain(*args); }); }};
}

}  // namespace vlab::cli
