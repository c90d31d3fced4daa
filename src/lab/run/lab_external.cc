// External controllers started by the lab (see lab_external.h).
#include "lab/run/lab_external.h"

#include <dirent.h>
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <thread>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

// the program's descriptors: stdin, stdout, stderr, the exit pipe; the exec error pipe
// sits above them until exec closes it
constexpr int kExitFd = 3;
constexpr int kExecErrorFd = 4;

// closes every descriptor from `lowest` on, between fork and exec (async-signal-safe calls
// only): close_range (Linux 5.9), else the descriptors /proc lists, else all up to the limit
void CloseFrom(int lowest) {
#ifdef SYS_close_range
  if (::syscall(SYS_close_range, static_cast<unsigned>(lowest), ~0U, 0) == 0) return;
#endif
  const int dir = ::open("/proc/self/fd", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    alignas(dirent64) char buffer[4096];
    ssize_t n;
    while ((n = ::getdents64(dir, buffer, sizeof(buffer))) > 0) {
      for (ssize_t at = 0; at < n;) {
        const auto* entry = reinterpret_cast<const dirent64*>(buffer + at);
        at += entry->d_reclen;
        int fd = 0;
        const char* c = entry->d_name;
        for (; *c >= '0' && *c <= '9'; ++c) fd = fd * 10 + (*c - '0');
        if (*c == '\0' && c != entry->d_name && fd >= lowest && fd != dir) ::close(fd);
      }
    }
    ::close(dir);
    return;
  }
  rlimit limit{};
  const rlim_t most = ::getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY
                          ? std::min<rlim_t>(limit.rlim_cur, 1 << 20)
                          : 1 << 16;
  for (int fd = lowest; fd < static_cast<int>(most); ++fd) ::close(fd);
}

// waitpid, resumed after a signal (a second Ctrl-C while the run finishes)
pid_t WaitFor(pid_t pid, int* status, int options) {
  pid_t done;
  do {
    done = ::waitpid(pid, status, options);
  } while (done < 0 && errno == EINTR);
  return done;
}

}  // namespace

bool StartsExternalController(const Scenario& scenario, bool serving) {
  return scenario.controller.type == ControllerType::kExternal && !serving;
}

BridgeOptions ExternalBridgeOptions(const Scenario& scenario) {
  BridgeOptions options;
  options.bind = "127.0.0.1";
  for (const DeviceConfig& d : scenario.devices) {
    if (d.port != 0) options.ports[d.name] = 0;  // a fixed port, or auto
  }
  return options;
}

ClockMode ExternalClock(const Scenario& scenario, std::optional<ClockMode> requested) {
  const ClockMode clock = requested.value_or(scenario.clock);
  return clock == ClockMode::kFast ? ClockMode::kLockstep : clock;
}

std::unique_ptr<ExternalController> ExternalController::Start(const std::vector<std::string>& argv,
                                                              const std::string& log_path, int realtime_priority,
                                                              const std::vector<std::string>& environment) {
  if (argv.empty() || argv[0].empty()) throw InputError("controller.command: no program named");
  std::unique_ptr<ExternalController> c(new ExternalController());
  c->program_ = argv[0];
  c->log_path_ = log_path;
  if (log_path.empty()) {
    char name[] = "/tmp/vlab-controller-XXXXXX";
    const int fd = ::mkstemp(name);
    if (fd < 0) throw std::runtime_error("controller '" + argv[0] + "': no temporary file for its output");
    ::close(fd);
    c->log_path_ = name;
    c->log_is_temporary_ = true;
  }
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  // the environment, made before the fork (the child may not allocate): vlab's own, less
  // the names `environment` sets, then those
  std::vector<char*> env;
  for (char** e = environ; *e; ++e) {
    const std::string_view entry(*e);
    const bool replaced = std::any_of(environment.begin(), environment.end(), [&entry](const std::string& add) {
      const std::size_t eq = add.find('=');
      return entry.size() > eq && entry.compare(0, eq + 1, add, 0, eq + 1) == 0;
    });
    if (!replaced) env.push_back(*e);
  }
  for (const std::string& add : environment) env.push_back(const_cast<char*>(add.c_str()));
  env.push_back(nullptr);

  const int log = ::open(c->log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  const int null = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  int exit_pipe[2] = {-1, -1}, error_pipe[2] = {-1, -1};
  if (log < 0 || null < 0 || ::pipe2(exit_pipe, O_CLOEXEC) != 0 || ::pipe2(error_pipe, O_CLOEXEC) != 0) {
    const std::string why = std::strerror(errno);
    for (int fd : {log, null, exit_pipe[0], exit_pipe[1], error_pipe[0], error_pipe[1]}) {
      if (fd >= 0) ::close(fd);
    }
    throw std::runtime_error("controller '" + argv[0] + "': cannot set up its output '" + c->log_path_ + "': " + why);
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // child: own process group, ended with its parent; only async-signal-safe calls until exec
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);
    // the descriptors it keeps, first above the ones they go to (so that none overwrites another)
    int keep[4] = {null, log, exit_pipe[1], error_pipe[1]};
    for (int& fd : keep) {
      fd = ::fcntl(fd, F_DUPFD_CLOEXEC, kExecErrorFd + 1);
      if (fd < 0) {
        const int error = errno;
        (void)!::write(error_pipe[1], &error, sizeof(error));
        ::_exit(127);
      }
    }
    ::dup2(keep[0], 0);
    ::dup2(keep[1], 1);
    ::dup2(keep[1], 2);
    ::dup2(keep[2], kExitFd);  // held open until the program (and its children) exit
    ::dup2(keep[3], kExecErrorFd);
    ::fcntl(kExecErrorFd, F_SETFD, FD_CLOEXEC);  // closed by a successful exec
    // nothing else of the lab's: its sockets, log.csv, images, video
    CloseFrom(kExecErrorFd + 1);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    if (realtime_priority > 0) {
      // inherited through exec and by the program's own children; a refusal is
      // reported (as -errno, before any exec error) and the program runs anyway
      sched_param param{};
      param.sched_priority = realtime_priority;
      if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
        const int refused = -errno;
        (void)!::write(kExecErrorFd, &refused, sizeof(refused));
      }
    }
    ::execvpe(args[0], args.data(), env.data());
    const int error = errno;
    (void)!::write(kExecErrorFd, &error, sizeof(error));
    ::_exit(127);
  }
  const int fork_error = errno;
  ::close(log);
  ::close(null);
  ::close(exit_pipe[1]);
  ::close(error_pipe[1]);
  c->exit_fd_ = exit_pipe[0];
  if (pid < 0) {
    ::close(error_pipe[0]);
    throw std::runtime_error("controller '" + argv[0] + "': fork failed: " + std::strerror(fork_error));
  }
  c->pid_ = pid;
  ::setpgid(pid, pid);  // also here: no race with the first kill
  // until exec closes the pipe: a scheduling refusal (-errno), then an exec error (errno)
  int exec_error = 0, sched_error = 0;
  ssize_t n;
  for (;;) {
    int value = 0;
    do {
      n = ::read(error_pipe[0], &value, sizeof(value));
    } while (n < 0 && errno == EINTR);
    if (n != static_cast<ssize_t>(sizeof(value))) break;
    if (value < 0) {
      sched_error = -value;
    } else {
      exec_error = value;
      break;
    }
  }
  ::close(error_pipe[0]);
  c->realtime_.requested = realtime_priority;
  if (realtime_priority > 0 && exec_error == 0) {
    // after the exec: what the program runs at
    c->realtime_.granted = ProcessRealtimePriority(pid) == realtime_priority;
    if (!c->realtime_.granted) {
      c->realtime_.reason =
          sched_error != 0 ? RealtimeRefusal(realtime_priority, sched_error) : "not in force after exec";
    }
  }
  if (exec_error != 0) {
    WaitFor(pid, &c->status_, 0);
    c->reaped_ = true;
    throw InputError("controller.command: cannot run '" + argv[0] + "': " + std::strerror(exec_error));
  }
  return c;
}

ExternalController::~ExternalController() {
  Stop(1.0);
  if (exit_fd_ >= 0) ::close(exit_fd_);
  if (log_is_temporary_) ::unlink(log_path_.c_str());
}

bool ExternalController::Exited() {
  if (!reaped_ && pid_ > 0 && WaitFor(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
  return reaped_;
}

bool ExternalController::WaitExited(double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!Exited() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return Exited();
}

void ExternalController::Stop(double grace_s) {
  if (pid_ <= 0) return;
  if (!Exited()) {
    stopped_ = true;
    ::kill(-pid_, SIGTERM);
    if (!WaitExited(grace_s)) {
      ::kill(-pid_, SIGKILL);
      WaitFor(pid_, &status_, 0);
      reaped_ = true;
    }
  }
  ::kill(-pid_, SIGKILL);  // whatever the program left running in its group
  pid_ = -1;
}

bool ExternalController::Succeeded() const {
  if (!reaped_) return false;
  // an exit status is the program's verdict, also after our SIGTERM; a signal
  // is a failure unless it was ours (Stop)
  if (WIFEXITED(status_)) return WEXITSTATUS(status_) == 0;
  return stopped_;
}

std::string ExternalController::Outcome() const {
  if (!reaped_) return "running";
  if (WIFEXITED(status_)) return "exit status " + std::to_string(WEXITSTATUS(status_));
  if (WIFSIGNALED(status_)) return "killed by signal " + std::to_string(WTERMSIG(status_));
  return "ended";
}

std::string ExternalController::LastLogLine() const {
  std::ifstream in(log_path_);
  std::string line, last;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  }
  return last;
}

}  // namespace vlab::lab
