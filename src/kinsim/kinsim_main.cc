// vlab-kinsim: a kinematic PA10 (any MJCF arm) behind the arm device's UDP
// interface. See kinsim_server.h and `vlab-kinsim --help`.
// Exit codes: 0 done (duration over, or SIGINT/SIGTERM); 2 bad input (scene,
// joint, option, address or port in use); 1 anything else.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bridge/bridge_errors.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_signals.h"
#include "core/core_errors.h"
#include "kinsim/kinsim.h"
#include "kinsim/kinsim_scene.h"
#include "kinsim/kinsim_server.h"

namespace {

struct Args {
  std::string name = "pa10";
  std::string scene = "scenes/pa10.xml";
  std::vector<std::string> joints = vlab::kinsim::Pa10Joints();
  std::vector<double> max_velocity = {vlab::kinsim::kPa10VelocityMax};
  std::vector<double> initial = vlab::kinsim::Pa10ReadyPose();
  vlab::kinsim::ServerConfig server;
};

int Fail(const std::string& what) {
  std::fprintf(stderr, "vlab-kinsim: error: %s\n", what.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  CLI::App app{
      "vlab-kinsim: a kinematic arm simulator (no dynamics) behind the vlab arm device's UDP interface\n"
      "(protocol v" +
      std::to_string(vlab::bridge::kProtocolVersion) +
      ", the same bytes as `vlab serve`). Velocity commands are integrated and clamped at\n"
      "the joint limits, position commands are followed at up to the velocity limit, torque commands\n"
      "are refused. Ends after --duration or on SIGINT/SIGTERM (exit 0) and prints its counters.\n"
      "Exit codes: 0 done; 2 bad input (scene, joint, option, address or port in use)."};
  app.add_option("--scene", args.scene, "MJCF scene with the arm's joints (names and ranges only)")
      ->capture_default_str();
  app.add_option("--name", args.name, "Device name")->capture_default_str();
  app.add_option("--joints", args.joints, "Joint names, in wire order (comma-separated)")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--max-velocity", args.max_velocity,
                 "Joint velocity limit, rad/s: one value for all joints or one per joint (default pi)")
      ->delimiter(',');
  app.add_option("--initial", args.initial, "Initial joint positions, rad (default: the PA10 'ready' pose)")
      ->delimiter(',');
  app.add_option("--rate", args.server.rate_hz, "Control rate, Hz (1 to 10000)")->capture_default_str();
  app.add_option("--duration", args.server.duration_s, "Run time, s (default: until SIGINT/SIGTERM)");
  app.add_option("--bind", args.server.bind_address, "Address to bind (numeric IPv4/IPv6)")->capture_default_str();
  app.add_option("--port", args.server.port, "UDP port (0: any free port, printed in the start line)")
      ->capture_default_str();
  app.add_option("--watchdog-periods", args.server.watchdog_periods,
                 "Hold when the owner sends no command for this many periods (0: off)")
      ->capture_default_str();
  app.add_option("--owner-timeout", args.server.owner_timeout_s,
                 "Another client may take the command input after the owner has been silent this long, s")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    return Fail(std::string(e.what()) + " (see vlab-kinsim --help)");
  }

  std::unique_ptr<vlab::kinsim::KinsimServer> server;
  try {
    const bool per_joint_default = app.count("--initial") == 0 && args.joints != vlab::kinsim::Pa10Joints();
    if (per_joint_default) throw vlab::InputError("--initial is required with --joints other than the PA10's");
    auto arm = vlab::kinsim::KinArm::Create(
        vlab::kinsim::ArmFromScene(args.name, args.scene, args.joints, args.max_velocity, args.initial));
    server = vlab::kinsim::KinsimServer::Create(args.server, std::move(arm));
  } catch (const vlab::InputError& e) {
    return Fail(e.what());
  } catch (const vlab::bridge::NetworkError& e) {
    return Fail(e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vlab-kinsim: error: %s\n", e.what());
    return 1;
  }

  vlab::InstallStopSignals();
  std::printf("%s\n", server->StartLine().c_str());
  std::fflush(stdout);
  server->Run(&vlab::g_stop_requested);
  std::printf("%s\n", server->ReportText().c_str());
  std::fflush(stdout);
  return 0;
}
