// vlab-yoyosim: the external yo-yo simulator. A yo-yo hanging from a hand that
// a controller moves: devices `point` (hand set-point in, hand state out) and
// `yoyo` (yo-yo state out) over UDP, protocol v1. See yoyosim_server.h and
// `vlab-yoyosim --help`.
// Exit codes: 0 done (duration over, or SIGINT/SIGTERM); 1 the simulation
// diverged or another failure; 2 bad input (option, scene, address or port in use).
#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "bridge/bridge_errors.h"
#include "bridge/bridge_signals.h"
#include "core/core_errors.h"
#include "yoyosim/yoyosim.h"
#include "yoyosim/yoyosim_server.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "vlab-yoyosim: error: %s\n", what.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  vlab::yoyosim::SimConfig sim_config;
  vlab::yoyosim::ServerConfig server_config;
  CLI::App app{
      "vlab-yoyosim: a yo-yo on a string hanging from a moving hand (MuJoCo), behind two vlab devices:\n"
      "`point` (kind 10: command [x, y, z] = the hand's set-point, m, world; state [status, x, y, z,\n"
      "vx, vy, vz] of the hand) and `yoyo` (kind 11: state [status, x, y, z, vz, string_force, spin]).\n"
      "Protocol v1 (docs/protocol.md). Ends after --duration or on SIGINT/SIGTERM and prints its counters.\n"
      "Exit codes: 0 done; 1 the simulation diverged; 2 bad input (option, scene, address, port)."};
  app.add_option("--scene", sim_config.scene, "MJCF scene (a hand on slides hand_x/y/z with servos, the yo-yo)")
      ->capture_default_str();
  app.add_option("--bind", server_config.bind_address, "Address to bind (numeric IPv4/IPv6)")->capture_default_str();
  app.add_option("--point-port", server_config.point_port, "UDP port of the point device (0: any free port)")
      ->capture_default_str();
  app.add_option("--yoyo-port", server_config.yoyo_port, "UDP port of the yoyo device (0: any free port)")
      ->capture_default_str();
  app.add_option("--period", sim_config.period_s, "Control period, s (a whole number of the scene's timesteps)")
      ->capture_default_str();
  app.add_option("--clock", server_config.clock, "lockstep (wait for each command) or realtime (wall clock)")
      ->capture_default_str();
  app.add_option("--duration", server_config.duration_s, "Simulated run time, s (0: until SIGINT/SIGTERM)")
      ->capture_default_str();
  app.add_option("--start-timeout", server_config.start_timeout_s, "Wait for a controller before period 0, s")
      ->capture_default_str();
  app.add_option("--timeout", server_config.timeout_s, "lockstep: wait for each period's command, s")
      ->capture_default_str();
  app.add_option("--max-speed", server_config.speed_max,
                 "Hand set-point speed limit, m/s (a far set-point is approached at this speed)")
      ->capture_default_str();
  app.add_flag("--quiet", server_config.quiet, "Print only the start line (no messages, no counters at exit)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    return Fail(std::string(e.what()) + " (see vlab-yoyosim --help)");
  }

  std::unique_ptr<vlab::yoyosim::YoyoSimServer> server;
  try {
    server = vlab::yoyosim::YoyoSimServer::Create(server_config, vlab::yoyosim::YoyoSim::Create(sim_config));
  } catch (const vlab::InputError& e) {
    return Fail(e.what());
  } catch (const vlab::bridge::NetworkError& e) {
    return Fail(e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vlab-yoyosim: error: %s\n", e.what());
    return 1;
  }

  vlab::InstallStopSignals();
  std::printf("%s\n", server->StartLine().c_str());
  std::fflush(stdout);
  const int result = server->Run(&vlab::g_stop_requested);
  if (!server_config.quiet) std::printf("%s\n", server->ReportText().c_str());
  std::fflush(stdout);
  return result;
}
