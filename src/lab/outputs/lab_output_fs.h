// The file-system parts of output folders (lab_output.h): folder locks, the
// list of entries a run wrote (kept in the marker file), the entries of a
// folder that vlab did not write, renames that never replace, and the removal
// of staging folders left by runs that died. Not a public header.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace vlab::lab::output_fs {

/// An exclusive flock(2) on a folder, held while the object lives. A file
/// system that refuses locks (some network ones) gives an object that holds
/// nothing (held() false); callers go on without it.
class FolderLock {
 public:
  enum class Wait { kBlock, kTry };
  FolderLock(const std::string& folder, Wait wait);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  bool held() const { return held_; }
  /// True when kTry found the lock taken by another open file (a live run).
  bool busy() const { return busy_; }

 private:
  int fd_ = -1;
  bool held_ = false;
  bool busy_ = false;
};

/// Every entry under `folder` as a path relative to it, a folder with a
/// trailing '/', sorted; the marker file at its top left out. Symbolic links
/// are entries, never followed.
std::vector<std::string> ListEntries(const std::string& folder);

/// The list of entries in `folder`'s marker file; nullopt when it has no
/// marker, or a marker without a list (a vlab older than the list, or a run
/// that could not finish writing it).
std::optional<std::set<std::string>> ReadManifest(const std::string& folder);

/// Writes `folder`'s marker file: what it is, the run that wrote it (`run`, an
/// id no other run has), and (with `entries`) the list of everything the run
/// wrote. Through a temporary file and a rename, so a failed write leaves the
/// previous marker. "" on success, else the errno text.
std::string WriteMarker(const std::string& folder, const std::string& run, const std::vector<std::string>* entries);

/// The run id in `folder`'s marker ("" when none).
std::string ReadRunId(const std::string& folder);

/// An id for a new run: the pid, the time in ns and a count.
std::string NewRunId();

/// The entries under `folder` (a folder with a marker) that vlab did not write,
/// relative to it, folders with a trailing '/', sorted: anything neither in its
/// list nor inside a nested output folder of vlab's (`vlab render`'s default
/// out/NAME/render/CAMERA) that is whole by its own list. At most `limit`.
std::vector<std::string> ForeignEntries(const std::string& folder, std::size_t limit);

/// rename(2) that fails with EEXIST where `to` exists (renameat2
/// RENAME_NOREPLACE; where the file system lacks it, a check and a rename).
/// 0, or the errno.
int RenameNoReplace(const std::string& from, const std::string& to);

/// A staging folder's name: ".vlab-PID-N".
std::string StagingName(long pid, unsigned n);
/// True for a name StagingName() makes.
bool IsStagingName(std::string_view name);

/// Removes the staging folders in `parent` whose run is dead: a name of
/// StagingName(), a marker without a list, or nothing in it yet (a finished
/// run's list is never removed), and no lock held on it (a live run holds one
/// while it lives). Call with `parent` locked. Returns their paths.
std::vector<std::string> RemoveStaleStaging(const std::string& parent);

}  // namespace vlab::lab::output_fs
