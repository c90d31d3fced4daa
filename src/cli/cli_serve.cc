// vlab serve: run a scenario with its devices served over UDP.
// vlab devices: list a scenario's devices, endpoints and layouts.
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::cli {

namespace {

// --bind, --port DEVICE=PORT|auto (0: any free port) and --ports auto (every served device on
// a free port); a device the scenario gives `port: auto` is bound to port 0 by the bridge
lab::BridgeOptions MakeBridgeOptions(const ServeArgs& args, const lab::Scenario& scenario) {
  lab::BridgeOptions options;
  options.bind = args.bind;
  options.max_subscribers = args.max_subscribers;
  if (args.ports_mode == "auto") {
    for (const lab::DeviceConfig& d : scenario.devices) {
      if (d.port != 0) options.ports[d.name] = 0;
    }
  }
  for (const std::string& p : args.ports) {
    const auto eq = p.find('=');
    const std::string value = eq == std::string::npos ? "" : p.substr(eq + 1);
    int port = -1;
    try {
      std::size_t used = 0;
      port = value == "auto" ? 0 : std::stoi(value, &used);
      if (value != "auto" && used != value.size()) port = -1;
    } catch (const std::exception&) {
      port = -1;
    }
    if (eq == std::string::npos || eq == 0 || port < 0 || port > 65535) {
      throw vlab::InputError("--port '" + p + "': expected DEVICE=PORT with PORT 0..65535 or auto");
    }
    options.ports[p.substr(0, eq)] = port;
  }
  return options;
}

std::string Layout(const nlohmann::ordered_json& fields) {
  std::string text;
  for (const auto& f : fields) text += (text.empty() ? "" : ", ") + f.get<std::string>();
  return text.empty() ? "-" : text;
}

}  // namespace

int ServeCommand(const ServeArgs& args) {
  return WithErrorReport([&args] {
    // SIGINT, SIGTERM: the run stops at the next period (a wait for a controller at once) and writes
    // what ran; installed before loading, so that one during loading is not lost
    InstallStopSignals();
    lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(args.scenario));
    if (args.duration_s > 0) scenario.duration_s = args.duration_s;
    const lab::BridgeOptions bridge = MakeBridgeOptions(args, scenario);
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    const std::string out_dir = args.out_dir.empty() ? "out/" + scenario.name : args.out_dir;
    lab::RunOptions options;
    options.out_dir = out_dir;
    options.interrupt = &g_stop_requested;
    options.serve = &bridge;
    if (!args.clock.empty()) options.clock = ParseClockMode(args.clock, "--clock");
    options.on_serving = [&scenario, &options](const std::vector<lab::ServedDevice>& devices) {
      std::string line =
          "vlab serve: " + scenario.name + ", clock " + ClockModeName(options.clock.value_or(scenario.clock)) + ";";
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
      std::printf(
          "  %-8s received %ld, accepted %ld, refused %ld (malformed %ld, limits %ld, not owner %ld, "
          "not subscribed %ld), stale %ld, duplicate %ld, future %ld, watchdog holds %ld; subscribed %ld, "
          "challenges %ld\n",
          d.name.c_str(), c.received, c.accepted, c.refused, c.refused_malformed, c.refused_limits, c.refused_not_owner,
          c.refused_not_subscribed, c.stale, c.duplicate, c.future, c.watchdog_holds, c.sessions.subscribed,
          c.sessions.challenges);
    }
    std::printf("%s: %s, %.2f s simulated in %.2f s, clock %s; output in %s/\n", scenario.name.c_str(), Verdict(r),
                r.sim_time_s, r.loop_wall_s, ClockModeName(r.clock), r.out_dir.c_str());
    PrintPlots(scenario, r.out_dir, r);
    if (!r.out_note.empty()) std::fprintf(stderr, "vlab: %s\n", r.out_note.c_str());
    if (r.exit_code != 0) std::fprintf(stderr, "vlab: %s\n", r.failure.c_str());
    return r.exit_code;
  });
}

int DevicesCommand(const ServeArgs& args) {
  return WithErrorReport([&args] {
    const lab::Scenario scenario = lab::LoadScenario(lab::ResolveScenarioPath(args.scenario));
    const lab::BridgeOptions asked = MakeBridgeOptions(args, scenario);
    // the port `vlab serve` with these options would bind (0: a free one, chosen then); to
    // describe, any free port is bound instead (a server may be running on the real ones)
    std::map<std::string, int> ports;
    lab::BridgeOptions bridge = asked;
    for (const auto& d : scenario.devices) {
      const auto o = asked.ports.find(d.name);
      if (o == asked.ports.end() && d.port == 0) continue;
      ports[d.name] = o != asked.ports.end() ? o->second : d.port == lab::kAutoPort ? 0 : d.port;
      bridge.ports[d.name] = 0;
    }
    std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
    std::optional<ClockMode> clock;
    if (!args.clock.empty()) clock = ParseClockMode(args.clock, "--clock");
    const std::vector<lab::ServedDevice> devices = lab->Describe(bridge, clock);
    std::printf("%s: clock %s\n", scenario.name.c_str(), ClockModeName(clock.value_or(scenario.clock)));
    for (const auto& d : devices) {
      const int port = ports.at(d.name);
      nlohmann::ordered_json j = nlohmann::ordered_json::parse(d.describe_json);
      const std::string endpoint = port > 0 ? std::to_string(port) : "auto (a free port, chosen when served)";
      std::printf("  %-8s %-6s udp %s:%s\n", d.name.c_str(), d.kind.c_str(), bridge.bind.c_str(), endpoint.c_str());
      std::printf("           state:   %s\n", Layout(j["layout"]["state"]).c_str());
      std::printf("           command: %s\n", Layout(j["layout"]["command"]).c_str());
      if (!args.json) continue;
      // the reply the served device would give: its port, not the one bound to describe it
      // (null where it is chosen when served)
      if (j.contains("endpoint")) {
        j["endpoint"]["port"] = port > 0 ? nlohmann::ordered_json(port) : nlohmann::ordered_json(nullptr);
      }
      std::printf("           describe: %s\n", j.dump().c_str());
    }
    for (const auto& d : scenario.devices) {
      if (ports.count(d.name) == 0) {
        std::printf("  %-8s %-6s not served (no port)\n", d.name.c_str(), bridge::KindName(static_cast<int>(d.kind)));
      }
    }
    return 0;
  });
}

}  // namespace vlab::cli
