// The run log: one CSV row of named signals per control period.
//
// The step loop copies each row into a preallocated block; full blocks go to a
// writer thread that formats them (shortest round-trip decimal, std::to_chars)
// and writes the file, so formatting costs the step loop nothing but a copy.
// The same values always give the same bytes: logs of identical runs are
// identical files. The writer flushes each block it writes, so a write that
// fails (disk full, a file size limit) shows in failed() at once.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vlab::lab {

class CsvLog {
 public:
  /// Creates the file and writes the header line. Throws std::runtime_error
  /// naming the path when it cannot be written.
  static std::unique_ptr<CsvLog> Open(const std::string& path, std::vector<std::string> columns);
  ~CsvLog();
  CsvLog(const CsvLog&) = delete;
  CsvLog& operator=(const CsvLog&) = delete;

  const std::vector<std::string>& columns() const { return columns_; }
  /// Appends one row of columns().size() values. Never allocates after Open.
  void Append(const double* row);
  /// Writes what is pending and closes the file. Throws std::runtime_error on
  /// a write error (error()). Called by the destructor if not called before.
  void Close();
  /// True once a write failed (lock-free: the step loop asks every period).
  bool failed() const { return write_errno_.load(std::memory_order_acquire) != 0; }
  /// "log 'PATH': write failed: ERRNO TEXT" once failed(), else "".
  std::string error() const;

 private:
  static constexpr int kRowsPerBlock = 256;
  static constexpr int kBlocks = 8;

  CsvLog(std::FILE* file, std::string path, std::vector<std::string> columns);
  void WriterLoop();
  void Submit();

  std::FILE* file_;
  std::string path_;
  std::vector<std::string> columns_;
  std::vector<std::vector<double>> blocks_;
  std::vector<double>* current_ = nullptr;
  int rows_in_current_ = 0;
  // shared with the writer thread
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<std::vector<double>*, int>> full_;
  std::vector<std::vector<double>*> free_;
  bool closing_ = false;
  std::atomic<int> write_errno_{0};  // the errno of the first failed write (0: none)
  std::thread writer_;
  bool closed_ = false;
};

/// Formats a double as the shortest decimal that reads back to the same value.
std::string FormatDouble(double value);

}  // namespace vlab::lab
