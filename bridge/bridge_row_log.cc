#include "bridge/bridge_row_log.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace vlab::bridge::program {

std::unique_ptr<RowLog> RowLog::Open(const std::string& path, std::vector<LogColumn> columns, std::size_t capacity) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw std::runtime_error(path + ": " + std::strerror(errno));
  return std::unique_ptr<RowLog>(new RowLog(file, path, std::move(columns), capacity));
}

RowLog::RowLog(std::FILE* file, std::string path, std::vector<LogColumn> columns, std::size_t capacity)
    : file_(file), path_(std::move(path)), columns_(std::move(columns)), capacity_(capacity),
      ring_(capacity * columns_.size()) {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    std::fputs(columns_[i].name.c_str(), file_);
    std::fputc(i + 1 < columns_.size() ? ',' : '\n', file_);
  }
  ::sem_init(&rows_, 0, 0);
  writer_ = std::thread([this] { WriterMain(); });
}

RowLog::~RowLog() { Finish(); }

bool RowLog::Finish() {
  if (!file_) return ok();
  stop_.store(true, std::memory_order_release);
  ::sem_post(&rows_);
  writer_.join();
  ::sem_destroy(&rows_);
  if (std::fclose(file_) != 0 && ok()) error_ = errno, failed_.store(true, std::memory_order_release);
  file_ = nullptr;
  return ok();
}

void RowLog::Add(const double* values) {
  if (!file_) return;
  const std::size_t head = head_.load(std::memory_order_relaxed);
  if (head - tail_.load(std::memory_order_acquire) == capacity_) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  std::copy(values, values + columns_.size(), ring_.begin() + static_cast<long>((head % capacity_) * columns_.size()));
  head_.store(head + 1, std::memory_order_release);
  ::sem_post(&rows_);
}

std::string RowLog::error() const { return ok() ? std::string() : path_ + ": " + std::strerror(error_); }

void RowLog::WriterMain() {
  // normal priority whatever the loop's (a thread inherits its maker's policy)
  sched_param normal{};
  ::pthread_setschedparam(::pthread_self(), SCHED_OTHER, &normal);
  char number[64];
  for (;;) {
    ::sem_wait(&rows_);
    const bool stopping = stop_.load(std::memory_order_acquire);
    const std::size_t head = head_.load(std::memory_order_acquire);
    for (std::size_t row = tail_.load(std::memory_order_relaxed); row != head; ++row) {
      const double* v = ring_.data() + (row % capacity_) * columns_.size();
      for (std::size_t i = 0; i < columns_.size() && !failed_.load(std::memory_order_relaxed); ++i) {
        const char end = i + 1 < columns_.size() ? ',' : '\n';
        std::snprintf(number, sizeof number, "%.*f%c", columns_[i].decimals, v[i], end);
        if (std::fputs(number, file_) == EOF) error_ = errno, failed_.store(true, std::memory_order_release);
      }
      tail_.store(row + 1, std::memory_order_release);
    }
    if (stopping && tail_.load(std::memory_order_relaxed) == head_.load(std::memory_order_acquire)) break;
  }
  if (std::fflush(file_) == EOF && !failed_.load()) error_ = errno, failed_.store(true, std::memory_order_release);
}

}  // namespace vlab::bridge::program
