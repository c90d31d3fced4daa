// CsvLog's hand-over when the writer cannot write (src/lab/outputs/lab_log.h): the log
// goes to a FIFO nobody reads, so the writer thread blocks in its first write
// and the step loop fills every block. The append that finds no free block
// waits (counted) and loses no row: once a reader drains the FIFO, every row
// arrives in order. The reader starts only when the appending thread is seen
// asleep (its state in /proc), so the wait is certain, not a race.
#include "lab/outputs/lab_log.h"

#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.h"

namespace vlab::lab::log_handover_test {
namespace {

// the scheduler state of thread `tid` of this process ('R' running, 'S' sleeping, ...)
char ThreadState(long tid) {
  std::ifstream in("/proc/self/task/" + std::to_string(tid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t paren = text.rfind(')');
  return paren != std::string::npos && paren + 2 < text.size() ? text[paren + 2] : '?';
}

TEST(CsvLogHandover, WaitsForAStalledWriterAndLosesNoRow) {
  vlab::testing::TempDir dir;
  const std::string fifo = dir.path() + "/log.fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // 100 columns of 7-character values: a block is 256 rows of 800 bytes, far over a pipe's 64 KiB
  constexpr int kColumns = 100;
  std::vector<std::string> columns;
  for (int c = 0; c < kColumns; ++c) columns.push_back("c" + std::to_string(c));
  // one row more than every block holds: the append that completes the last block waits
  constexpr int kRows = CsvLog::kBlocks * CsvLog::kRowsPerBlock + 1;

  const long appender = syscall(SYS_gettid);
  std::atomic<bool> last_block{false};
  std::string received;
  std::thread reader([&] {
    std::FILE* in = std::fopen(fifo.c_str(), "rb");  // opens once the log opens its end
    ASSERT_NE(in, nullptr);
    // drain only while the appending thread sleeps in the last block's hand-over
    while (!last_block.load() || ThreadState(appender) != 'S') {
    }
    char buffer[65536];
    std::size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, in)) > 0) received.append(buffer, n);
    std::fclose(in);
  });
  auto log = CsvLog::Open(fifo, columns);
  std::vector<double> row(kColumns);
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kColumns; ++c) row[c] = 100000 + r % 900000 + c;  // 6 digits, exact in decimal
    if (r == CsvLog::kBlocks * CsvLog::kRowsPerBlock - 1) last_block = true;
    log->Append(row.data());
  }
  log->Close();
  reader.join();
  EXPECT_EQ(log->waits(), 1);
  EXPECT_GT(log->wait_s(), 0.0);
  EXPECT_FALSE(log->failed());
  // every row, in order
  const std::vector<std::string> lines = vlab::testing::Lines(received);
  ASSERT_EQ(lines.size(), static_cast<std::size_t>(kRows) + 1);
  for (int r = 0; r < kRows; ++r) {
    const std::string first = FormatDouble(100000 + r % 900000) + ",";
    ASSERT_EQ(lines[r + 1].compare(0, first.size(), first), 0) << "row " << r << ": " << lines[r + 1];
  }
}

}  // namespace
}  // namespace vlab::lab::log_handover_test
