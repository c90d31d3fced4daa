// Runs the real vlab-kinsim executable for a test (tests/test_process.h): wait
// for its start line, stop it with SIGINT and collect its report.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "test_process.h"

namespace vlab::testing {

class KinsimProcess : public TestProcess {
 public:
  /// Starts VLAB_BINARY_DIR/vlab-kinsim with `args` (plus --port 0, from the
  /// source root) and waits up to timeout_s for its start line. ok() tells.
  explicit KinsimProcess(std::vector<std::string> args, double timeout_s = 20)
      : TestProcess(WithProgram(std::move(args)), timeout_s) {
    // the start line: "vlab-kinsim: arm 'pa10' (7 joints) on 127.0.0.1:PORT, 500 Hz"
    port_ = PortAfter(" on ");
  }

  bool ok() const { return port_ > 0; }
  int port() const { return port_; }

 private:
  static std::vector<std::string> WithProgram(std::vector<std::string> args) {
    args.insert(args.begin(), VLAB_BINARY_DIR "/vlab-kinsim");
    args.push_back("--port");
    args.push_back("0");
    return args;
  }
  int port_ = 0;
};

}  // namespace vlab::testing
