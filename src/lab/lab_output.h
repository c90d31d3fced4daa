// Output folders that appear whole or not at all.
//
// A run writes into a hidden staging folder beside its output folder
// (out/.NAME.partial-PID) and renames it into place when everything is written.
// An error or a MuJoCo abort removes the staging folder (an interrupted run is
// written whole, for the periods that ran), so a reader never sees a
// half-written out/NAME/; a previous complete out/NAME/ stays until the new one
// replaces it.
//
// vlab replaces only what it wrote: every output folder carries a marker file
// (kOutputMarker), and an existing folder is replaced only when it has the
// marker or is empty. Anything else at that path is refused (InputError,
// before anything is written), so `--out` can never delete a user's folder.
#pragma once

#include <memory>
#include <string>

namespace vlab::lab {

/// The file that marks a folder as an output folder vlab wrote.
inline constexpr const char* kOutputMarker = ".vlab-output";

class OutputDir {
 public:
  /// Creates the staging folder (and the parent of final_dir) with the marker
  /// in it. Throws InputError naming the folder when it cannot be created
  /// there, or when final_dir exists and is not an output folder of vlab's (a
  /// file, or a folder with entries and no marker); nothing is written then.
  static std::unique_ptr<OutputDir> Create(const std::string& final_dir);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Path of a file inside the staging folder.
  std::string File(const std::string& name) const;
  /// Replaces final_dir with the staging folder. When final_dir became a
  /// folder vlab may not replace meanwhile, the run's files stay in the
  /// staging folder and the error (std::runtime_error) names it.
  void Commit();
  /// Removes the staging folder (no-op after Commit).
  void Discard();
  const std::string& final_dir() const { return final_dir_; }

 private:
  OutputDir(std::string final_dir, std::string staging);
  std::string final_dir_;
  std::string staging_;
  bool done_ = false;
};

}  // namespace vlab::lab
