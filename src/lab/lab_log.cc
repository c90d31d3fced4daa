#include "lab/lab_log.h"

#include <charconv>
#include <cerrno>
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

CsvLog::CsvLog(std::FILE* file, std::string path, std::vector<std::string> columns)
    : file_(file), path_(std::move(path)), columns_(std::move(columns)) {
  std::string header;
  for (std::size_t i = 0; i < columns_.size(); ++i) header += (i ? "," : "") + columns_[i];
  header += "\n";
  if (std::fwrite(header.data(), 1, header.size(), file_) != header.size()) write_errno_ = errno ? errno : EIO;
  blocks_.resize(kBlocks);
  for (auto& block : blocks_) {
    block.resize(static_cast<std::size_t>(kRowsPerBlock) * columns_.size());
    free_.push_back(&block);
  }
  current_ = free_.back();
  free_.pop_back();
  writer_ = std::thread(&CsvLog::WriterLoop, this);
}

CsvLog::~CsvLog() {
  try {
    Close();
  } catch (...) {
    // destructor: the error was already reported by an explicit Close(), or is moot
  }
}

void CsvLog::Append(const double* row) {
  std::memcpy(current_->data() + static_cast<std::size_t>(rows_in_current_) * columns_.size(), row,
              columns_.size() * sizeof(double));
  if (++rows_in_current_ == kRowsPerBlock) Submit();
}

void CsvLog::Submit() {
  std::unique_lock<std::mutex> lock(mutex_);
  full_.emplace_back(current_, rows_in_current_);
  cv_.notify_all();
  // back-pressure: wait for a free block only if the writer fell 8 blocks behind
  cv_.wait(lock, [this] { return !free_.empty(); });
  current_ = free_.back();
  free_.pop_back();
  rows_in_current_ = 0;
}

void CsvLog::WriterLoop() {
  std::string text;
  const std::size_t n = columns_.size();
  for (;;) {
    std::pair<std::vector<double>*, int> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return closing_ || !full_.empty(); });
      if (full_.empty()) return;
      job = full_.front();
      full_.pop_front();
    }
    text.clear();
    char buffer[32];
    for (int r = 0; r < job.second; ++r) {
      const double* row = job.first->data() + static_cast<std::size_t>(r) * n;
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
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(job.first);
    cv_.notify_all();
  }
}

void CsvLog::Close() {
  if (closed_) return;
  closed_ = true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (rows_in_current_ > 0) full_.emplace_back(current_, rows_in_current_);
    rows_in_current_ = 0;
    closing_ = true;
    cv_.notify_all();
  }
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
