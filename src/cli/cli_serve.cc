// vlab serve: run a scenario with its devices served over UDP.
// vlab devices: list a scenario's devices, endpoints and layouts.
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "core/core_signals.h"
#include "lab/lab_runner.h"
#include "lab/lab_scenario.h"

namespace vlab::cli {

namespace {

lab::BridgeOptions MakeBridgeOptions(const ServeArgs& args) {
  lab::BridgeOptions options;
  options.bind = args.bind;
  options.max_subscribers = args.max_subscribers;
  for (const std::string& p : args.ports) {
    const auto eq = p.find('=');
    int port = -1;
    try {
      port = eq == std::string::npos ? -1 : std::stoi(p.substr(eq + 1));
    } catch (const std::exception&) {
      port = -1;
    }
    if (eq == std::string::npos || eq == 0 || port < 0 || port > 65535) {
      throw vlab::InputError("--port '" + p + "': expected DEVICE=PORT with PORT 0..65535");
    }
    options.ports[p.substr(0, eq)] = port;
  }
  return options;
}

std::string Layout(const nlohmann::json& fields) {
  std::string text;
  for (const auto& f : fields) text += (text.empty() ? "" : ", ") + f.get<std::string>();
  return text.empty() ? "-" : text;
}

}  // namespace

int ServeCommand(const ServeArgs& args) {
  return WithErrorReport([&args] {
    lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(args.scenario));
    if (args.duration_s > 0) scenario.duration_s = args.duration_s;
    const lab::BridgeOptions bridge = MakeBridgeOptions(args);
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    const std::string out_dir = args.out_dir.empty() ? "out/" + scenario.name : args.out_dir;

    // SIGINT, SIGTERM: the run stops at the next period (a wait for a controller at once) and writes what ran
    InstallStopSignals();
    lab::RunOptions options;
    options.out_dir = out_dir;
    options.interrupt = &g_stop_requested;
    options.serve = &bridge;
    if (!args.clock.empty()) options.clock = ParseClockMode(args.clock, "--clock");
    options.on_serving = [&scenario, &options](const std::vector<lab::ServedDevice>& devices) {
      std::string line = "vlab serve: " + scenario.name + ", clock " +
                         ClockModeName(options.clock.value_or(scenario.clock)) + ";";
      for (const auto& d : devices) {
        line += " " + d.name + " (" + d.kind + ") " + d.address + ":" + std::to_string(d.port) + ";";
      }
      if (devices.empty()) line += " no device has a port";
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    };
    if (args.rt_priority >= 0) options.realtime_priority = args.rt_priority;
    if (!args.quiet) options.on_realtime = PrintRealtime;
    if (!args.quiet) {
      options.on_waiting = [](const std::string& message) {
        std::fprintf(stderr, "vlab serve: %s\n", message.c_str());
        std::fflush(stderr);
      };
    }
    const lab::RunResult r = lab->Run(options);
    for (const auto& d : r.served) {
      if (args.quiet) break;
      const auto& c = d.counters;
      std::printf("  %-8s received %ld, accepted %ld, refused %ld (malformed %ld, limits %ld, not owner %ld, "
                  "not subscribed %ld), stale %ld, duplicate %ld, future %ld, watchdog holds %ld; subscribed %ld, "
                  "challenges %ld\n",
                  d.name.c_str(), c.received, c.accepted, c.refused, c.refused_malformed, c.refused_limits,
                  c.refused_not_owner, c.refused_not_subscribed, c.stale, c.duplicate, c.future, c.watchdog_holds,
                  c.sessions.subscribed, c.sessions.challenges);
    }
    std::printf("%s: %s, %.2f s simulated in %.2f s, clock %s; output in %s/\n", scenario.name.c_str(),
                Verdict(r), r.sim_time_s, r.loop_wall_s, ClockModeName(r.clock), out_dir.c_str());
    PrintPlots(scenario, out_dir, r);
    if (r.exit_code != 0) std::fprintf(stderr, "vlab: %s\n", r.failure.c_str());
    return r.exit_code;
  });
}

int DevicesCommand(const ServeArgs& args) {
  return WithErrorReport([&args] {
    const lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(args.scenario));
    lab::BridgeOptions bridge = MakeBridgeOptions(args);
    // describe without taking the ports (a server may be running): bind any free port
    std::map<std::string, int> ports;
    for (const auto& d : scenario.devices) {
      const auto o = bridge.ports.find(d.name);
      ports[d.name] = o != bridge.ports.end() ? o->second : d.port;
      if (ports[d.name] > 0 || o != bridge.ports.end()) bridge.ports[d.name] = 0;
    }
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    std::optional<ClockMode> clock;
    if (!args.clock.empty()) clock = ParseClockMode(args.clock, "--clock");
    const std::vector<lab::ServedDevice> devices = lab->Describe(bridge, clock);
    std::printf("%s: clock %s\n", scenario.name.c_str(), ClockModeName(clock.value_or(scenario.clock)));
    for (const auto& d : devices) {
      const nlohmann::json j = nlohmann::json::parse(d.describe_json);
      std::printf("  %-8s %-6s udp %s:%d\n", d.name.c_str(), d.kind.c_str(), bridge.bind.c_str(), ports[d.name]);
      std::printf("           state:   %s\n", Layout(j["layout"]["state"]).c_str());
      std::printf("           command: %s\n", Layout(j["layout"]["command"]).c_str());
      if (args.json) std::printf("           describe: %s\n", d.describe_json.c_str());
    }
    for (const auto& d : scenario.devices) {
      if (ports[d.name] == 0) std::printf("  %-8s %-6s not served (no port)\n", d.name.c_str(), bridge::KindName(static_cast<int>(d.kind)));
    }
    return 0;
  });
}

}  // namespace vlab::cli
