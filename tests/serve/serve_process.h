// Test helpers for `vlab serve`: start it as a child process on free ports,
// wait for its start line, collect its exit code; and a scripted UDP peer.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "bridge/bridge_protocol.h"
#include "bridge/bridge_udp.h"
#include "wire_session.h"

namespace vlab::testing {

/// A free UDP port on 127.0.0.1 (bound and released at once).
inline int FreeUdpPort() { return bridge::UdpSocket::Bind("127.0.0.1", 0)->local_port(); }

/// `vlab serve ARGS` as a child; stdout/stderr into files of `dir`.
class ServeProcess {
 public:
  ServeProcess(const std::string& args, const std::string& dir) : out_(dir + "/serve.out"), err_(dir + "/serve.err") {
    const std::string cmd = "cd '" VLAB_SOURCE_DIR "' && exec '" VLAB_BINARY_DIR "/vlab' serve " + args + " >'" + out_ +
                            "' 2>'" + err_ + "' </dev/null";
    pid_ = fork();
    if (pid_ == 0) {
      execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
  }
  ~ServeProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  /// Waits up to timeout_s for the "vlab serve:" start line.
  bool WaitStarted(double timeout_s = 20) {
    for (int i = 0; i < timeout_s * 100; ++i) {
      if (Output().find("vlab serve:") != std::string::npos) return true;
      usleep(10000);
    }
    return false;
  }
  /// Sends it a signal (SIGINT, SIGTERM).
  void Signal(int signal_number) {
    if (pid_ > 0 && !reaped_) kill(pid_, signal_number);
  }
  /// Waits for the exit (kills it after timeout_s); returns the exit code, -1 if killed.
  /// With `resend`, sends that signal every 10 ms while it has not exited.
  int Wait(double timeout_s = 60, int resend = 0) {
    for (int i = 0; i < timeout_s * 100; ++i) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        reaped_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      if (resend != 0) kill(pid_, resend);
      usleep(10000);
    }
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    reaped_ = true;
    return -1;
  }
  std::string Output() const { return Read(out_); }
  std::string Errors() const { return Read(err_); }

 private:
  static std::string Read(const std::string& path) {
    std::string text;
    if (FILE* f = std::fopen(path.c_str(), "rb")) {
      char buf[4096];
      size_t n;
      while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) text.append(buf, n);
      std::fclose(f);
    }
    return text;
  }
  pid_t pid_ = -1;
  bool reaped_ = false;
  std::string out_, err_;
};

/// A scripted peer: raw datagrams, no client library.
class Peer {
 public:
  explicit Peer(int port)
      : socket_(bridge::UdpSocket::Bind("127.0.0.1", 0)), to_(bridge::UdpSocket::MakeEndpoint("127.0.0.1", port)) {}
  void Send(const std::vector<unsigned char>& packet) { socket_->SendTo(packet.data(), packet.size(), to_); }
  /// Subscribes (the cookie handshake), then asks for the describe reply.
  void Describe(bridge::DeviceKind kind) {
    cookie_ = WireSubscribe(*socket_, to_, kind);
    std::vector<unsigned char> p;
    bridge::EncodeDescribeRequest(static_cast<int>(kind), cookie_, &p);
    Send(p);
  }
  double cookie() const { return cookie_; }
  /// Next arm state (skips describe and session replies); false on timeout.
  bool ReadArm(bridge::Header* h, bridge::ArmStateMsg* m, double timeout_s = 5) {
    unsigned char buf[65536];
    std::vector<double> payload;
    for (;;) {
      const long n = socket_->Receive(buf, sizeof(buf), nullptr, timeout_s);
      if (n < 0) return false;
      if (n > 0 && buf[0] == '{') continue;
      if (bridge::DecodePacket(buf, static_cast<std::size_t>(n), h, &payload) != bridge::DecodeError::kNone) continue;
      if (bridge::ParseArmState(*h, payload, 7, m) == bridge::DecodeError::kNone) return true;
    }
  }
  /// Next arm state, then every state already queued behind it: the newest one (what a
  /// controller answers after a pause, while the lab ran on without waiting for it).
  bool ReadNewestArm(bridge::Header* h, bridge::ArmStateMsg* m) {
    if (!ReadArm(h, m)) return false;
    bridge::Header next;
    bridge::ArmStateMsg state;
    while (ReadArm(&next, &state, 0)) {
      *h = next;
      *m = state;
    }
    return true;
  }
  void Command(double seq, int mode, const std::vector<double>& value) {
    std::vector<unsigned char> p;
    bridge::EncodeArmCommand(seq, 0, {mode, value}, &p);
    Send(p);
  }

 private:
  std::unique_ptr<bridge::UdpSocket> socket_;
  bridge::Endpoint to_;
  double cookie_ = 0;
};

}  // namespace vlab::testing
