// Runs the real vlab-kinsim executable for a test: fork/exec with its stdout on
// a pipe, wait for its start line, stop it with SIGINT and collect its report.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

namespace vlab::testing {

class KinsimProcess {
 public:
  /// Starts VLAB_BINARY_DIR/vlab-kinsim with `args` (plus --port 0, from the
  /// source root) and waits up to timeout_s for its start line. ok() tells.
  explicit KinsimProcess(std::vector<std::string> args, double timeout_s = 20) {
    int fds[2];
    if (::pipe(fds) != 0) return;
    args.insert(args.begin(), VLAB_BINARY_DIR "/vlab-kinsim");
    args.push_back("--port");
    args.push_back("0");
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(fds[1], STDOUT_FILENO);
      ::close(fds[0]);
      ::close(fds[1]);
      if (::chdir(VLAB_SOURCE_DIR) != 0) ::_exit(126);
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(fds[1]);
    out_fd_ = fds[0];
    if (pid_ < 0) return;
    // the start line: "vlab-kinsim: arm 'pa10' (7 joints) on 127.0.0.1:PORT, 500 Hz"
    const auto deadline = Deadline(timeout_s);
    while (output_.find('\n') == std::string::npos && ReadSome(deadline)) {
    }
    const std::size_t newline = output_.find('\n');
    if (newline == std::string::npos) return;
    start_line_ = output_.substr(0, newline);
    const std::size_t on = start_line_.rfind(':');
    const std::size_t comma = start_line_.rfind(',');
    if (on == std::string::npos || comma == std::string::npos || comma < on) return;
    port_ = std::stoi(start_line_.substr(on + 1, comma - on - 1));
  }

  ~KinsimProcess() {
    if (pid_ > 0 && !stopped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) ::close(out_fd_);
  }

  bool ok() const { return port_ > 0; }
  int port() const { return port_; }
  const std::string& start_line() const { return start_line_; }

  /// Sends SIGINT, reads stdout to its end, returns the exit code (-1 if it
  /// did not exit normally within timeout_s; then it is killed).
  int Stop(double timeout_s = 20) {
    if (pid_ <= 0 || stopped_) return -1;
    ::kill(pid_, SIGINT);
    const auto deadline = Deadline(timeout_s);
    while (ReadSome(deadline)) {
    }
    int status = 0;
    pid_t done = 0;
    while ((done = ::waitpid(pid_, &status, WNOHANG)) == 0 && std::chrono::steady_clock::now() < deadline) {
      ::usleep(10000);
    }
    if (done != pid_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
    }
    stopped_ = true;
    return done == pid_ && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  /// Everything it printed to stdout so far.
  const std::string& output() const { return output_; }

 private:
  static std::chrono::steady_clock::time_point Deadline(double seconds) {
    return std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
  }
  // reads what is there; false at end of file or at the deadline
  bool ReadSome(std::chrono::steady_clock::time_point deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p{out_fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return false;
    char buffer[4096];
    const ssize_t n = ::read(out_fd_, buffer, sizeof(buffer));
    if (n <= 0) return false;
    output_.append(buffer, static_cast<std::size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  int out_fd_ = -1;
  int port_ = 0;
  bool stopped_ = false;
  std::string output_, start_line_;
};

}  // namespace vlab::testing
