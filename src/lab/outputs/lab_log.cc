#include "lab/outputs/lab_log.h"

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace vlab::lab {

std::string FormatDouble(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::unique_ptr<CsvLog> CsvLog::Open(const std::string& path, std::vector<std::string> columns) {
  std::FILE* file = std::fopen(path.c_str(), "wbe");  // e: not inherited by a controller
  if (!file) throw std::runtime_error("log '" + path + "': cannot create file: " + std::strerror(errno));
  return std::unique_ptr<CsvLog>(new CsvLog(file, path, std::move(columns)));
}

bool CsvLog::Ring::Push(int block) {
  const int tail = tail_.load(std::memory_order_relaxed);
  const int next = (tail + 1) % (kBlocks + 1);
  if (next == head_.load(std::memory_order_acquire)) return false;  // full
  slots_[tail] = block;
  tail_.store(next, std::memory_order_release);
  return true;
}

bool CsvLog::Ring::Pop(int* block) {
  const int head = head_.load(std::memory_order_relaxed);
  if (head == tail_.load(std::memory_order_acquire)) return false;  // empty
  *block = slots_[head];
  head_.store((head + 1) % (kBlocks + 1), std::memory_order_release);
  return true;
}

CsvLog::CsvLog(std::FILE* file, std::string path, std::vector<std::string> columns)
    : file_(file), path_(std::move(path)), columns_(std::move(columns)) {
  std::string header;
  for (std::size_t i = 0; i < columns_.size(); ++i) header += (i ? "," : "") + columns_[i];
  header += "\n";
  if (std::fwrite(header.data(), 1, header.size(), file_) != header.size()) write_errno_ = errno ? errno : EIO;
  blocks_.resize(kBlocks);
  rows_.assign(kBlocks, 0);
  for (int b = 0; b < kBlocks; ++b) {
    blocks_[b].resize(static_cast<std::size_t>(kRowsPerBlock) * columns_.size());
    if (b > 0) free_.Push(b);
  }
  current_ = 0;
  sem_init(&work_, 0, 0);
  sem_init(&freed_, 0, 0);
  writer_ = std::thread(&CsvLog::WriterLoop, this);
}

CsvLog::~CsvLog() {
  try {
    Close();
  } catch (...) {
    // destructor: the error was already reported by an explicit Close(), or is moot
  }
  sem_destroy(&work_);
  sem_destroy(&freed_);
}

void CsvLog::Append(const double* row) {
  std::memcpy(blocks_[current_].data() + static_cast<std::size_t>(rows_in_current_) * columns_.size(), row,
              columns_.size() * sizeof(double));
  if (++rows_in_current_ == kRowsPerBlock) Submit();
}

void CsvLog::Submit() {
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

void CsvLog::WriterLoop() {
  std::string text;
  const std::size_t n = columns_.size();
  for (;;) {
    while (sem_wait(&work_) != 0 && errno == EINTR) {
    }
    int block = 0;
    if (!full_.Pop(&block)) {
      if (closing_.load(std::memory_order_acquire)) return;
      continue;
    }
    text.clear();
    char buffer[32];
    for (int r = 0; r < rows_[block]; ++r) {
      const double* row = blocks_[block].data() + static_cast<std::size_t>(r) * n;
      for (std::size_t c = 0; c < n; ++c) {
        if (c) text.push_back(',');
        const auto result = std::to_chars(buffer, buffer + sizeof(buffer), row[c]);
        text.append(buffer, result.ptr);
      }
      text.push_back('\n');
    }
    // after a failed write nothing more is written: the file ends where the failure left it
    if (write_errno_.load(std::memory_order_relaxed) == 0) {
      errno = 0;
      const bool ok = std::fwrite(text.data(), 1, text.size(), file_) == text.size() && std::fflush(file_) == 0;
      if (!ok) write_errno_.store(errno ? errno : EIO, std::memory_order_release);
    }
    free_.Push(block);
    sem_post(&freed_);
  }
}

void CsvLog::Close() {
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
  errno = 0;
  if (std::fflush(file_) != 0 && write_errno_ == 0) write_errno_ = errno ? errno : EIO;
  if (std::fclose(file_) != 0 && write_errno_ == 0) write_errno_ = errno ? errno : EIO;
  if (failed()) throw std::runtime_error(error());
}

std::string CsvLog::error() const {
  const int e = write_errno_.load(std::memory_order_acquire);
  return e == 0 ? "" : "log '" + path_ + "': write failed: " + std::strerror(e);
}

}  // namespace vlab::lab
