#include "lab/lab_output.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "core/core_errors.h"

namespace vlab::lab {

namespace fs = std::filesystem;

namespace {

// "" when vlab may replace `target` (absent, an empty folder, or a folder with the marker); else why not
std::string NotReplaceable(const fs::path& target) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(target, ec);
  if (ec || status.type() == fs::file_type::not_found) return "";
  if (status.type() != fs::file_type::directory) return "exists and is not a folder";
  if (fs::exists(target / kOutputMarker, ec)) return "";
  if (fs::is_empty(target, ec) && !ec) return "";
  return std::string("exists and is not an output folder of vlab's (it has no ") + kOutputMarker +
         "): vlab replaces only the folders it wrote; give another --out, or move it away";
}

}  // namespace

std::unique_ptr<OutputDir> OutputDir::Create(const std::string& final_dir) {
  const fs::path target = fs::path(final_dir).lexically_normal();
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string leaf = target.filename().string();
  if (leaf.empty() || leaf == "." || leaf == "..") {
    throw InputError("output folder '" + final_dir + "': not a folder name");
  }
  const std::string refused = NotReplaceable(target);
  if (!refused.empty()) throw InputError("output folder '" + target.string() + "': " + refused);
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InputError("output folder '" + parent.string() + "': " + ec.message());
  const fs::path staging = parent / ("." + leaf + ".partial-" + std::to_string(::getpid()));
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw InputError("output folder '" + staging.string() + "': " + ec.message());
  std::ofstream marker(staging / kOutputMarker);
  marker << "This folder was written by vlab. vlab replaces it (vlab run --out) only while this file is here.\n";
  marker.close();
  if (!marker) {
    fs::remove_all(staging, ec);
    throw InputError("output folder '" + staging.string() + "': cannot write " + kOutputMarker);
  }
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
  // something not vlab's appeared there during the run: keep the run's files where they are
  const std::string refused = NotReplaceable(target);
  if (!refused.empty()) {
    done_ = true;
    throw std::runtime_error("output folder '" + final_dir_ + "': " + refused + "; this run's files are in '" +
                             staging_ + "'");
  }
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
