#include "lab/lab_output.h"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "core/core_errors.h"

namespace vlab::lab {

namespace fs = std::filesystem;

std::unique_ptr<OutputDir> OutputDir::Create(const std::string& final_dir) {
  const fs::path target = fs::path(final_dir).lexically_normal();
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string leaf = target.filename().string();
  if (leaf.empty() || leaf == "." || leaf == "..") {
    throw InputError("output folder '" + final_dir + "': not a folder name");
  }
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InputError("output folder '" + parent.string() + "': " + ec.message());
  const fs::path staging = parent / ("." + leaf + ".partial-" + std::to_string(::getpid()));
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw InputError("output folder '" + staging.string() + "': " + ec.message());
  return std::unique_ptr<OutputDir>(new OutputDir(target.string(), staging.string()));
}

OutputDir::OutputDir(std::string final_dir, std::string staging)
    : final_dir_(std::move(final_dir)), staging_(std::move(staging)) {}

OutputDir::~OutputDir() { Discard(); }

std::string OutputDir::File(const std::string& name) const { return (fs::path(staging_) / name).string(); }

void OutputDir::Commit() {
  if (done_) return;
  std::error_code ec;
  const fs::path target(final_dir_);
  // move any previous result aside, put the new one in place, then delete the old
  const fs::path old = target.parent_path() / ("." + target.filename().string() + ".old-" + std::to_string(::getpid()));
  const bool had_old = fs::exists(target);
  if (had_old) {
    fs::remove_all(old, ec);
    fs::rename(target, old, ec);
    if (ec) throw std::runtime_error("output folder '" + final_dir_ + "': cannot replace: " + ec.message());
  }
  fs::rename(staging_, target, ec);
  if (ec) {
    if (had_old) fs::rename(old, target, ec);
    throw std::runtime_error("output folder '" + final_dir_ + "': cannot create: " + ec.message());
  }
  done_ = true;
  if (had_old) fs::remove_all(old, ec);
}

void OutputDir::Discard() {
  if (done_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  done_ = true;
}

}  // namespace vlab::lab
