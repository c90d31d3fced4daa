#include "lab/outputs/lab_log.h"

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace vlab::lab {

namespace {

// log.csv: the header at open, each block formatted and flushed
class CsvSink : public LogSink {
 public:
  CsvSink(std::FILE* file, std::string path, std::size_t columns) : file_(file), path_(std::move(path)), n_(columns) {}
  ~CsvSink() override {
    if (file_) std::fclose(file_);
  }

  std::string WriteText(const std::string& text) {
    if (!header_error_.empty()) return header_error_;
    errno = 0;
    const bool ok = std::fwrite(text.data(), 1, text.size(), file_) == text.size() && std::fflush(file_) == 0;
    return ok ? "" : Error();
  }

  // the header, buffered: a failure shows at the first block or at Close, as any write's
  void WriteHeader(const std::string& text) {
    errno = 0;
    if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) header_error_ = Error();
  }

  std::string Write(const double* rows, int count) override {
    text_.clear();
    char buffer[32];
    for (int r = 0; r < count; ++r) {
      const double* row = rows + static_cast<std::size_t>(r) * n_;
      for (std::size_t c = 0; c < n_; ++c) {
        if (c) text_.push_back(',');
        const auto result = std::to_chars(buffer, buffer + sizeof(buffer), row[c]);
        text_.append(buffer, result.ptr);
      }
      text_.push_back('\n');
    }
    return WriteText(text_);
  }

  std::string Close() override {
    if (!file_) return "";
    errno = 0;
    const bool flushed = std::fflush(file_) == 0;
    std::string why = flushed ? "" : Error();
    errno = 0;
    if (std::fclose(file_) != 0 && why.empty()) why = Error();
    file_ = nullptr;
    return header_error_.empty() ? why : header_error_;
  }

 private:
  std::string Error() const { return "log '" + path_ + "': write failed: " + std::strerror(errno ? errno : EIO); }

  std::FILE* file_;
  std::string path_;
  std::size_t n_;
  std::string text_;
  std::string header_error_;
};

}  // namespace

std::string FormatDouble(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::unique_ptr<LogSink> OpenCsvSink(const std::string& path, const std::vector<std::string>& columns) {
  std::FILE* file = std::fopen(path.c_str(), "wbe");  // e: not inherited by a controller
  if (!file) throw std::runtime_error("log '" + path + "': cannot create file: " + std::strerror(errno));
  auto sink = std::make_unique<CsvSink>(file, path, columns.size());
  std::string header;
  for (std::size_t i = 0; i < columns.size(); ++i) header += (i ? "," : "") + columns[i];
  header += "\n";
  sink->WriteHeader(header);
  return sink;
}

std::unique_ptr<RunLog> RunLog::Open(const std::string& path, std::vector<std::string> columns) {
  std::vector<std::unique_ptr<LogSink>> sinks;
  sinks.push_back(OpenCsvSink(path, columns));
  return Open(std::move(sinks), path, std::move(columns));
}

std::unique_ptr<RunLog> RunLog::Open(std::vector<std::unique_ptr<LogSink>> sinks, std::string path,
                                     std::vector<std::string> columns) {
  return std::unique_ptr<RunLog>(new RunLog(std::move(sinks), std::move(path), std::move(columns)));
}

bool RunLog::Ring::Push(int block) {
  const int tail = tail_.load(std::memory_order_relaxed);
  const int next = (tail + 1) % (kBlocks + 1);
  if (next == head_.load(std::memory_order_acquire)) return false;  // full
  slots_[tail] = block;
  tail_.store(next, std::memory_order_release);
  return true;
}

bool RunLog::Ring::Pop(int* block) {
  const int head = head_.load(std::memory_order_relaxed);
  if (head == tail_.load(std::memory_order_acquire)) return false;  // empty
  *block = slots_[head];
  head_.store((head + 1) % (kBlocks + 1), std::memory_order_release);
  return true;
}

RunLog::RunLog(std::vector<std::unique_ptr<LogSink>> sinks, std::string path, std::vector<std::string> columns)
    : sinks_(std::move(sinks)), path_(std::move(path)), columns_(std::move(columns)) {
  blocks_.resize(kBlocks);
  rows_.assign(kBlocks, 0);
  for (int b = 0; b < kBlocks; ++b) {
    blocks_[b].resize(static_cast<std::size_t>(kRowsPerBlock) * columns_.size());
    if (b > 0) free_.Push(b);
  }
  current_ = 0;
  sem_init(&work_, 0, 0);
  sem_init(&freed_, 0, 0);
  writer_ = std::thread(&RunLog::WriterLoop, this);
}

RunLog::~RunLog() {
  try {
    Close();
  } catch (...) {
    // destructor: the error was already reported by an explicit Close(), or is moot
  }
  sem_destroy(&work_);
  sem_destroy(&freed_);
}

void RunLog::Append(const double* row) {
  std::memcpy(blocks_[current_].data() + static_cast<std::size_t>(rows_in_current_) * columns_.size(), row,
              columns_.size() * sizeof(double));
  if (++rows_in_current_ == kRowsPerBlock) Submit();
}

void RunLog::Submit() {
  rows_[current_] = rows_in_current_;
  full_.Push(current_);  // never full: kBlocks + 1 slots for kBlocks blocks
  sem_post(&work_);
  rows_in_current_ = 0;
  if (free_.Pop(&current_)) return;
  // back-pressure: the writer is kBlocks blocks behind; wait for it, never drop a row
  const auto start = std::chrono::steady_clock::now();
  while (!free_.Pop(&current_)) {
    while (sem_wait(&freed_) != 0 && errno == EINTR) {
    }
  }
  ++waits_;
  wait_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void RunLog::Fail(const std::string& why) {
  if (failed_.load(std::memory_order_relaxed)) return;  // the first failure is the one that tells
  error_ = why;
  failed_.store(true, std::memory_order_release);
}

void RunLog::WriterLoop() {
  for (;;) {
    while (sem_wait(&work_) != 0 && errno == EINTR) {
    }
    int block = 0;
    if (!full_.Pop(&block)) {
      if (closing_.load(std::memory_order_acquire)) return;
      continue;
    }
    // after a failed write nothing more is written: each file ends where the failure left it
    for (const std::unique_ptr<LogSink>& sink : sinks_) {
      if (failed_.load(std::memory_order_relaxed)) break;
      const std::string why = sink->Write(blocks_[block].data(), rows_[block]);
      if (!why.empty()) Fail(why);
    }
    free_.Push(block);
    sem_post(&freed_);
  }
}

void RunLog::Close() {
  if (closed_) return;
  closed_ = true;
  if (rows_in_current_ > 0) {
    rows_[current_] = rows_in_current_;
    full_.Push(current_);
    sem_post(&work_);
    rows_in_current_ = 0;
  }
  closing_.store(true, std::memory_order_release);
  sem_post(&work_);
  writer_.join();
  // every file is closed whatever failed: what was written stays readable
  for (const std::unique_ptr<LogSink>& sink : sinks_) {
    const std::string why = sink->Close();
    if (!why.empty()) Fail(why);
  }
  if (failed()) throw std::runtime_error(error());
}

std::string RunLog::error() const { return failed() ? error_ : ""; }

}  // namespace vlab::lab
