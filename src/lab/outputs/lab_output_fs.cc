#include "lab/outputs/lab_output_fs.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "lab/outputs/lab_output.h"

namespace vlab::lab::output_fs {

namespace fs = std::filesystem;

namespace {

constexpr const char* kStagingPrefix = ".vlab-";
constexpr const char* kMarkerTemp = ".vlab-output.tmp";
constexpr const char* kMarkerNote =
    "This folder was written by vlab. vlab replaces it (vlab run --out) only while this file is here and "
    "lists every entry in the folder: a file added to the folder makes vlab refuse to replace it.";

bool AllDigits(std::string_view text) {
  if (text.empty()) return false;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

// the children of `dir`, sorted by name (so that messages list them in a stable order)
std::vector<fs::directory_entry> Children(const fs::path& dir, std::error_code& ec) {
  std::vector<fs::directory_entry> children;
  fs::directory_iterator it(dir, ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) children.push_back(*it);
  std::sort(children.begin(), children.end(),
            [](const fs::directory_entry& a, const fs::directory_entry& b) { return a.path() < b.path(); });
  return children;
}

// true when `dir` holds nothing, or only the marker's temporary file
bool OnlyMarkerTemp(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    if (it->path().filename() != kMarkerTemp) return false;
  }
  return !ec;
}

bool IsFolder(const fs::directory_entry& entry) {
  std::error_code ec;
  return entry.symlink_status(ec).type() == fs::file_type::directory;
}

// what under `dir` is neither in `manifest` (paths relative to the manifest's folder, `rel`
// the prefix of dir's entries in it) nor inside a nested output folder that is whole by its own
void Walk(const fs::path& dir, const std::set<std::string>& manifest, const std::string& rel, const std::string& shown,
          bool top, std::size_t limit, std::vector<std::string>* out) {
  std::error_code ec;
  const std::vector<fs::directory_entry> children = Children(dir, ec);
  if (ec) {
    out->push_back((shown.empty() ? "." : shown) + " (cannot be read: " + ec.message() + ")");
    return;
  }
  for (const fs::directory_entry& child : children) {
    if (out->size() >= limit) return;
    const std::string name = child.path().filename().string();
    if (top && (name == kOutputMarker || name == kMarkerTemp)) continue;
    if (!IsFolder(child)) {
      if (!manifest.count(rel + name)) out->push_back(shown + name);
      continue;
    }
    if (manifest.count(rel + name + "/")) {
      Walk(child.path(), manifest, rel + name + "/", shown + name + "/", false, limit, out);
    } else if (const auto nested = ReadManifest(child.path().string())) {
      Walk(child.path(), *nested, "", shown + name + "/", true, limit, out);
    } else {
      // a folder the list does not name: what is in it (an empty one holds nobody's files)
      Walk(child.path(), manifest, rel + name + "/", shown + name + "/", false, limit, out);
    }
  }
}

}  // namespace

FolderLock::FolderLock(const std::string& folder, Wait wait) {
  fd_ = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) return;
  const int how = LOCK_EX | (wait == Wait::kTry ? LOCK_NB : 0);
  int rc;
  do {
    rc = ::flock(fd_, how);  // (a stop signal, installed without SA_RESTART, interrupts a wait)
  } while (rc != 0 && errno == EINTR);
  held_ = rc == 0;
  busy_ = rc != 0 && errno == EWOULDBLOCK;
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // (closing the file releases the lock)
}

std::vector<std::string> ListEntries(const std::string& folder) {
  std::vector<std::string> entries;
  std::error_code ec;
  fs::recursive_directory_iterator it(folder, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const std::string rel = it->path().lexically_relative(folder).generic_string();
    if (it.depth() == 0 && (rel == kOutputMarker || rel == kMarkerTemp)) continue;
    entries.push_back(rel + (IsFolder(*it) ? "/" : ""));
  }
  std::sort(entries.begin(), entries.end());
  return entries;
}

namespace {

// the marker's JSON (null when there is none, or it is not JSON)
nlohmann::json ReadMarker(const std::string& folder) {
  std::ifstream in(fs::path(folder) / kOutputMarker);
  if (!in) return nullptr;
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json marker = nlohmann::json::parse(text.str(), nullptr, false);
  return marker.is_object() ? marker : nlohmann::json(nullptr);
}

}  // namespace

std::string ReadRunId(const std::string& folder) {
  const nlohmann::json marker = ReadMarker(folder);
  return marker.is_object() && marker.contains("run") && marker["run"].is_string() ? marker["run"].get<std::string>()
                                                                                   : "";
}

std::string NewRunId() {
  static std::atomic<unsigned> count{0};
  const auto ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  return std::to_string(::getpid()) + "-" + std::to_string(ns) + "-" + std::to_string(++count);
}

std::optional<std::set<std::string>> ReadManifest(const std::string& folder) {
  const nlohmann::json marker = ReadMarker(folder);
  if (!marker.is_object() || !marker.contains("entries") || !marker["entries"].is_array()) {
    return std::nullopt;
  }
  std::set<std::string> entries;
  for (const nlohmann::json& entry : marker["entries"]) {
    if (entry.is_string()) entries.insert(entry.get<std::string>());
  }
  return entries;
}

std::string WriteMarker(const std::string& folder, const std::string& run, const std::vector<std::string>* entries) {
  nlohmann::json marker = {{"written_by", "vlab"}, {"note", kMarkerNote}, {"run", run}};
  if (entries) marker["entries"] = *entries;
  // (invalid UTF-8 in a file name a controller chose is replaced, not thrown about)
  const std::string text = marker.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  const fs::path temp = fs::path(folder) / kMarkerTemp;
  std::FILE* file = std::fopen(temp.c_str(), "wbe");
  if (!file) return std::strerror(errno);
  int error = 0;
  if (std::fwrite(text.data(), 1, text.size(), file) != text.size()) error = errno;
  if (std::fclose(file) != 0 && error == 0) error = errno;
  if (error == 0 && std::rename(temp.c_str(), (fs::path(folder) / kOutputMarker).c_str()) != 0) error = errno;
  if (error != 0) {
    std::remove(temp.c_str());
    return std::strerror(error);
  }
  return "";
}

std::vector<std::string> ForeignEntries(const std::string& folder, std::size_t limit) {
  std::vector<std::string> foreign;
  Walk(folder, ReadManifest(folder).value_or(std::set<std::string>{}), "", "", true, limit, &foreign);
  return foreign;
}

int RenameNoReplace(const std::string& from, const std::string& to) {
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return 0;
  if (errno != EINVAL && errno != ENOSYS) return errno;
  // a file system without RENAME_NOREPLACE: vlab's own runs are kept apart by the folder lock
  struct stat status {};
  if (::lstat(to.c_str(), &status) == 0) return EEXIST;
  return ::rename(from.c_str(), to.c_str()) == 0 ? 0 : errno;
}

std::string StagingName(long pid, unsigned n) { return kStagingPrefix + std::to_string(pid) + "-" + std::to_string(n); }

bool IsStagingName(std::string_view name) {
  const std::string_view prefix(kStagingPrefix);
  if (name.substr(0, prefix.size()) != prefix) return false;
  const std::size_t dash = name.find('-', prefix.size());
  return dash != std::string_view::npos && AllDigits(name.substr(prefix.size(), dash - prefix.size())) &&
         AllDigits(name.substr(dash + 1));
}

std::vector<std::string> RemoveStaleStaging(const std::string& parent) {
  // the names first, without a path made for every entry (a sweep's folder holds many)
  std::vector<std::string> candidates;
  if (DIR* dir = ::opendir(parent.c_str())) {
    while (const dirent* entry = ::readdir(dir)) {
      if (IsStagingName(entry->d_name)) candidates.emplace_back(entry->d_name);
    }
    ::closedir(dir);
  }
  std::vector<std::string> removed;
  for (const std::string& name : candidates) {
    const fs::path path = fs::path(parent) / name;
    std::error_code ec;
    if (fs::symlink_status(path, ec).type() != fs::file_type::directory) continue;
    // a run killed between making its folder and writing the marker left it empty (or with the
    // marker's temporary file alone); any other folder without a marker is not one vlab staged
    const bool marked = fs::exists(path / kOutputMarker, ec);
    if (!marked && !OnlyMarkerTemp(path)) continue;
    if (marked && ReadManifest(path.string())) continue;  // a finished run's files kept there: never removed
    const FolderLock lock(path.string(), FolderLock::Wait::kTry);
    if (!lock.held()) continue;  // its run lives (or this file system has no locks: then left alone)
    fs::remove_all(path, ec);
    if (!ec) removed.push_back(path.string());
  }
  return removed;
}

}  // namespace vlab::lab::output_fs
