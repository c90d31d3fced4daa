// CsvLog: what is appended reads back bit for bit, across many writer blocks;
// FormatDouble round-trips; write failures name the file and the error, and
// show in failed() as soon as the writer meets them. (OutputDir: output_test.cc.)
#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "test_util.h"

namespace vlab::lab::log_test {
namespace {

using vlab::testing::Bits;

namespace fs = std::filesystem;
using vlab::testing::Entries;
using vlab::testing::Lines;
using vlab::testing::ReadFile;
using vlab::testing::SplitCsv;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

// Parses with strtod and requires the whole field to be consumed.
double Parse(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  EXPECT_EQ(*end, '\0') << "'" << text << "' not fully parsed";
  return v;
}

TEST(CsvLogTest, HeaderAndManyRowsReadBackExactly) {
  const std::vector<std::string> columns = {"time", "a.q", "b.tau", "c"};
  // awkward values: shortest decimals that are not exact, tiny and huge, signed zero, denormals
  const std::vector<double> awkward = {0.1,
                                       1.0 / 3.0,
                                       1e-300,
                                       -0.0,
                                       1e300,
                                       4.9406564584124654e-324,
                                       2.2250738585072009e-308,
                                       -1.7976931348623157e308,
                                       42.0,
                                       -7.0,
                                       0.0,
                                       9007199254740993.0,
                                       123456789.0,
                                       2.0 / 3.0,
                                       -1e-5};
  std::mt19937_64 rng(20240611);
  std::normal_distribution<double> normal(0.0, 1e3);
  constexpr int kRows = 5000;  // 19 full blocks of 256 rows and a partial one of 136
  std::vector<double> written;
  TempDir dir;
  {
    auto log = CsvLog::Open(dir / "log.csv", columns);
    EXPECT_EQ(log->columns(), columns);
    std::vector<double> row(columns.size());
    for (int r = 0; r < kRows; ++r) {
      row[0] = r * 0.002;
      row[1] = awkward[r % awkward.size()];
      row[2] = normal(rng);
      row[3] = awkward[(r * 7 + 3) % awkward.size()] * (r % 2 ? -1 : 1);
      log->Append(row.data());
      written.insert(written.end(), row.begin(), row.end());
    }
    log->Close();
  }
  const std::string text = ReadFile(dir / "log.csv");
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  const std::vector<std::string> lines = Lines(text);
  ASSERT_EQ(lines.size(), static_cast<std::size_t>(kRows + 1));
  EXPECT_EQ(lines[0], "time,a.q,b.tau,c");
  for (int r = 0; r < kRows; ++r) {
    const std::vector<std::string> fields = SplitCsv(lines[r + 1]);
    ASSERT_EQ(fields.size(), columns.size()) << "row " << r;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const double expected = written[r * columns.size() + c];
      ASSERT_EQ(Bits(Parse(fields[c])), Bits(expected)) << "row " << r << " col " << c << ": '" << fields[c] << "'";
    }
  }
  EXPECT_EQ(SplitCsv(lines[4])[0], "0.006");  // row 3: 3 * 0.002 in shortest form
}

TEST(CsvLogTest, DestructorFlushesPendingRows) {
  TempDir dir;
  {
    auto log = CsvLog::Open(dir / "log.csv", {"x"});
    for (int r = 0; r < 300; ++r) {
      const double v = r;
      log->Append(&v);
    }
  }  // no Close(): the destructor writes the partial block
  const auto lines = Lines(ReadFile(dir / "log.csv"));
  ASSERT_EQ(lines.size(), 301u);
  EXPECT_EQ(lines[300], "299");
}

TEST(CsvLogTest, FormatDoubleRoundTripsAndIsShortest) {
  EXPECT_EQ(FormatDouble(0.1), "0.1");
  EXPECT_EQ(FormatDouble(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(FormatDouble(-0.0), "-0");
  EXPECT_EQ(FormatDouble(13.0), "13");
  EXPECT_EQ(FormatDouble(0.002 * 3), "0.006");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  for (int i = 0; i < 100000; ++i) {
    // every finite bit pattern is fair game, plus ordinary magnitudes
    std::uint64_t b = rng();
    double v;
    std::memcpy(&v, &b, sizeof v);
    if (!std::isfinite(v)) v = uniform(rng);
    if (i % 2) v = uniform(rng);
    const std::string s = FormatDouble(v);
    ASSERT_EQ(Bits(Parse(s)), Bits(v)) << s;
    ASSERT_LE(s.size(), 24u) << s;  // shortest round-trip form of a double is at most 24 characters
  }
}

TEST(CsvLogTest, UncreatableFileThrowsNamingPath) {
  TempDir dir;
  const std::string path = dir / "no/such/folder/log.csv";
  try {
    CsvLog::Open(path, {"time"});
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  // a folder where the file should be
  fs::create_directory(dir / "taken.csv");
  EXPECT_THROW(CsvLog::Open(dir / "taken.csv", {"time"}), std::runtime_error);
}

TEST(CsvLogTest, WriteErrorThrowsOnCloseNamingPathAndError) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  auto log = CsvLog::Open("/dev/full", {"time", "x"});
  EXPECT_FALSE(log->failed());
  EXPECT_EQ(log->error(), "");
  const double row[2] = {1.0, 2.0};
  for (int r = 0; r < 1000; ++r) log->Append(row);
  try {
    log->Close();
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    // /dev/full answers every write with ENOSPC
    EXPECT_EQ(std::string(e.what()), "log '/dev/full': write failed: " + std::string(std::strerror(ENOSPC)));
  }
  EXPECT_TRUE(log->failed());
}

// the writer flushes each block it writes: a failure shows in failed() before Close, while the
// step loop goes on appending (the loop reads the flag every period and stops the run)
TEST(CsvLogTest, WriteErrorShowsBeforeClose) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  auto log = CsvLog::Open("/dev/full", {"time", "x"});
  const double row[2] = {1.0, 2.0};
  // back-pressure: kBlocks blocks of kRowsPerBlock rows, one being filled; the kBlocks-th full
  // block waits for the writer to hand one back, which it does after writing (and failing) it
  for (int r = 0; r < (CsvLog::kBlocks + 2) * CsvLog::kRowsPerBlock; ++r) log->Append(row);
  EXPECT_TRUE(log->failed());
  EXPECT_NE(log->error().find(std::strerror(ENOSPC)), std::string::npos) << log->error();
  EXPECT_THROW(log->Close(), std::runtime_error);
}

}  // namespace
}  // namespace vlab::lab::log_test
