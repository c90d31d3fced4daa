// A controller's CSV log written off its loop (bridge/bridge_row_log.h): rows come out
// in order with each column's decimals, a writer the disk holds up costs rows (counted),
// never the loop's time, and a failed write is reported by Finish.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "bridge/bridge_row_log.h"

namespace vlab::bridge::program::row_log_test {
namespace {

std::string TempPath(const char* name) { return ::testing::TempDir() + name + std::to_string(::getpid()); }

TEST(RowLog, WritesTheHeaderAndEveryRowWithItsColumnsDecimals) {
  const std::string path = TempPath("row_log_rows_");
  auto log = RowLog::Open(path, {{"time", 3}, {"z", 6}, {"rpm", 1}});
  for (int k = 0; k < 3; ++k) {
    const double row[] = {k * 0.01, 1.0 / 3.0 + k, k == 1 ? NAN : 1234.56};
    log->Add(row);
  }
  ASSERT_TRUE(log->Finish()) << log->error();
  EXPECT_EQ(log->dropped(), 0);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "time,z,rpm\n0.000,0.333333,1234.6\n0.010,1.333333,nan\n0.020,2.333333,1234.6\n");
  std::remove(path.c_str());
}

TEST(RowLog, AWriterTheDiskHoldsUpLosesRowsNotTheLoopsTime) {
  // a FIFO nobody reads yet: the writer blocks once the pipe is full
  const std::string path = TempPath("row_log_fifo_");
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  const int reader = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(reader, 0);
  auto log = RowLog::Open(path, {{"n", 0}}, 16);
  constexpr int kRows = 100000;
  for (int n = 0; n < kRows; ++n) {
    const double row[] = {static_cast<double>(n)};
    log->Add(row);  // (never blocks: the test would hang here otherwise)
  }
  const long dropped = log->dropped();
  EXPECT_GT(dropped, 0);  // a 64 KiB pipe holds a few thousand rows, not 100,000
  bool finished = false;
  std::thread finish([&] { finished = log->Finish(); });
  // read it all: the rows that were kept, in order
  ::fcntl(reader, F_SETFL, 0);
  std::string text;
  char buf[65536];
  for (ssize_t n; (n = ::read(reader, buf, sizeof buf)) > 0;) text.append(buf, static_cast<std::size_t>(n));
  finish.join();
  ::close(reader);
  std::remove(path.c_str());
  EXPECT_TRUE(finished) << log->error();
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "n");
  long rows = 0, last = -1;
  for (; std::getline(lines, line); ++rows) {
    const long n = std::stol(line);
    EXPECT_GT(n, last);
    last = n;
  }
  EXPECT_EQ(rows, kRows - dropped);
}

TEST(RowLog, AFailedWriteIsReportedByFinish) {
  auto log = RowLog::Open("/dev/full", {{"t", 3}});
  for (int k = 0; k < 10; ++k) {
    const double row[] = {k * 1.0};
    log->Add(row);
  }
  EXPECT_FALSE(log->Finish());
  EXPECT_NE(log->error().find("/dev/full: No space left on device"), std::string::npos) << log->error();
}

TEST(RowLog, AFileThatCannotBeOpenedIsNamed) {
  try {
    RowLog::Open("/nonexistent-dir/log.csv", {{"t", 3}});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent-dir/log.csv: No such file or directory");
  }
}

}  // namespace
}  // namespace vlab::bridge::program::row_log_test
