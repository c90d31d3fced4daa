// A controller program's CSV log, written off its control loop.
//
// A realtime controller that writes its log from its loop waits whenever the
// kernel makes writers wait: beside a process writing a large file, the page
// cache's dirty-page throttling (balance_dirty_pages) holds every writer for up
// to 200 ms, and a 100 Hz loop then misses its periods. RowLog's Add copies one
// row of numbers into a ring and returns without a system call but a semaphore
// post; its own thread, at normal priority, formats the rows and writes them.
//
// Threading: Add and Finish from one thread (the loop's); the writer is internal.
// A full ring (the writer held up for capacity rows) drops the row and counts it.
// Finish (or the destructor) writes what is queued and closes the file.
#pragma once

#include <semaphore.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace vlab::bridge::program {

/// A column of the log: its header name and the decimals its numbers are printed with
/// ("%.Nf"; NaN prints as "nan").
struct LogColumn {
  std::string name;
  int decimals = 6;
};

class RowLog {
 public:
  /// Creates (truncates) `path`, writes the header line and starts the writer.
  /// Throws std::runtime_error naming the file when it cannot be opened.
  static std::unique_ptr<RowLog> Open(const std::string& path, std::vector<LogColumn> columns,
                                      std::size_t capacity = 16384);
  ~RowLog();
  RowLog(const RowLog&) = delete;
  RowLog& operator=(const RowLog&) = delete;

  /// Queues one row: columns().size() numbers. Never blocks.
  void Add(const double* values);
  /// Writes what is queued, stops the writer and closes the file; ok() after. Further
  /// calls, and Add after it, do nothing.
  bool Finish();
  /// Rows lost to a full ring so far.
  long dropped() const { return dropped_.load(std::memory_order_relaxed); }
  /// False once a write failed (the writer then stops writing); error() says why.
  bool ok() const { return !failed_.load(std::memory_order_acquire); }
  std::string error() const;
  const std::vector<LogColumn>& columns() const { return columns_; }

 private:
  RowLog(std::FILE* file, std::string path, std::vector<LogColumn> columns, std::size_t capacity);
  void WriterMain();

  std::FILE* file_;  // nullptr once finished
  std::string path_;
  std::vector<LogColumn> columns_;
  std::size_t capacity_;              // rows
  std::vector<double> ring_;          // capacity_ rows of columns_.size() numbers
  std::atomic<std::size_t> head_{0};  // rows added (the loop's)
  std::atomic<std::size_t> tail_{0};  // rows written (the writer's)
  std::atomic<long> dropped_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> failed_{false};
  int error_ = 0;  // errno of the failed write (set before failed_)
  sem_t rows_;
  std::thread writer_;
};

}  // namespace vlab::bridge::program
