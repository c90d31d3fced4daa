// The run log: one row of named signals per control period, written as CSV
// (log.csv) and, by choice, HDF5 and MATLAB .mat (lab_log_formats.h).
//
// The step loop copies each row into a preallocated block; full blocks go to a
// writer thread that hands them to every format's LogSink (CSV: shortest
// round-trip decimal, std::to_chars) and writes the files, so formatting costs
// the step loop nothing but a copy.
// The same values always give the same bytes: logs of identical runs are
// identical files.
//
// The hand-over takes no lock: full and free blocks pass through two
// single-producer single-consumer rings, and the writer sleeps on a semaphore
// the step loop posts. A realtime control thread therefore never waits on a
// lock the normal-priority writer holds (the writer may be preempted, or wait
// for the disk, at any point). It waits only when the writer has fallen
// kBlocks blocks behind (the disk took nothing for that long: 4 s of a 1 kHz
// run): a row is never dropped, and the wait is counted (waits(), wait_s()).
// The writer flushes each block it writes, so a write that fails (disk full, a
// file size limit) shows in failed() at once, and a file holds every whole
// block written so far.
#pragma once

#include <semaphore.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace vlab::lab {

/// One file format of the log. The writer thread calls Write for each block
/// of rows and Close once at the end; nothing else calls them.
class LogSink {
 public:
  virtual ~LogSink() = default;
  /// Appends `count` rows of columns().size() values (row-major) and flushes
  /// them to the file. "" on success, else one line naming the file and the
  /// error; after a failure the sink is not written again.
  virtual std::string Write(const double* rows, int count) = 0;
  /// Completes and closes the file. "" on success, else why not (as Write).
  virtual std::string Close() = 0;
};

/// The CSV sink: a header line of column names, then one line per row of
/// shortest round-trip decimals. Throws std::runtime_error naming the path
/// when the file cannot be created.
std::unique_ptr<LogSink> OpenCsvSink(const std::string& path, const std::vector<std::string>& columns);

class RunLog {
 public:
  /// Creates the CSV file `path` and writes the header line. Throws
  /// std::runtime_error naming the path when it cannot be written.
  static std::unique_ptr<RunLog> Open(const std::string& path, std::vector<std::string> columns);
  /// A log that writes each block into every sink (at least one), in order;
  /// `path` names the log in error(). Never throws.
  static std::unique_ptr<RunLog> Open(std::vector<std::unique_ptr<LogSink>> sinks, std::string path,
                                      std::vector<std::string> columns);
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  const std::vector<std::string>& columns() const { return columns_; }
  /// Appends one row of columns().size() values. Never allocates or locks
  /// after Open; waits only when the writer is kBlocks blocks behind.
  void Append(const double* row);
  /// Writes what is pending and closes the file. Throws std::runtime_error on
  /// a write error (error()). Called by the destructor if not called before.
  void Close();
  /// How often, and how long in all (s), Append waited for the writer.
  long waits() const { return waits_; }
  double wait_s() const { return wait_s_; }
  /// True once a write failed (lock-free: the step loop asks every period).
  bool failed() const { return failed_.load(std::memory_order_acquire); }
  /// The first sink's error once failed() (CSV: "log 'PATH': write failed:
  /// ERRNO TEXT"), else "".
  std::string error() const;

  /// Rows a block holds, and blocks in all.
  static constexpr int kRowsPerBlock = 256;
  static constexpr int kBlocks = 16;

 private:
  // a single-producer single-consumer ring of block indices
  class Ring {
   public:
    bool Push(int block);
    bool Pop(int* block);

   private:
    int slots_[kBlocks + 1] = {};
    std::atomic<int> head_{0};  // next to pop (consumer)
    std::atomic<int> tail_{0};  // next to push (producer)
  };

  RunLog(std::vector<std::unique_ptr<LogSink>> sinks, std::string path, std::vector<std::string> columns);
  void WriterLoop();
  void Submit();
  void Fail(const std::string& why);

  std::vector<std::unique_ptr<LogSink>> sinks_;  // used by the writer thread only, then by Close
  std::string path_;
  std::vector<std::string> columns_;
  std::vector<std::vector<double>> blocks_;
  std::vector<int> rows_;  // rows in each block, set before it is handed over
  int current_ = 0;
  int rows_in_current_ = 0;
  long waits_ = 0;
  double wait_s_ = 0;
  // shared with the writer thread, lock-free
  Ring full_;    // step loop -> writer
  Ring free_;    // writer -> step loop
  sem_t work_;   // posted once per full block, and once to close
  sem_t freed_;  // posted once per block given back
  std::atomic<bool> closing_{false};
  std::string error_;  // the first failure, set before failed_ (release)
  std::atomic<bool> failed_{false};
  std::thread writer_;
  bool closed_ = false;
};

/// The log as it was first named: a CSV-only RunLog.
using CsvLog = RunLog;

/// Formats a double as the shortest decimal that reads back to the same value.
std::string FormatDouble(double value);

}  // namespace vlab::lab
