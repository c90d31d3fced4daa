// Helpers shared by tests: temporary folders, files, running the vlab binary.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace vlab::testing {

/// A fresh folder under the system temp folder, removed on destruction.
class TempDir {
 public:
  TempDir() {
    std::string templ = (std::filesystem::temp_directory_path() / "vlab-test-XXXXXX").string();
    path_ = ::mkdtemp(templ.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return (std::filesystem::path(path_) / name).string(); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

inline void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct ProcessResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// Runs the built vlab binary with `args` (shell words) from the source root,
/// with a time limit; captures stdout and stderr.
inline ProcessResult RunVlab(const std::string& args, int timeout_s = 120) {
  TempDir tmp;
  const std::string cmd = "cd '" VLAB_SOURCE_DIR "' && timeout " + std::to_string(timeout_s) + " '" VLAB_BINARY_DIR
                          "/vlab' " + args + " >'" + (tmp / "out") + "' 2>'" + (tmp / "err") + "' </dev/null";
  const int status = std::system(cmd.c_str());
  ProcessResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(tmp / "out");
  r.err = ReadFile(tmp / "err");
  return r;
}

}  // namespace vlab::testing
