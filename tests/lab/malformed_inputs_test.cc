// Malformed input through the real vlab binary: every case of the corpus
// (tests/data/malformed/, plus FIFOs, devices, sockets, folders and oversized
// files made here) must exit 2 with one line on stderr that names the file (and
// line and key where there is one), write nothing, and stay small and quick.
//
// Bounds and where they come from: each case runs under `timeout -s KILL 30`,
// so a read that blocks (a FIFO) or never ends (/dev/zero) fails the test as
// a kill instead of hanging it; 30 s is far above a case's measured time (0.6 to
// 0.8 s on two busy cores, the same as `vlab --version`: loading vlab's shared
// libraries; printed at the end). Peak memory is read from wait4()'s rusage (the
// largest resident set of vlab and the `timeout` around it) and must stay under
// 200 MB; `vlab --version` alone measured 121 MB of that (its libraries mapped).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "test_util.h"

namespace vlab::lab::malformed_inputs_test {
namespace {

namespace fs = std::filesystem;
using vlab::testing::ReadFile;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

constexpr long kMaxRssKb = 200 * 1024;

struct Case {
  std::string name;
  std::vector<std::string> args;    // with the placeholders of Expand()
  std::vector<std::string> expect;  // parts of stderr, placeholders as in args
};

struct Outcome {
  int exit_code = -1;
  std::string err;
  double wall_s = 0;
  long max_rss_kb = 0;
};

// the placeholders of a case filled in: "@D" the corpus, "@T" the generated
// inputs, "@O" the case's own output folder
std::string Expand(std::string text, const std::string& data, const std::string& tmp, const std::string& own) {
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"@D", data}, {"@T", tmp}, {"@O", own}}) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
      text.replace(at, from.size(), to);
    }
  }
  return text;
}

// vlab ARGS from the source root, stdin /dev/null, stdout dropped, stderr to
// `err_file`; returns its pid (the `timeout` around it)
pid_t StartVlab(const std::vector<std::string>& args, const std::string& err_file) {
  std::vector<std::string> words = {"timeout", "-s", "KILL", "30", VLAB_BINARY_DIR "/vlab"};
  words.insert(words.end(), args.begin(), args.end());
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int in = ::open("/dev/null", O_RDONLY);
    const int out = ::open("/dev/null", O_WRONLY);
    const int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || err < 0 || ::chdir(VLAB_SOURCE_DIR) != 0) ::_exit(126);
    ::dup2(in, 0);
    ::dup2(out, 1);
    ::dup2(err, 2);
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

// waits for one started run: its exit code, stderr and peak memory
Outcome FinishVlab(pid_t pid, const std::string& err_file, std::chrono::steady_clock::time_point start) {
  Outcome o;
  int status = 0;
  struct rusage usage {};
  if (pid < 0 || ::wait4(pid, &status, 0, &usage) != pid) return o;
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.max_rss_kb = usage.ru_maxrss;
  o.err = ReadFile(err_file);
  return o;
}

void MakeFifo(const std::string& path) { ASSERT_EQ(::mkfifo(path.c_str(), 0644), 0) << path; }

void MakeSocket(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  ASSERT_LT(path.size(), sizeof(addr.sun_path)) << path;
  std::snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", path.c_str());
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0) << path;
  ::close(fd);  // the socket file stays
}

// The inputs no repository can hold: made in `tmp`.
void MakeGenerated(const TempDir& tmp) {
  const std::string scene = VLAB_SOURCE_DIR "/scenes/pa10.xml";
  MakeFifo(tmp / "fifo.yaml");
  MakeFifo(tmp / "fifo.xml");
  MakeFifo(tmp / "fifo.csv");
  MakeSocket(tmp / "socket.yaml");
  fs::create_directory(tmp / "folder.yaml");
  fs::create_symlink("/dev/zero", tmp / "zero.yaml");
  WriteFile(tmp / "big.yaml", "name: big\nscene: " + scene + "\nduration: 1\n# " + std::string(1 << 20, 'x') + "\n");
  WriteFile(tmp / "big.xml", "<mujoco>\n<!-- " + std::string(4 << 20, 'x') + " -->\n</mujoco>\n");
  WriteFile(tmp / "include_fifo.xml", "<mujoco>\n  <include file=\"fifo.xml\"/>\n</mujoco>\n");
  for (const std::string s : {"fifo.xml", "/dev/zero", "folder.yaml", "big.xml", "include_fifo.xml"}) {
    const std::string name = "scene_" + fs::path(s).stem().string();
    WriteFile(tmp / (name + ".yaml"), "name: " + name + "\nscene: " + s + "\nduration: 1\n");
  }
  const std::string golden = "scenario: " VLAB_SOURCE_DIR "/scenes/pa10_reach.yaml\nevery: 10\n";
  fs::create_directory(tmp / "golden_fifo");
  MakeFifo(tmp / "golden_fifo/golden.yaml");
  fs::create_directory(tmp / "golden_zero_log");
  WriteFile(tmp / "golden_zero_log/golden.yaml", golden);
  fs::create_symlink("/dev/zero", tmp / "golden_zero_log/log.csv");
  fs::create_directory(tmp / "golden_scenario_fifo");
  WriteFile(tmp / "golden_scenario_fifo/golden.yaml", "scenario: ../fifo.yaml\n");
  fs::create_directory(tmp / "golden_fifo_log");
  WriteFile(tmp / "golden_fifo_log/golden.yaml", golden);
  MakeFifo(tmp / "golden_fifo_log/log.csv");
}

std::vector<Case> Cases() {
  const std::string out = "--out=@O/out";
  const std::string bomb =
      "[&a [x,x,x,x,x,x,x,x,x,x], &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a], "
      "&c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b], &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c], "
      "&e [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d], &f [*e,*e,*e,*e,*e,*e,*e,*e,*e,*e], "
      "&g [*f,*f,*f,*f,*f,*f,*f,*f,*f,*f], &h [*g,*g,*g,*g,*g,*g,*g,*g,*g,*g]]";
  auto run = [&](const std::string& file, std::vector<std::string> expect) {
    return Case{file, {"run", file, "-q", out}, std::move(expect)};
  };
  auto set = [&](const std::string& name, const std::string& kv, std::vector<std::string> expect) {
    return Case{name, {"run", "scenes/pa10_reach", "-q", out, "--set", kv}, std::move(expect)};
  };
  auto seed = [&](const std::string& value) {
    return Case{"--seed " + value,
                {"run", "scenes/pa10_reach", "-q", out, "--seed=" + value},
                {"--seed: must be an integer from 0 to 9007199254740992 (2^53), got '" + value + "'"}};
  };
  auto sweep = [&](const std::string& file, std::vector<std::string> expect) {
    return Case{"sweep " + file, {"sweep", file, "--list"}, std::move(expect)};
  };
  auto golden = [&](const std::string& dir, std::vector<std::string> expect) {
    return Case{"golden " + dir, {"golden", dir, "--keep", "@O/keep"}, std::move(expect)};
  };
  auto compare = [&](const std::string& file, std::vector<std::string> expect) {
    return Case{"compare " + file, {"compare", file, "tests/goldens/pa10_reach"}, std::move(expect)};
  };
  return {
      // scenario files: read faults
      run("@T/fifo.yaml", {"scenario '@T/fifo.yaml': a FIFO (named pipe), not a regular file"}),
      run("@T/zero.yaml", {"scenario '@T/zero.yaml': a character device, not a regular file"}),
      run("/dev/zero", {"scenario '/dev/zero': a character device, not a regular file"}),
      run("@T/folder.yaml", {"scenario '@T/folder.yaml': a folder, not a regular file"}),
      run("@T/socket.yaml", {"scenario '@T/socket.yaml': a socket, not a regular file"}),
      run("@T/big.yaml", {"scenario '@T/big.yaml': 1 MiB, over the 1 MiB an input file of this kind may have"}),
      run("@T/none.yaml", {"scenario '@T/none.yaml': cannot open file"}),
      run("@D/non_utf8_latin1.yaml", {"@D/non_utf8_latin1.yaml:2:17: byte 0xE9 is not UTF-8"}),
      run("@D/non_utf8_overlong.yaml", {"@D/non_utf8_overlong.yaml:4:14: byte 0xC0 is not UTF-8"}),
      run("@D/non_utf8_surrogate.yaml", {"@D/non_utf8_surrogate.yaml:3:14: byte 0xED is not UTF-8"}),
      run("@D/non_utf8_truncated.yaml", {"@D/non_utf8_truncated.yaml:4:14: byte 0xE2 is not UTF-8"}),
      run("@D/utf16.yaml", {"@D/utf16.yaml:1:1: byte 0xFF is not UTF-8"}),
      // scenario files: YAML faults
      run("@D/dup_duration.yaml", {"@D/dup_duration.yaml:5: duration: duplicate key (first at line 4)"}),
      run("@D/dup_devices.yaml", {"@D/dup_devices.yaml:6: devices: duplicate key (first at line 4)"}),
      run("@D/dup_nested.yaml", {"@D/dup_nested.yaml:7: devices[0].kind: duplicate key (first at line 6)"}),
      run("@D/dup_flow.yaml", {"@D/dup_flow.yaml:4: realtime.factor: duplicate key (first at line 4)"}),
      run("@D/dup_quoted.yaml", {"@D/dup_quoted.yaml:4: duration: duplicate key (first at line 3)"}),
      run("@D/alias_bomb.yaml", {"@D/alias_bomb.yaml:", "randomize.a4[", "expands to more than 100000 nodes"}),
      run("@D/alias_cycle.yaml", {"@D/alias_cycle.yaml:4: devices[0]: an alias inside the node it names"}),
      run("@D/deep_nesting.yaml", {"@D/deep_nesting.yaml:4: devices", "nested more than 64 deep"}),
      run("@D/two_documents.yaml", {"@D/two_documents.yaml:", "a second YAML document"}),
      // scenario files: integers
      run("@D/seed_too_big.yaml",
          {"@D/seed_too_big.yaml:4: seed: must be a non-negative integer, at most 9007199254740992 (2^53); got "
           "'99999999999999999999999'"}),
      run("@D/seed_2p53_plus_1.yaml", {"@D/seed_2p53_plus_1.yaml:4: seed:", "got '9007199254740993'"}),
      run("@D/seed_negative.yaml", {"@D/seed_negative.yaml:4: seed:", "got '-1'"}),
      run("@D/seed_fraction.yaml", {"@D/seed_fraction.yaml:4: seed:", "got '1.5'"}),
      run("@D/seed_exponent.yaml", {"@D/seed_exponent.yaml:4: seed:", "got '1e3'"}),
      run("@D/integer_too_big.yaml",
          {"@D/integer_too_big.yaml:4: realtime.priority: out of range: expected an integer from -2147483647 to "
           "2147483647, got '99999999999'"}),
      run("@D/integer_fraction.yaml", {"@D/integer_fraction.yaml:4: lockstep.release_after: expected an integer"}),
      // scenes (MJCF): checked before MuJoCo opens them
      run("@T/scene_fifo.yaml", {"@T/scene_fifo.yaml:2: scene: scene '@T/fifo.xml': a FIFO"}),
      run("@T/scene_zero.yaml", {"@T/scene_zero.yaml:2: scene: scene '/dev/zero': a character device"}),
      run("@T/scene_folder.yaml", {"@T/scene_folder.yaml:2: scene: scene '@T/folder.yaml': a folder"}),
      run("@T/scene_big.yaml", {"@T/scene_big.yaml:2: scene: scene '@T/big.xml': 4 MiB, over the 4 MiB"}),
      run("@T/scene_include_fifo.yaml",
          {"@T/scene_include_fifo.yaml:2: scene: scene '@T/include_fifo.xml': include 'fifo.xml': a FIFO"}),
      run("@D/scene_non_utf8.yaml", {"@D/scene_non_utf8.yaml:2: scene:", "@D/scene_non_utf8.xml:1:19: byte 0xE9"}),
      // --seed
      seed("99999999999999999999999"),
      seed("9007199254740993"),
      seed("-1"),
      seed("1.5"),
      seed("0x10"),
      Case{"--seed ''", {"run", "scenes/pa10_reach", "-q", out, "--seed="}, {"--seed"}},
      seed("1e3"),
      Case{"cubes --seed",
           {"cubes", out, "--scene=@O/s.xml", "--seed=18446744073709551616"},
           {"--seed: must be an integer from 0 to 9007199254740992 (2^53), got '18446744073709551616'"}},
      Case{"task --seed",
           {"task", "@T/none.lua", "--arm=127.0.0.1:9", "--scene=scenes/pa10.xml", "--tip=tool",
            "--seed=9007199254740993"},
           {"--seed: must be an integer from 0 to 9007199254740992 (2^53), got '9007199254740993'"}},
      // --set
      set("--set seed=2^53+1", "seed=9007199254740993", {"pa10_reach.yaml", "seed:", "got '9007199254740993'"}),
      set("--set seed=-3", "seed=-3", {"pa10_reach.yaml", "seed:", "got '-3' (from --set seed=-3)"}),
      set("--set integer out of range", "devices.jr3.filter=99999999999",
          {"pa10_reach.yaml", "devices[1].filter: out of range", "(from --set devices.jr3.filter=99999999999)"}),
      set("--set alias bomb", "description=" + bomb, {"--set description=", "expands to more than 100000 nodes"}),
      set("--set duplicate key", "controller.gains={position: 1, position: 2}",
          {"--set controller.gains={position: 1, position: 2}: position: duplicate key (first at column 2)"}),
      set("--set alias cycle", "description=&a [*a]", {"--set description=&a [*a]: [0]: an alias inside"}),
      set("--set deep nesting", "description=" + std::string(100, '[') + std::string(100, ']'),
          {"--set description=[[[", "nested more than 64 deep"}),
      set("--set non-UTF-8", "description=caf\xe9", {"--set: byte 0xE9 at column 16 of KEY=VALUE is not UTF-8"}),
      set("--set malformed", "description=[1", {"--set description=[1: the value is not valid YAML"}),
      // golden folders and logs
      golden("@D/golden_dup", {"@D/golden_dup/golden.yaml:3: every: duplicate key (first at line 2)"}),
      golden("@D/golden_seed", {"@D/golden_seed/golden.yaml:2: seed:", "got '9007199254740993'"}),
      golden("@D/golden_non_utf8", {"@D/golden_non_utf8/golden.yaml:2:4: byte 0xE9 is not UTF-8"}),
      golden("@D/golden_alias_bomb", {"@D/golden_alias_bomb/golden.yaml:", "expands to more than 100000 nodes"}),
      golden("@T/golden_fifo", {"golden '@T/golden_fifo/golden.yaml': a FIFO"}),
      golden("@T/golden_zero_log", {"golden log '@T/golden_zero_log/log.csv': a character device"}),
      golden("@T/golden_scenario_fifo",
             {"@T/golden_scenario_fifo/golden.yaml:1: scenario: '@T/fifo.yaml': a FIFO (named pipe)"}),
      golden("@T/golden_fifo_log", {"golden log '@T/golden_fifo_log/log.csv': a FIFO"}),
      compare("@T/fifo.csv", {"CSV log '@T/fifo.csv': a FIFO"}),
      compare("/dev/zero", {"CSV log '/dev/zero': a character device"}),
      compare("@D/log_non_utf8.csv", {"@D/log_non_utf8.csv:3:5: byte 0xFF is not UTF-8"}),
      // sweep files, as far as reading them goes
      sweep("@D/sweep_dup.yaml", {"@D/sweep_dup.yaml:4: seeds: duplicate key (first at line 3)"}),
      sweep("@D/sweep_alias_bomb.yaml", {"@D/sweep_alias_bomb.yaml:", "expands to more than 100000 nodes"}),
      sweep("@D/sweep_non_utf8.yaml", {"@D/sweep_non_utf8.yaml:4:48: byte 0xA0 is not UTF-8"}),
      sweep("@T/fifo.yaml", {"'@T/fifo.yaml': a FIFO"}),
      sweep("/dev/zero", {"'/dev/zero': a character device"}),
      // identification specs and overrides files (vlab identify, vlab run --overrides)
      Case{"identify @T/fifo.yaml",
           {"identify", "@T/fifo.yaml", "--out", "@O/fit"},
           {"identification spec '@T/fifo.yaml': a FIFO (named pipe), not a regular file"}},
      Case{"identify /dev/zero",
           {"identify", "/dev/zero", "--out", "@O/fit"},
           {"identification spec '/dev/zero': a character device"}},
      Case{"identify alias bomb",
           {"identify", "@D/alias_bomb.yaml", "--out", "@O/fit"},
           {"@D/alias_bomb.yaml:", "expands to more than 100000 nodes"}},
      Case{"--overrides @T/fifo.yaml",
           {"run", "scenes/pa10_reach", "-q", out, "--overrides", "@T/fifo.yaml"},
           {"overrides file '@T/fifo.yaml': a FIFO (named pipe), not a regular file"}},
      Case{"--overrides /dev/zero",
           {"run", "scenes/pa10_reach", "-q", out, "--overrides", "/dev/zero"},
           {"overrides file '/dev/zero': a character device"}},
  };
}

TEST(MalformedInputs, EachExitsTwoNamingTheFileAndWritesNothing) {
  TempDir tmp;
  MakeGenerated(tmp);
  const std::string data = VLAB_SOURCE_DIR "/tests/data/malformed";
  const std::vector<Case> cases = Cases();
  ASSERT_GE(cases.size(), 50u);
  // eight at a time, each in its own output folder: a case that writes is seen
  constexpr std::size_t kBatch = 8;
  std::vector<Outcome> outcomes(cases.size());
  for (std::size_t first = 0; first < cases.size(); first += kBatch) {
    const std::size_t last = std::min(cases.size(), first + kBatch);
    std::vector<pid_t> pids;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = first; i < last; ++i) {
      std::vector<std::string> args;
      const std::string own = tmp.path() + "/" + std::to_string(i);
      fs::create_directory(own);
      for (const std::string& a : cases[i].args) args.push_back(Expand(a, data, tmp.path(), own));
      pids.push_back(StartVlab(args, own + ".err"));
    }
    for (std::size_t i = first; i < last; ++i) {
      outcomes[i] = FinishVlab(pids[i - first], tmp.path() + "/" + std::to_string(i) + ".err", start);
    }
  }
  double worst_s = 0;
  long worst_kb = 0;
  std::string worst_case;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const Outcome& o = outcomes[i];
    const std::string own = tmp.path() + "/" + std::to_string(i);
    const std::string name = Expand(c.name, data, tmp.path(), own);
    EXPECT_EQ(o.exit_code, 2) << name << ": " << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << name << ": " << o.err;
    for (const std::string& part : c.expect) {
      const std::string want = Expand(part, data, tmp.path(), own);
      EXPECT_NE(o.err.find(want), std::string::npos) << name << ": expected '" << want << "' in: " << o.err;
    }
    EXPECT_LT(o.max_rss_kb, kMaxRssKb) << name;
    EXPECT_TRUE(fs::is_empty(own)) << name << ": wrote into " << own;
    if (o.wall_s > worst_s) {
      worst_s = o.wall_s;
      worst_case = name;
    }
    worst_kb = std::max(worst_kb, o.max_rss_kb);
  }
  std::printf("%zu malformed inputs, 8 at a time: slowest batch member %.3f s (%s), peak RSS %.1f MB\n", cases.size(),
              worst_s, worst_case.c_str(), worst_kb / 1024.0);
}

// The corpus stays a corpus: each file is read by one of the cases above.
TEST(MalformedInputs, EveryCorpusFileIsUsed) {
  std::string all;
  for (const Case& c : Cases()) {
    for (const std::string& a : c.args) all += a + "\n";
  }
  for (const auto& e : fs::recursive_directory_iterator(VLAB_SOURCE_DIR "/tests/data/malformed")) {
    if (!e.is_regular_file()) continue;
    const std::string rel = fs::relative(e.path(), VLAB_SOURCE_DIR "/tests/data/malformed").string();
    const std::string top = rel.substr(0, rel.find('/'));
    const bool used = all.find("@D/" + rel) != std::string::npos || all.find("@D/" + top + "\n") != std::string::npos ||
                      rel == "scene_non_utf8.xml";
    EXPECT_TRUE(used) << rel << " is in the corpus but no case reads it";
  }
}

}  // namespace
}  // namespace vlab::lab::malformed_inputs_test
