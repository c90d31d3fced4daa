#include "lab/outputs/lab_output.h"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>
#include <set>
#include <system_error>
#include <vector>

#include "core/core_errors.h"
#include "lab/outputs/lab_output_fs.h"

namespace vlab::lab {

namespace fs = std::filesystem;
using output_fs::FolderLock;

namespace {

// the foreign entries a refusal names; the rest are counted as "and more"
constexpr std::size_t kEntriesShown = 10;

// staging and set-aside names of this process: .vlab-PID-N, N counting up
std::atomic<unsigned> g_names{0};

std::string NewName(const std::string& parent) {
  return (fs::path(parent) / output_fs::StagingName(::getpid(), ++g_names)).string();
}

// the folder final_dir names; a trailing '/' dropped ("results/" is "results")
fs::path Target(const std::string& final_dir) {
  if (final_dir.empty()) throw InputError("output folder '': an empty name (give a folder, e.g. --out results)");
  fs::path target = fs::path(final_dir).lexically_normal();
  while (target.filename().empty() && target.has_relative_path()) target = target.parent_path();
  const std::string leaf = target.filename().string();
  if (leaf.empty() || leaf == "." || leaf == "..") {
    throw InputError("output folder '" + final_dir + "': not a folder name");
  }
  return target;
}

// "" when vlab may replace `target` (absent, an empty folder, or one with the marker and nothing
// its list does not name); else why not, naming what vlab did not write
std::string NotReplaceable(const fs::path& target) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(target, ec);
  if (status.type() == fs::file_type::not_found) return "";
  if (ec) return "cannot be read: " + ec.message();
  if (status.type() != fs::file_type::directory) return "exists and is not a folder";
  if (fs::is_empty(target, ec) && !ec) return "";
  if (!fs::exists(target / kOutputMarker, ec)) {
    return std::string("exists and is not an output folder of vlab's (it has no ") + kOutputMarker +
           "): vlab replaces only the folders it wrote; give another --out, or move it away";
  }
  if (!output_fs::ReadManifest(target.string())) {
    return std::string("has a ") + kOutputMarker +
           " without the list of what vlab wrote there (written by an older vlab, or by a run that could not "
           "finish writing it): vlab cannot tell files added to it from its own; move it away or delete it";
  }
  const std::vector<std::string> foreign = output_fs::ForeignEntries(target.string(), kEntriesShown + 1);
  if (foreign.empty()) return "";
  std::string names;
  for (std::size_t i = 0; i < foreign.size() && i < kEntriesShown; ++i) names += (i ? ", " : "") + foreign[i];
  if (foreign.size() > kEntriesShown) names += ", and more";
  return "holds entries vlab did not write: " + names +
         "; vlab replaces only what it wrote: move them out of it, or give another --out";
}

void Refuse(const fs::path& target) {
  const std::string why = NotReplaceable(target);
  if (!why.empty()) throw InputError("output folder '" + target.string() + "': " + why);
}

}  // namespace

std::string AddToOutputList(const std::string& folder, const std::string& name) {
  std::optional<std::set<std::string>> list = output_fs::ReadManifest(folder);
  if (!list) return "'" + folder + "' has no list of what vlab wrote in its " + kOutputMarker;
  list->insert(name);
  const std::vector<std::string> entries(list->begin(), list->end());
  const std::string error = output_fs::WriteMarker(folder, output_fs::ReadRunId(folder), &entries);
  return error.empty() ? "" : "'" + folder + "/" + kOutputMarker + "': " + error;
}

std::unique_ptr<OutputDir> OutputDir::Create(const std::string& final_dir) {
  const fs::path target = Target(final_dir);
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  Refuse(target);  // before anything is written, parent folders included
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InputError("output folder '" + parent.string() + "': " + ec.message());

  // under the parent's lock: no other run of vlab renames there meanwhile
  const FolderLock parent_lock(parent.string(), FolderLock::Wait::kBlock);
  Refuse(target);
  output_fs::RemoveStaleStaging(parent.string());
  std::string staging;
  for (int tries = 0;; ++tries) {
    staging = NewName(parent.string());
    if (::mkdir(staging.c_str(), 0777) == 0) break;
    if (errno != EEXIST || tries == 100) {
      throw InputError("output folder '" + target.string() + "': cannot create '" + staging +
                       "': " + std::strerror(errno));
    }
  }
  std::unique_ptr<OutputDir> out(new OutputDir(target.string(), staging));  // (removes it if what follows throws)
  out->parent_ = parent.string();
  out->staging_lock_ = std::make_unique<FolderLock>(staging, FolderLock::Wait::kTry);
  out->run_ = output_fs::NewRunId();
  const std::string error = output_fs::WriteMarker(staging, out->run_, nullptr);
  if (!error.empty()) {
    throw InputError("output folder '" + staging + "': cannot write " + kOutputMarker + ": " + error);
  }
  // the folder this run may replace: the one there now (another one there at Commit is kept)
  struct stat status {};
  if (::lstat(target.c_str(), &status) == 0) {
    out->had_target_ = true;
    out->target_device_ = status.st_dev;
    out->target_inode_ = status.st_ino;
    out->target_run_ = output_fs::ReadRunId(target.string());
  }
  return out;
}

OutputDir::OutputDir(std::string final_dir, std::string staging)
    : final_dir_(std::move(final_dir)), staging_(std::move(staging)) {}

OutputDir::~OutputDir() { Discard(); }

std::string OutputDir::File(const std::string& name) const { return (fs::path(staging_) / name).string(); }

std::string OutputDir::Place() {
  const FolderLock lock(parent_, FolderLock::Wait::kBlock);
  std::string why;
  // a few tries: something may come and go at final_dir between a look and a rename
  for (int attempt = 0; attempt < 8 && why.empty(); ++attempt) {
    struct stat status {};
    if (::lstat(final_dir_.c_str(), &status) != 0) {
      const int rc = errno == ENOENT ? output_fs::RenameNoReplace(staging_, final_dir_) : errno;
      if (rc == 0) return final_dir_;
      if (rc != EEXIST && rc != ENOTEMPTY) why = std::strerror(rc);
      continue;
    }
    std::error_code ec;
    if (S_ISDIR(status.st_mode) && fs::is_empty(final_dir_, ec) && !ec) {
      // an empty folder holds nobody's files: rename(2) replaces it
      if (::rename(staging_.c_str(), final_dir_.c_str()) == 0) return final_dir_;
      if (errno != EEXIST && errno != ENOTEMPTY) why = std::strerror(errno);
      continue;
    }
    const bool same = had_target_ && status.st_dev == target_device_ && status.st_ino == target_inode_ &&
                      output_fs::ReadRunId(final_dir_) == target_run_;
    if (!same) {
      const std::string refused = NotReplaceable(final_dir_);
      why = refused.empty() ? "another run put its folder there while this one ran"
                            : "appeared while this run ran, and " + refused;
      break;
    }
    const std::string refused = NotReplaceable(final_dir_);
    if (!refused.empty()) {
      why = refused;
      break;
    }
    // the folder this run began with, still vlab's alone: set aside, then replaced
    const std::string aside = NewName(parent_);
    if (::rename(final_dir_.c_str(), aside.c_str()) != 0) {
      if (errno != ENOENT) why = "cannot be replaced: " + std::string(std::strerror(errno));
      continue;
    }
    const int rc = output_fs::RenameNoReplace(staging_, final_dir_);
    if (rc == 0) {
      set_aside_ = aside;
      return final_dir_;
    }
    ::rename(aside.c_str(), final_dir_.c_str());  // the previous result back (rename: the lock keeps vlab out)
    why = "cannot be replaced: " + std::string(std::strerror(rc));
  }
  if (why.empty()) why = "it changed under every try to rename this run's folder there";
  // the first free sibling, taken by a rename that never replaces
  for (int n = 2; n < 1000; ++n) {
    const std::string sibling = final_dir_ + "." + std::to_string(n);
    const int rc = output_fs::RenameNoReplace(staging_, sibling);
    if (rc == 0) {
      note_ = "output folder '" + final_dir_ + "': " + why + "; this run's files are in '" + sibling + "'";
      return sibling;
    }
    if (rc != EEXIST && rc != ENOTEMPTY) break;  // (a name too long for the file system: no sibling fits)
  }
  note_ = "output folder '" + final_dir_ + "': " + why + "; no sibling name is free: this run's files are in '" +
          staging_ + "'";
  return staging_;
}

std::string OutputDir::Commit() {
  if (done_) return committed_;
  done_ = true;
  // the list: everything in the staging folder now is this run's (an external controller's files too)
  const std::vector<std::string> entries = output_fs::ListEntries(staging_);
  const std::string unlisted = output_fs::WriteMarker(staging_, run_, &entries);
  committed_ = Place();
  staging_lock_.reset();
  std::error_code ec;
  if (!set_aside_.empty()) fs::remove_all(set_aside_, ec);
  if (!unlisted.empty()) {
    note_ += std::string(note_.empty() ? "" : "; ") + "output folder '" + committed_ + "': the list of its files in " +
             kOutputMarker + " could not be written (" + unlisted + "), so vlab will not replace it: delete it by hand";
  }
  return committed_;
}

void OutputDir::Discard() {
  if (done_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  staging_lock_.reset();
  done_ = true;
}

}  // namespace vlab::lab
