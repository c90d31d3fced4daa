// Runs the real vlab-yoyosim executable for a test (tests/test_process.h): wait
// for its start line (which names both ports), then either wait for it to end
// (a --duration run) or stop it with SIGINT, and collect its report.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "test_process.h"

namespace vlab::testing {

class YoyosimProcess : public TestProcess {
 public:
  /// Starts VLAB_BINARY_DIR/vlab-yoyosim with `args` (plus --point-port 0
  /// --yoyo-port 0, from the source root) and waits up to timeout_s for its
  /// start line. ok() tells.
  explicit YoyosimProcess(std::vector<std::string> args, double timeout_s = 20)
      : TestProcess(WithProgram(std::move(args)), timeout_s) {
    // "vlab-yoyosim: point on 127.0.0.1:P, yoyo on 127.0.0.1:Q, lockstep, 100 Hz, scene ..."
    point_port_ = PortAfter("point on ");
    yoyo_port_ = PortAfter("yoyo on ");
  }

  bool ok() const { return point_port_ > 0 && yoyo_port_ > 0; }
  int point_port() const { return point_port_; }
  int yoyo_port() const { return yoyo_port_; }

 private:
  static std::vector<std::string> WithProgram(std::vector<std::string> args) {
    args.insert(args.begin(), VLAB_BINARY_DIR "/vlab-yoyosim");
    for (const char* a : {"--point-port", "0", "--yoyo-port", "0"}) args.emplace_back(a);
    return args;
  }
  int point_port_ = 0, yoyo_port_ = 0;
};

}  // namespace vlab::testing
