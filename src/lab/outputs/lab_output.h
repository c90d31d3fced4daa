// Output folders that appear whole or not at all, never lose a run, and never
// delete a user's files.
//
// A run writes into a hidden staging folder in the parent of its output
// folder, PARENT/.vlab-PID-N (short: any name the file system takes for the
// output folder works), and renames it into place when everything is written.
// An error or a MuJoCo abort removes the staging folder (an interrupted run,
// or one whose writes failed, is moved into place for the periods that ran),
// so a reader never sees a half-written out/NAME/; a previous complete
// out/NAME/ stays until the new one replaces it.
//
// vlab replaces only what it wrote: every output folder carries a marker file
// (kOutputMarker) that lists every entry the run wrote. An existing folder is
// replaced only when it is empty, or has the marker and nothing the list does
// not name (a nested output folder of vlab's, whole by its own list, counts as
// vlab's). Anything else is refused (InputError naming the entries, before
// anything is written), so `--out` can never delete a user's files.
//
// Two runs into one folder both keep their results: a run replaces only the
// folder that was there when it began. When another run (or anyone) put a
// folder there meanwhile, or files were added to it, this run's folder goes to
// the first free sibling DIR.2, DIR.3, ... (a rename that never replaces), and
// note() says so. Create and Commit hold an flock on the parent folder, so
// vlab's own runs never interleave their renames.
//
// A run holds an flock on its staging folder while it lives. Create removes the
// staging folders in the same parent whose runs died (SIGKILL, a crash): no
// lock held on them and no list in their marker.
#pragma once

#include <memory>
#include <string>

namespace vlab::lab {

namespace output_fs {
class FolderLock;
}

/// The file that marks a folder as an output folder vlab wrote, and lists what it wrote.
inline constexpr const char* kOutputMarker = ".vlab-output";

/// Adds `name` (a path relative to `folder`) to the list of a finished output
/// folder, for a file vlab writes into it after the run (vlab golden's
/// golden_log.csv), so that the next run into it may replace it. "" on success,
/// else why not (no list there; the marker could not be written).
std::string AddToOutputList(const std::string& folder, const std::string& name);

class OutputDir {
 public:
  /// Creates the staging folder (and the parent of final_dir) with the marker
  /// in it, after removing the staging folders of dead runs there. A trailing
  /// '/' is dropped ("results/" is "results"). Throws InputError naming the
  /// folder for an empty name, ".", "..", when it cannot be created there, or
  /// when final_dir exists and vlab may not replace it (a file; a folder with
  /// entries and no marker; entries its marker does not list, named in the
  /// message); nothing is written then.
  static std::unique_ptr<OutputDir> Create(const std::string& final_dir);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Path of a file inside the staging folder.
  std::string File(const std::string& name) const;
  /// Lists the staging folder's entries in its marker and puts it in place:
  /// at final_dir() when that holds nothing or the folder that was there at
  /// Create (still replaceable), else at the first free sibling DIR.N; where
  /// no name is free, it stays where it is. Returns the folder that holds the
  /// run's files now; note() says why when that is not final_dir(). Never
  /// throws: the files are not lost, whatever happened there meanwhile.
  std::string Commit();
  /// "" when Commit put the files at final_dir() with their list; else one
  /// line: where they went and why, or that their list could not be written.
  const std::string& note() const { return note_; }
  /// Removes the staging folder (no-op after Commit).
  void Discard();
  const std::string& final_dir() const { return final_dir_; }
  /// The staging folder (no trailing '/').
  const std::string& staging_dir() const { return staging_; }

 private:
  OutputDir(std::string final_dir, std::string staging);
  // the folder's new place, under the parent's lock: final_dir, a sibling, or the staging folder
  std::string Place();
  std::string final_dir_;
  std::string parent_;
  std::string staging_;
  std::unique_ptr<output_fs::FolderLock> staging_lock_;  // held while the run lives
  std::string run_;                                      // this run's id, in its marker
  // the folder at final_dir at Create, the one this run may replace: its inode and its
  // marker's run id (an inode number can come back for another folder; a run id cannot)
  bool had_target_ = false;
  unsigned long target_device_ = 0, target_inode_ = 0;
  std::string target_run_;
  bool done_ = false;
  std::string committed_;  // where Commit put the files
  std::string set_aside_;  // the replaced folder, removed once the lock is released
  std::string note_;
};

}  // namespace vlab::lab
