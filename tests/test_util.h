// Helpers shared by tests: temporary folders, files, running the vlab binary.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

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

/// The 64 bits of a double: two values compare equal here only when they are
/// the same to the bit (signed zeros and NaN payloads told apart).
inline std::uint64_t Bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

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

/// Lines of a text, without their newlines.
inline std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream s(text);
  std::string line;
  while (std::getline(s, line)) lines.push_back(line);
  return lines;
}

/// Fields of one CSV line (no quoting); a trailing comma gives an empty last field.
inline std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  std::string field;
  while (std::getline(s, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

/// Names of the entries of a folder.
inline std::set<std::string> Entries(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

struct ProcessResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// Runs the built vlab binary with `args` (shell words) from the source root,
/// with a time limit; captures stdout and stderr. With `signal` (e.g. "INT"),
/// that signal ends the run at the time limit and the exit code is vlab's own.
inline ProcessResult RunVlab(const std::string& args, int timeout_s = 120, const std::string& signal = "") {
  TempDir tmp;
  const std::string how = signal.empty() ? "timeout " : "timeout --preserve-status -s " + signal + " ";
  const std::string cmd = "cd '" VLAB_SOURCE_DIR "' && " + how + std::to_string(timeout_s) +
                          " '" VLAB_BINARY_DIR "/vlab' " + args + " >'" + (tmp / "out") + "' 2>'" + (tmp / "err") +
                          "' </dev/null";
  const int status = std::system(cmd.c_str());
  ProcessResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(tmp / "out");
  r.err = ReadFile(tmp / "err");
  return r;
}

/// Runs a command line (a shell's) to its end: its exit status (-1: not a
/// normal exit) and, into `output`, what it wrote to stdout and stderr.
inline int RunCapture(const std::string& command, std::string* output) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) output->append(buffer, n);
  const int status = ::pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace vlab::testing
