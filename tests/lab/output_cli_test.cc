// vlab run's output folder end to end: --out names (a trailing slash, an empty
// name), two runs into one --out both keep their results, a user's files in a
// vlab folder are never deleted, the first failed write stops the run and keeps
// what was written, a stop signal is taken even when SIGINT was ignored or
// blocked at start, and the staging folders of killed runs are removed.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_run_output.h"
#include "test_util.h"

namespace vlab::lab::output_cli_test {
namespace {

namespace fs = std::filesystem;
using vlab::testing::Entries;
using vlab::testing::ExpectInterruptedOutput;
using vlab::testing::Lines;
using vlab::testing::ReadFile;
using vlab::testing::RunVlab;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

constexpr double kPeriod_s = 0.002;   // scenes/pa10_reach.yaml's control_period
constexpr double kDuration_s = 13.0;  // and its duration

bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// How the test starts vlab: what the process inherits.
struct Launch {
  std::vector<std::string> args;  // after the program's name
  bool ignore_sigint = false;     // SIGINT at SIG_IGN, as bash leaves it for a script's `&` job
  bool sigint_pending = false;    // ... and blocked, with one SIGINT pending: a signal that came before
  long file_size_limit = 0;       // RLIMIT_FSIZE in bytes (SIGXFSZ ignored: a write past it fails, EFBIG)
};

// vlab running from the source root, stdout and stderr into files of its own.
class Vlab {
 public:
  explicit Vlab(const Launch& launch) {
    out_ = tmp_ / "out";
    err_ = tmp_ / "err";
    pid_ = ::fork();
    if (pid_ != 0) return;
    const int out = ::open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open(err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int in = ::open("/dev/null", O_RDONLY);
    if (out < 0 || err < 0 || in < 0 || ::dup2(out, 1) < 0 || ::dup2(err, 2) < 0 || ::dup2(in, 0) < 0) ::_exit(126);
    if (launch.file_size_limit > 0) {
      const rlimit limit{static_cast<rlim_t>(launch.file_size_limit), static_cast<rlim_t>(launch.file_size_limit)};
      ::setrlimit(RLIMIT_FSIZE, &limit);
      ::signal(SIGXFSZ, SIG_IGN);
    }
    if (launch.ignore_sigint || launch.sigint_pending) ::signal(SIGINT, SIG_IGN);
    if (launch.sigint_pending) {
      sigset_t set;
      sigemptyset(&set);
      sigaddset(&set, SIGINT);
      ::sigprocmask(SIG_BLOCK, &set, nullptr);
      ::raise(SIGINT);  // (blocked: kept pending, ignored or not, and through exec)
    }
    if (::chdir(VLAB_SOURCE_DIR) != 0) ::_exit(126);
    std::vector<std::string> args = launch.args;
    args.insert(args.begin(), VLAB_BINARY_DIR "/vlab");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ~Vlab() {
    if (pid_ > 0 && !ended_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  pid_t pid() const { return pid_; }
  bool Ended() {
    if (!ended_ && ::waitpid(pid_, &status_, WNOHANG) == pid_) ended_ = true;
    return ended_;
  }
  /// Its exit code once it ended by itself within timeout_s (-1 otherwise: then killed).
  int Wait(double timeout_s = 120) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!Ended() && std::chrono::steady_clock::now() < until) ::usleep(1000);
    if (!Ended()) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status_, 0);
      ended_ = true;
      return -1;
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }
  /// Waits until its staging folder is in `parent` (the run has begun; nothing is renamed
  /// before it ends); false when it ended first or after timeout_s.
  bool WaitForStaging(const std::string& parent, double timeout_s = 60) {
    const std::string prefix = ".vlab-" + std::to_string(pid_) + "-";
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < until && !Ended()) {
      for (const std::string& name : Entries(parent)) {
        if (name.rfind(prefix, 0) == 0) return true;
      }
      ::usleep(1000);
    }
    return false;
  }
  std::string out() const { return ReadFile(out_); }
  std::string err() const { return ReadFile(err_); }

 private:
  TempDir tmp_;
  std::string out_, err_;
  pid_t pid_ = -1;
  int status_ = 0;
  bool ended_ = false;
};

Launch RunLaunch(const std::string& out_dir, const std::string& duration) {
  return Launch{{"run", "scenes/pa10_reach", "-q", "--duration", duration, "--out", out_dir}};
}

TEST(OutputCliTest, OutNames) {
  TempDir tmp;
  // the trailing slash tab completion adds names the same folder
  const auto r = RunVlab("run scenes/pa10_reach -q --duration 0.01 --out '" + (tmp / "res/") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(Has(r.out, "output in " + (tmp / "res") + "/")) << r.out;
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"res"});
  EXPECT_EQ(Entries(tmp / "res"), (std::set<std::string>{"log.csv", "summary.json", ".vlab-output"}));
  // an empty name is refused (it used to mean out/<scenario name>)
  for (const std::string command : {"run scenes/pa10_reach", "serve scenes/pa10_reach"}) {
    const auto empty = RunVlab(command + " -q --duration 0.01 --out ''");
    EXPECT_EQ(empty.exit_code, 2) << command;
    EXPECT_EQ(empty.err, "vlab: error: --out: an empty name (give a folder, e.g. --out results) (see vlab --help)\n");
  }
  const auto render = RunVlab("render scenes/pa10_reach --camera overview --out ''");
  EXPECT_EQ(render.exit_code, 2);
  EXPECT_EQ(render.err, "vlab: error: --out: an empty name (give a folder, e.g. --out frames)\n");
}

// 20 pairs of runs into one --out, each pair's two runs under way at once (both staging folders
// there) and stopped by SIGINT together, so both finish at the same moment; every other pair over
// a previous result. Both results survive every time: one in DIR, one in DIR.2, and that run says so.
TEST(OutputCliTest, TwoRunsIntoOneFolderKeepBoth) {
  constexpr int kPairs = 20;
  for (int pair = 0; pair < kPairs; ++pair) {
    TempDir tmp;
    const std::string dir = tmp / "res";
    if (pair % 2 == 1) {
      ASSERT_EQ(RunVlab("run scenes/pa10_reach -q --duration 0.01 --out '" + dir + "'").exit_code, 0);
    }
    Vlab a(RunLaunch(dir, "1000")), b(RunLaunch(dir, "1000"));
    ASSERT_TRUE(a.WaitForStaging(tmp.path())) << a.err();
    ASSERT_TRUE(b.WaitForStaging(tmp.path())) << b.err();
    ::kill(a.pid(), SIGINT);
    ::kill(b.pid(), SIGINT);
    EXPECT_EQ(a.Wait(), 1) << a.err();
    EXPECT_EQ(b.Wait(), 1) << b.err();
    ASSERT_EQ(Entries(tmp.path()), (std::set<std::string>{"res", "res.2"})) << "pair " << pair;
    EXPECT_GE(ExpectInterruptedOutput(dir, "SIGINT", kPeriod_s), 0);
    EXPECT_GE(ExpectInterruptedOutput(dir + ".2", "SIGINT", kPeriod_s), 0);
    const std::string moved = "this run's files are in '" + dir + ".2'";
    EXPECT_NE(Has(a.err(), moved), Has(b.err(), moved)) << a.err() << b.err();  // exactly one says so
    EXPECT_TRUE(Has(a.out() + b.out(), "output in " + dir + ".2/")) << a.out() << b.out();
  }
}

// files a user put in a folder vlab wrote: the next run into it is refused before it simulates
TEST(OutputCliTest, AUsersFilesInAVlabFolderAreNeverDeleted) {
  TempDir tmp;
  const std::string dir = tmp / "res";
  ASSERT_EQ(RunVlab("run scenes/pa10_reach -q --duration 0.01 --out '" + dir + "'").exit_code, 0);
  WriteFile(dir + "/my_notes.txt", "notes");
  fs::create_directory(dir + "/analysis");
  WriteFile(dir + "/analysis/fig.py", "plot()");
  const auto r = RunVlab("run scenes/pa10_reach -q --out '" + dir + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "vlab: error: output folder '" + dir +
                       "': holds entries vlab did not write: analysis/fig.py, my_notes.txt; vlab replaces only what "
                       "it wrote: move them out of it, or give another --out\n");
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"res"});
  EXPECT_EQ(ReadFile(dir + "/my_notes.txt"), "notes");
  EXPECT_EQ(ReadFile(dir + "/analysis/fig.py"), "plot()");
}

// A file size limit (RLIMIT_FSIZE, as a full disk does with ENOSPC) fails the log's writes: the
// run stops within the log writer's blocks in flight, names the file and the error, and what was
// written is in the output folder with a summary saying so.
TEST(OutputCliTest, FirstFailedWriteStopsTheRun) {
  TempDir tmp;
  const std::string dir = tmp / "res";
  constexpr long kLimit = 64 * 1024;
  Launch launch = RunLaunch(dir, "13");
  launch.file_size_limit = kLimit;
  Vlab vlab(launch);
  EXPECT_EQ(vlab.Wait(), 1) << vlab.err();
  const std::string err = vlab.err();
  EXPECT_TRUE(Has(err, "vlab: log '" + dir + "/log.csv': write failed: File too large; the run stopped at t = "))
      << err;
  EXPECT_TRUE(Has(err, " s of 13 s; what was written is in " + dir + "/\n")) << err;
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"res"});
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(dir + "/summary.json"));
  EXPECT_EQ(summary.at("result"), "fail");
  EXPECT_TRUE(Has(summary.at("failure").get<std::string>(), "log '" + dir + "/log.csv': write failed"));
  const long periods = summary.at("timings").at("control_periods").get<long>();
  // the log holds what fit under the limit; the run went on at most while the writer was
  // behind: 8 blocks of 256 rows in flight, the failing one and the one being filled
  EXPECT_EQ(fs::file_size(dir + "/log.csv"), static_cast<std::uintmax_t>(kLimit));
  const long rows = static_cast<long>(Lines(ReadFile(dir + "/log.csv")).size()) - 1;
  EXPECT_LE(periods, rows + 10 * 256);
  EXPECT_LT(periods * kPeriod_s, kDuration_s / 2) << "stopped early, far short of the duration";
}

// SIGINT ignored and blocked at start, with one pending: taken as soon as vlab installs its handler,
// before loading, so the run stops at t = 0 and writes that (before: the run went to its end)
TEST(OutputCliTest, SigintThatCameBeforeTheRunIsTaken) {
  TempDir tmp;
  Launch launch = RunLaunch(tmp / "res", "13");
  launch.sigint_pending = true;
  Vlab vlab(launch);
  EXPECT_EQ(vlab.Wait(), 1) << vlab.err();
  EXPECT_TRUE(Has(vlab.err(), "vlab: interrupted by SIGINT at t = 0 s, after 0 of 6500 periods")) << vlab.err();
  EXPECT_EQ(ExpectInterruptedOutput(tmp / "res", "SIGINT", kPeriod_s), 0);
}

// SIGINT at SIG_IGN at start (a script's `cmd &` in bash): a SIGINT during the run stops it as Ctrl-C does
TEST(OutputCliTest, SigintIgnoredAtStartStillStops) {
  TempDir tmp;
  Launch launch = RunLaunch(tmp / "res", "1000");
  launch.ignore_sigint = true;
  Vlab vlab(launch);
  ASSERT_TRUE(vlab.WaitForStaging(tmp.path())) << vlab.err();
  ::kill(vlab.pid(), SIGINT);
  EXPECT_EQ(vlab.Wait(), 1) << vlab.err();
  EXPECT_TRUE(Has(vlab.err(), "vlab: interrupted by SIGINT at t = ")) << vlab.err();
  EXPECT_GE(ExpectInterruptedOutput(tmp / "res", "SIGINT", kPeriod_s), 0);
}

// a run killed (SIGKILL) leaves its staging folder; the next run into the same parent removes it
TEST(OutputCliTest, StagingFolderOfAKilledRunIsRemoved) {
  TempDir tmp;
  Vlab killed(RunLaunch(tmp / "a", "1000"));
  ASSERT_TRUE(killed.WaitForStaging(tmp.path())) << killed.err();
  ::kill(killed.pid(), SIGKILL);
  EXPECT_EQ(killed.Wait(), -1);
  const std::set<std::string> left = Entries(tmp.path());
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left.begin()->rfind(".vlab-" + std::to_string(killed.pid()) + "-", 0), 0u) << *left.begin();
  ASSERT_EQ(RunVlab("run scenes/pa10_reach -q --duration 0.01 --out '" + (tmp / "b") + "'").exit_code, 0);
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"b"});
}

}  // namespace
}  // namespace vlab::lab::output_cli_test
