// An external controller's command line and environment (see lab_command.h).
#include "lab/run/lab_command.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "bridge/bridge_errors.h"
#include "core/core_errors.h"

namespace vlab::lab {

namespace {

constexpr char kPortPrefix[] = "port:";

bool ServedInScenario(const Scenario& scenario, const std::string& name) {
  return std::any_of(scenario.devices.begin(), scenario.devices.end(),
                     [&name](const DeviceConfig& d) { return d.name == name && d.port != 0; });
}

// "VLAB_PORT_" + NAME in upper case, anything but a letter or digit as '_'
std::string EnvironmentName(const std::string& prefix, const std::string& name) {
  std::string out = prefix;
  for (const char c : name) {
    out += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::toupper(static_cast<unsigned char>(c)))
                                                       : '_';
  }
  return out;
}

}  // namespace

PortReservations PortReservations::Reserve(const std::vector<std::string>& names, const std::string& address) {
  PortReservations r;
  for (const std::string& name : names) {
    try {
      r.sockets_.push_back(bridge::UdpSocket::Bind(address, 0));
    } catch (const bridge::NetworkError& e) {
      throw std::runtime_error("controller.command: {port:" + name + "}: no free port: " + e.what());
    }
    r.ports_[name] = r.sockets_.back()->local_port();
  }
  return r;
}

std::vector<std::string> CommandPortNames(const Scenario& scenario, const std::string& where) {
  std::vector<std::string> names;
  for (const std::string& arg : scenario.controller.command) {
    for (std::size_t at = arg.find(std::string("{") + kPortPrefix); at != std::string::npos;
         at = arg.find(std::string("{") + kPortPrefix, at + 1)) {
      const std::size_t begin = at + 1 + sizeof(kPortPrefix) - 1;
      const std::size_t close = arg.find('}', begin);
      if (close == std::string::npos) continue;  // ExpandCommand names the unclosed brace
      const std::string name = arg.substr(begin, close - begin);
      const bool valid = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
      });
      if (!valid) {
        throw InputError(where + ": controller.command: {port:" + name +
                         "}: a port's name is letters, digits and '_' (a device's name, or any other for a free port)");
      }
      if (!ServedInScenario(scenario, name) && std::find(names.begin(), names.end(), name) == names.end()) {
        names.push_back(name);
      }
    }
  }
  return names;
}

std::map<std::string, std::string> CommandValues(const Scenario& scenario, const std::vector<ServedDevice>& served,
                                                 const std::string& out_dir,
                                                 const std::map<std::string, int>& reserved) {
  std::map<std::string, std::string> values;
  for (const DeviceConfig& d : scenario.devices) {
    if (d.port == 0) continue;
    values[d.name] = "127.0.0.1:0";
    values[kPortPrefix + d.name] = "0";
  }
  for (const ServedDevice& d : served) {
    values[d.name] = d.address + ":" + std::to_string(d.port);
    values[kPortPrefix + d.name] = std::to_string(d.port);
  }
  for (const std::string& name : CommandPortNames(scenario, scenario.controller.where)) {
    const auto it = reserved.find(name);
    values[kPortPrefix + name] = std::to_string(it == reserved.end() ? 0 : it->second);
  }
  values["bin"] = ExecutableDir();
  const std::string dir = std::filesystem::path(scenario.file).parent_path().string();
  values["scenario_dir"] = dir.empty() ? "." : dir;
  char duration[32];
  std::snprintf(duration, sizeof(duration), "%.17g", scenario.duration_s);
  values["duration"] = duration;
  std::string out = out_dir.empty() ? std::filesystem::temp_directory_path().string() : out_dir;
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  values["out"] = out;
  return values;
}

std::vector<std::string> CommandEnvironment(const std::vector<ServedDevice>& served,
                                            const std::map<std::string, int>& reserved) {
  std::vector<std::string> env;
  for (const ServedDevice& d : served) {
    env.push_back(EnvironmentName("VLAB_DEVICE_", d.name) + "=" + d.address + ":" + std::to_string(d.port));
    env.push_back(EnvironmentName("VLAB_PORT_", d.name) + "=" + std::to_string(d.port));
  }
  for (const auto& [name, port] : reserved) {
    env.push_back(EnvironmentName("VLAB_PORT_", name) + "=" + std::to_string(port));
  }
  return env;
}

std::vector<std::string> ExpandCommand(const std::vector<std::string>& command,
                                       const std::map<std::string, std::string>& values, const std::string& where) {
  std::vector<std::string> out;
  for (const std::string& arg : command) {
    std::string expanded;
    std::size_t at = 0;
    while (at < arg.size()) {
      const std::size_t open = arg.find('{', at);
      if (open == std::string::npos) {
        expanded += arg.substr(at);
        break;
      }
      const std::size_t close = arg.find('}', open);
      if (close == std::string::npos) {
        throw InputError(where + ": controller.command: '" + arg + "': a '{' without its '}'");
      }
      const std::string name = arg.substr(open + 1, close - open - 1);
      const auto it = values.find(name);
      if (it == values.end()) {
        std::string known;
        for (const auto& [k, v] : values) {
          if (k.rfind(kPortPrefix, 0) != 0) known += (known.empty() ? "" : ", ") + ("{" + k + "}");
        }
        throw InputError(where + ": controller.command: unknown placeholder {" + name + "} (known: " + known +
                         ", {port:NAME}; a device needs a port to be named)");
      }
      expanded += arg.substr(at, open - at) + it->second;
      at = close + 1;
    }
    out.push_back(expanded);
  }
  return out;
}

std::string ExecutableDir() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : self.parent_path().string();
}

}  // namespace vlab::lab
