// Output folders that appear whole or not at all.
//
// A run writes into a hidden staging folder beside its output folder
// (out/.NAME.partial-PID) and renames it into place when everything is written.
// An error, a MuJoCo abort or an interrupt removes the staging folder, so a
// reader never sees a half-written out/NAME/; a previous complete out/NAME/
// stays until the new one replaces it.
#pragma once

#include <memory>
#include <string>

namespace vlab::lab {

class OutputDir {
 public:
  /// Creates the staging folder (and the parent of final_dir). Throws
  /// InputError naming the folder when it cannot be created there.
  static std::unique_ptr<OutputDir> Create(const std::string& final_dir);
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Path of a file inside the staging folder.
  std::string File(const std::string& name) const;
  /// Replaces final_dir with the staging folder.
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
