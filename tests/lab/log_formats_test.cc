// The run log's formats (lab_log_formats.h, lab_log_hdf5.h, lab_log_mat.h) and
// vlab convert (lab_log_convert.h), through the real binary where a run is needed:
// log.h5 and log.mat read back with libhdf5 and libmatio equal log.csv bit for
// bit; log.mcap read by the MCAP reference reader (tests/node/read_mcap.mjs: every
// schema and message, signals bit for bit, poses, frames) and written again byte for byte
// by convert; a SIGINT leaves a valid log.h5 and log.mcap of every period written; the scenario key's
// refusals; convert's refusals (an existing target, a file vlab did not write, a
// malformed CSV, a FIFO), with nothing half-written left behind.
#include <matio.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/core_errors.h"
#include "lab/outputs/lab_log_convert.h"
#include "lab/outputs/lab_log_formats.h"
#include "lab/outputs/lab_log_hdf5.h"
#include "lab/outputs/lab_log_mat.h"
#include "scene/scene_csv.h"
#include "test_util.h"
#include "wait_until.h"

namespace vlab::lab::log_formats_test {
namespace {

using vlab::testing::Bits;

namespace fs = std::filesystem;
using vlab::testing::ProcessResult;
using vlab::testing::ReadFile;
using vlab::testing::RunVlab;
using vlab::testing::TempDir;
using vlab::testing::WaitUntil;
using vlab::testing::WriteFile;

// every value of `b` has the bits of `a`'s value in the same row and column (columns by name)
void ExpectSameBits(const scene::CsvTable& a, const scene::CsvTable& b) {
  ASSERT_EQ(a.columns, b.columns) << b.file;
  ASSERT_EQ(a.rows.size(), b.rows.size()) << b.file;
  for (std::size_t r = 0; r < a.rows.size(); ++r) {
    for (std::size_t c = 0; c < a.columns.size(); ++c) {
      ASSERT_EQ(Bits(a.rows[r][c]), Bits(b.rows[r][c])) << b.file << " row " << r << " " << a.columns[c];
    }
  }
}

// a char matrix's rows, trailing blanks dropped
std::vector<std::string> Strings(matvar_t* chars) {
  std::vector<std::string> out;
  if (!chars) return out;
  const std::size_t rows = chars->dims[0], width = chars->dims[1];
  const char* text = static_cast<const char*>(chars->data);
  for (std::size_t r = 0; r < rows; ++r) {
    std::string row;
    for (std::size_t c = 0; c < width; ++c) row.push_back(text[c * rows + r]);
    out.push_back(row.substr(0, row.find_last_not_of(' ') + 1));
  }
  return out;
}

// log.mat read back with libmatio: its groups' columns in the file's order, as a table
scene::CsvTable ReadMat(const std::string& path, std::map<std::string, std::string>* units) {
  scene::CsvTable t;
  t.file = path;
  mat_t* mat = Mat_Open(path.c_str(), MAT_ACC_RDONLY);
  EXPECT_NE(mat, nullptr) << path;
  if (!mat) return t;
  std::vector<std::vector<double>> columns;
  while (matvar_t* info = Mat_VarReadNextInfo(mat)) {
    matvar_t* v = Mat_VarRead(mat, info->name);
    Mat_VarFree(info);
    EXPECT_EQ(v->class_type, MAT_C_STRUCT);
    matvar_t* data = Mat_VarGetStructFieldByName(v, "data", 0);
    const std::vector<std::string> names = Strings(Mat_VarGetStructFieldByName(v, "names", 0));
    const std::vector<std::string> unit = Strings(Mat_VarGetStructFieldByName(v, "units", 0));
    EXPECT_EQ(data->dims[1], names.size());
    EXPECT_EQ(unit.size(), names.size());
    for (std::size_t c = 0; c < names.size(); ++c) {
      t.columns.push_back(names[c]);
      (*units)[names[c]] = unit[c];
      const double* values = static_cast<const double*>(data->data) + c * data->dims[0];
      columns.emplace_back(values, values + data->dims[0]);
    }
    Mat_VarFree(v);
  }
  Mat_Close(mat);
  const std::size_t rows = columns.empty() ? 0 : columns[0].size();
  for (std::size_t r = 0; r < rows; ++r) {
    t.rows.emplace_back();
    for (const auto& c : columns) t.rows.back().push_back(c[r]);
  }
  return t;
}

const char kAllFormats[] = " --set 'outputs.log={format: [csv, hdf5, mat]}'";

TEST(LogFormats, UnitsGroupsAndNames) {
  EXPECT_EQ(ColumnUnit("time"), "s");
  EXPECT_EQ(ColumnUnit("pa10.q.S1"), "rad");
  EXPECT_EQ(ColumnUnit("pa10.qd.W2"), "rad/s");
  EXPECT_EQ(ColumnUnit("pa10.tau.E1"), "N*m");
  EXPECT_EQ(ColumnUnit("jr3.Fz"), "N");
  EXPECT_EQ(ColumnUnit("jr3.Mx"), "N*m");
  EXPECT_EQ(ColumnUnit("controller.p_des.x"), "m");
  EXPECT_EQ(ColumnUnit("jr3.saturated"), "");
  EXPECT_EQ(ColumnGroup("pa10.q.S1"), "pa10.q");
  EXPECT_EQ(ColumnGroup("jr3.Fx"), "jr3");
  EXPECT_EQ(ColumnGroup("time"), "time");
  EXPECT_EQ(MatVariableName("pa10.q"), "pa10_q");
  EXPECT_EQ(MatVariableName("3d-cam.x"), "v3d_cam_x");
  EXPECT_EQ(MatVariableName(std::string(80, 'a')).size(), 63u);
}

TEST(LogFormats, HdfAndMatEqualCsvBitForBit) {
  TempDir tmp;
  const auto r = RunVlab("run scenes/pa10_reach -q --duration 3 --out '" + (tmp / "run") + "'" + kAllFormats);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const scene::CsvTable csv = scene::ReadCsvTable(tmp / "run/log.csv");
  ASSERT_EQ(csv.rows.size(), 1501u);  // t = 0 and 1500 periods of 2 ms: more than one HDF5 chunk
  ExpectSameBits(csv, ReadHdf5Log(tmp / "run/log.h5"));
  std::map<std::string, std::string> units;
  ExpectSameBits(csv, ReadMat(tmp / "run/log.mat", &units));
  EXPECT_EQ(units["pa10.q.S1"], "rad");
  EXPECT_EQ(units["time"], "s");
  EXPECT_FALSE(fs::exists(tmp / "run/.log.mat.part"));  // the file of compressed pieces is gone
}

TEST(LogFormats, ScenarioKeyRefusals) {
  const std::string run = "run scenes/pa10_reach -q --duration 0.01 --out /nonexistent/never --set ";
  auto r = RunVlab(run + "'outputs.log={format: [csv, parquet]}'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown log format 'parquet' (csv, mat, hdf5 or mcap)"), std::string::npos) << r.err;
  r = RunVlab(run + "'outputs.log={format: [hdf5, hdf5]}'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("'hdf5' listed twice"), std::string::npos) << r.err;
  r = RunVlab(run + "'outputs.log={formats: csv}'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("formats"), std::string::npos) << r.err;
}

// tests/node/read_mcap.mjs on a run folder (the MCAP reference reader): its output and exit code
ProcessResult ReadMcap(const std::string& run_dir) {
  TempDir tmp;
  const std::string cmd = "cd '" VLAB_SOURCE_DIR "/tests/node' && timeout 60 node read_mcap.mjs '" + run_dir + "' >'" +
                          (tmp / "out") + "' 2>&1";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadFile(tmp / "out"), ""};
}

// without the Node packages (./test.sh installs them) the MCAP tests are skipped, saying so
#define SKIP_WITHOUT_NODE_PACKAGES()                                                                                \
  if (!fs::exists(VLAB_SOURCE_DIR "/tests/node/node_modules/@mcap/core") || std::system("node -v >/dev/null 2>&1")) \
  GTEST_SKIP() << "no node or tests/node/node_modules (./test.sh installs them)"

const char kMcapRun[] =
    " --set 'outputs.log={format: [csv, mcap]}' --set 'outputs.poses={rate: 50}'"
    " --set 'outputs.images=[{camera: overview, width: 64, height: 48, every: 0.25}]'";

TEST(LogFormats, McapHoldsSignalsPosesAndFramesAndConvertWritesTheSameBytes) {
  SKIP_WITHOUT_NODE_PACKAGES();
  TempDir tmp;
  const std::string run = tmp / "run";
  auto r = RunVlab("run scenes/pa10_reach -q --duration 1 --out '" + run + "'" + kMcapRun);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  // the reference reader: every schema and message, signals bit for bit, /tf, frames (read_mcap.mjs)
  const ProcessResult read = ReadMcap(run);
  ASSERT_EQ(read.exit_code, 0) << read.out;
  EXPECT_NE(read.out.find("(501 rows on 3 devices, 51 /tf, 5 images)"), std::string::npos) << read.out;
  // convert from log.csv, poses.bin and the frames: the bytes the run wrote (whichever thread
  // handed the poses and frames over when, the file follows from its contents alone)
  fs::rename(run + "/log.mcap", tmp / "written.mcap");
  auto c = RunVlab("convert '" + run + "' --to mcap");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.out.find("log.mcap: written from"), std::string::npos) << c.out;
  EXPECT_EQ(ReadFile(run + "/log.mcap"), ReadFile(tmp / "written.mcap"));
  // refusals (an existing target: as every format's, ConvertWritesEachFormatAndRefuses): a
  // poses.bin cut short, a frame missing; nothing written
  fs::remove(run + "/log.mcap");
  fs::resize_file(run + "/poses.bin", fs::file_size(run + "/poses.bin") - 1);
  c = RunVlab("convert '" + run + "' --to mcap");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("poses.bin: 15095 bytes are not whole frames of 296"), std::string::npos) << c.err;
  fs::remove(run + "/poses.bin");
  fs::remove(run + "/overview/rgb_000001.png");
  c = RunVlab("convert '" + run + "' --to mcap");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("overview/rgb_000001.png: missing (frames.csv lists frame 1)"), std::string::npos) << c.err;
  EXPECT_FALSE(fs::exists(run + "/log.mcap"));
  for (const auto& e : fs::directory_iterator(run)) {
    EXPECT_NE(e.path().filename().string().rfind(".log.mcap", 0), 0u) << e.path();  // no temporary file left
  }
}

// the run's staging folder (PARENT/.vlab-PID-N) while it runs
std::string StagingFile(const std::string& parent, const std::string& name) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(parent, ec)) {
    if (entry.path().filename().string().rfind(".vlab-", 0) == 0) return (entry.path() / name).string();
  }
  return "";
}

// `vlab run scenes/pa10_reach` for 600 s into parent/run with the scenario overrides `sets`,
// stopped by SIGINT once its staged log.csv holds more than `bytes`; its wait status, and
// whether log.csv grew so far (false: SIGINT at the 120 s bound)
struct Interrupted {
  bool grew = false;
  int status = 0;
};
Interrupted RunUntilTheLogGrows(const std::string& parent, const std::vector<std::string>& sets, std::uintmax_t bytes) {
  fs::create_directories(parent);
  const std::string out = parent + "/run";
  std::vector<const char*> argv = {"vlab", "run", "scenes/pa10_reach", "-q", "--duration", "600", "--out", out.c_str()};
  for (const std::string& set : sets) argv.insert(argv.end(), {"--set", set.c_str()});
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(VLAB_SOURCE_DIR) != 0) ::_exit(126);
    ::freopen("/dev/null", "w", stdout);
    ::execv(VLAB_BINARY_DIR "/vlab", const_cast<char* const*>(argv.data()));
    ::_exit(127);
  }
  Interrupted r;
  r.grew = WaitUntil(
      [&] {
        std::error_code ec;
        const std::string csv = StagingFile(parent, "log.csv");
        return !csv.empty() && fs::file_size(csv, ec) > bytes && !ec;
      },
      120);
  ::kill(pid, SIGINT);
  ::waitpid(pid, &r.status, 0);
  return r;
}

TEST(LogFormats, SigintLeavesAValidHdf5OfEveryPeriod) {
  TempDir tmp;
  // SIGINT once log.csv holds a few blocks of rows (the HDF5 writer is at the same block)
  const Interrupted run = RunUntilTheLogGrows(tmp / "parent", {"outputs.log={format: [csv, hdf5]}"}, 1000000);
  ASSERT_TRUE(run.grew) << "log.csv never grew";
  ASSERT_TRUE(WIFEXITED(run.status));
  EXPECT_EQ(WEXITSTATUS(run.status), 1);  // interrupted
  const scene::CsvTable csv = scene::ReadCsvTable(tmp / "parent/run/log.csv");
  const scene::CsvTable h5 = ReadHdf5Log(tmp / "parent/run/log.h5");
  ASSERT_GT(csv.rows.size(), 1000u);
  ExpectSameBits(csv, h5);
  // every period from t = 0 on, none missing
  for (std::size_t r = 0; r < h5.rows.size(); ++r) ASSERT_NEAR(h5.rows[r][0], 0.002 * r, 1e-9) << "row " << r;
}

TEST(LogFormats, SigintLeavesAValidMcapOfEveryPeriod) {
  SKIP_WITHOUT_NODE_PACKAGES();
  TempDir tmp;
  // SIGINT once log.csv holds a few blocks of rows
  const Interrupted run =
      RunUntilTheLogGrows(tmp / "parent", {"outputs.log={format: [csv, mcap]}", "outputs.poses={rate: 50}"}, 300000);
  ASSERT_TRUE(run.grew) << "log.csv never grew";
  ASSERT_TRUE(WIFEXITED(run.status));
  EXPECT_EQ(WEXITSTATUS(run.status), 1);  // interrupted
  const scene::CsvTable csv = scene::ReadCsvTable(tmp / "parent/run/log.csv");
  ASSERT_GT(csv.rows.size(), 256u);
  // every period from t = 0 on, none missing, in log.csv; log.mcap holds them all (read_mcap.mjs)
  for (std::size_t r = 0; r < csv.rows.size(); ++r) ASSERT_NEAR(csv.rows[r][0], 0.002 * r, 1e-9) << "row " << r;
  const ProcessResult read = ReadMcap(tmp / "parent/run");
  ASSERT_EQ(read.exit_code, 0) << read.out;
  EXPECT_NE(read.out.find("(" + std::to_string(csv.rows.size()) + " rows on 3 devices"), std::string::npos) << read.out;
}

TEST(LogFormats, ConvertWritesEachFormatAndRefuses) {
  TempDir tmp;
  const std::string run = tmp / "run";
  const auto r = RunVlab("run scenes/pa10_reach -q --duration 0.5 --out '" + run + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const scene::CsvTable csv = scene::ReadCsvTable(run + "/log.csv");

  // csv -> hdf5 and mat, hdf5 -> csv in another folder: the same bits
  auto c = RunVlab("convert '" + run + "' --to hdf5");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  ExpectSameBits(csv, ReadHdf5Log(run + "/log.h5"));
  c = RunVlab("convert '" + run + "' --to mat");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.out.find("(MAT 5 (compressed))"), std::string::npos) << c.out;
  std::map<std::string, std::string> units;
  ExpectSameBits(csv, ReadMat(run + "/log.mat", &units));
  // the same rows give the same bytes (no date in the header)
  const std::string first = ReadFile(run + "/log.mat");
  c = RunVlab("convert '" + run + "' --to mat --force");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(ReadFile(run + "/log.mat"), first);
  const std::string other = tmp / "other";
  fs::create_directories(other);
  fs::copy_file(run + "/log.h5", other + "/log.h5");
  c = RunVlab("convert '" + other + "' --to csv");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(ReadFile(other + "/log.csv"), ReadFile(run + "/log.csv"));

  // an existing target: refused, replaced with --force only when vlab's list names it
  c = RunVlab("convert '" + run + "' --to hdf5");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("log.h5: exists (--force replaces it"), std::string::npos) << c.err;
  c = RunVlab("convert '" + run + "' --to hdf5 --force");
  EXPECT_EQ(c.exit_code, 0) << c.err;
  c = RunVlab("convert '" + other + "' --to csv --force");  // other/ has no list: its log.csv is the user's
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("vlab did not write it"), std::string::npos) << c.err;

  // malformed, a FIFO, no folder: the file and line named, nothing written
  const std::string bad = tmp / "bad";
  fs::create_directories(bad);
  WriteFile(bad + "/log.csv", "time,a\n0,1\n0.002,x\n");
  c = RunVlab("convert '" + bad + "' --to hdf5");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("log.csv:3: a: not a number: 'x'"), std::string::npos) << c.err;
  const std::string fifo = tmp / "fifo";
  fs::create_directories(fifo);
  ASSERT_EQ(::mkfifo((fifo + "/log.csv").c_str(), 0644), 0);
  c = RunVlab("convert '" + fifo + "' --to mat", 20);
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("log.csv"), std::string::npos) << c.err;
  c = RunVlab("convert '" + (tmp / "none") + "' --to mat");
  EXPECT_EQ(c.exit_code, 2);
  EXPECT_NE(c.err.find("not a folder"), std::string::npos) << c.err;
  for (const std::string& dir : {bad, fifo}) {
    std::vector<std::string> entries;
    for (const auto& e : fs::directory_iterator(dir)) entries.push_back(e.path().filename().string());
    EXPECT_EQ(entries, std::vector<std::string>{"log.csv"}) << dir;
  }
}

}  // namespace
}  // namespace vlab::lab::log_formats_test
