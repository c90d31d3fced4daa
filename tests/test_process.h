// Runs one of the project's programs for a test: fork/exec from the source root
// with its stdout on a pipe, wait for its start line, then wait for it to end
// or stop it with SIGINT, and collect what it printed. Shared by the tests of
// vlab-kinsim, vlab-yoyosim and vlab vision.
#pragma once

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

namespace vlab::testing {

class TestProcess {
 public:
  /// Starts `args` (args[0]: the executable's path) from VLAB_SOURCE_DIR and
  /// waits up to timeout_s for its first line of output (start_line(): empty
  /// when none came); timeout_s 0: does not wait (WaitForStartLine later).
  explicit TestProcess(std::vector<std::string> args, double timeout_s = 20) {
    int fds[2];
    if (::pipe(fds) != 0) return;
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
    if (timeout_s > 0) WaitForStartLine(timeout_s);
  }
  ~TestProcess() {
    if (pid_ > 0 && !ended_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_fd_ >= 0) ::close(out_fd_);
  }
  TestProcess(const TestProcess&) = delete;
  TestProcess& operator=(const TestProcess&) = delete;

  const std::string& start_line() const { return start_line_; }
  /// Waits up to timeout_s for its first line of output; the start line (empty when none
  /// came). For a program that prints it only once the test has done something.
  const std::string& WaitForStartLine(double timeout_s) {
    if (pid_ <= 0 || !start_line_.empty()) return start_line_;
    const auto deadline = Deadline(timeout_s);
    while (output_.find('\n') == std::string::npos && ReadSome(deadline)) {
    }
    const std::size_t newline = output_.find('\n');
    if (newline != std::string::npos) start_line_ = output_.substr(0, newline);
    return start_line_;
  }
  /// Everything it printed to stdout so far.
  const std::string& output() const { return output_; }

  /// Waits up to timeout_s for it to end by itself, reading stdout to its end;
  /// returns the exit code (-1 if it did not exit normally in time: then it is killed).
  int Wait(double timeout_s = 20) {
    if (pid_ <= 0 || ended_) return -1;
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
    ended_ = true;
    return done == pid_ && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  /// Sends SIGINT, then Wait(timeout_s).
  int Stop(double timeout_s = 20) {
    if (pid_ <= 0 || ended_) return -1;
    ::kill(pid_, SIGINT);
    return Wait(timeout_s);
  }

  /// Sends `signal` (SIGSTOP, SIGCONT, ...) to the running process; false once it has ended.
  bool Signal(int signal) { return pid_ > 0 && !ended_ && ::kill(pid_, signal) == 0; }

  /// The port of "LABEL ADDRESS:PORT," in the start line (0 when it is not there).
  int PortAfter(const std::string& label) const {
    const std::size_t at = start_line_.find(label);
    if (at == std::string::npos) return 0;
    const std::size_t colon = start_line_.find(':', at + label.size());
    const std::size_t comma = start_line_.find(',', at);
    if (colon == std::string::npos || comma == std::string::npos || comma < colon) return 0;
    return std::stoi(start_line_.substr(colon + 1, comma - colon - 1));
  }

 private:
  static std::chrono::steady_clock::time_point Deadline(double seconds) {
    return std::chrono::steady_clock::now() +
           std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
  }
  // reads what is there; false at end of file or at the deadline
  bool ReadSome(std::chrono::steady_clock::time_point deadline) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
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
  bool ended_ = false;
  std::string output_, start_line_;
};

}  // namespace vlab::testing
