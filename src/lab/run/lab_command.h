// The command line and environment of an external controller (scenario
// controller type `external`): placeholders, and free ports for the programs
// it starts.
//
// Placeholders of controller.command
//   {DEVICE}       ADDRESS:PORT of a served device (a device with a port)
//   {port:DEVICE}  the port alone of a served device
//   {port:NAME}    NAME not a device: a free UDP port of the loopback address,
//                  for a program the command starts that binds a socket of its
//                  own (`vlab vision --port {port:vision}`); one port per NAME,
//                  the same number wherever NAME appears
//   {bin} {scenario_dir} {duration} {out}   see CommandValues
// Environment: the program gets VLAB_DEVICE_<NAME>=ADDRESS:PORT for every
// served device and VLAB_PORT_<NAME>=PORT for every port above (NAME in upper
// case), besides what vlab itself was given.
//
// Free ports: the lab binds a UDP socket of 127.0.0.1 to port 0 for each NAME
// and reads the port the kernel chose; the socket holds the port (against
// other runs, and this run's own sockets) until just before the program
// starts (PortReservations::Release). In the few milliseconds between that and
// the program's own bind, only a process binding that very number can take
// it: the kernel gives a port-0 bind a random free port of its ephemeral range
// (Linux: 32768-60999), so two runs side by side collide about once in 28,000
// such binds that fall in the window; the program then cannot bind and says so.
// Handing the bound socket to the program instead would close that window but
// needs every program to take a descriptor rather than a port number; a
// number works with any program as it is.
// Threading: one thread. Errors: InputError naming the scenario's line.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_udp.h"
#include "lab/run/lab_bridge.h"
#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

/// Ports reserved for the programs of a controller command ({port:NAME}),
/// held by bound sockets until Release().
class PortReservations {
 public:
  PortReservations() = default;
  /// Binds one UDP socket of `address` to a free port for each of `names`.
  /// Throws std::runtime_error naming the name when no port can be bound.
  static PortReservations Reserve(const std::vector<std::string>& names, const std::string& address);
  /// NAME -> port, for every name reserved (kept after Release()).
  const std::map<std::string, int>& ports() const { return ports_; }
  /// Closes the sockets: the ports are free for the programs to bind.
  void Release() { sockets_.clear(); }

 private:
  std::map<std::string, int> ports_;
  std::vector<std::unique_ptr<bridge::UdpSocket>> sockets_;
};

/// The names of {port:NAME} placeholders in `command` that name no device
/// with a port in `scenario`, each once, in order of first appearance. Throws
/// InputError ("WHERE: controller.command: {port:NAME}: ...") for a name that
/// is empty or not of letters, digits and '_'.
std::vector<std::string> CommandPortNames(const Scenario& scenario, const std::string& where);

/// The placeholder values of the scenario's controller command: every served
/// device (ADDRESS:PORT, and port:DEVICE; port 0 before binding), every
/// reserved port (port:NAME; 0 when not reserved yet), bin, scenario_dir,
/// duration, and out: the folder the program may write its own files into
/// (the run's output folder while it is written; "" gives the system's
/// temporary folder).
std::map<std::string, std::string> CommandValues(const Scenario& scenario, const std::vector<ServedDevice>& served,
                                                 const std::string& out_dir = "",
                                                 const std::map<std::string, int>& reserved = {});

/// "NAME=VALUE" entries for the program's environment: VLAB_DEVICE_<DEVICE>
/// for every served device, VLAB_PORT_<NAME> for every served device and
/// reserved port.
std::vector<std::string> CommandEnvironment(const std::vector<ServedDevice>& served,
                                            const std::map<std::string, int>& reserved);

/// Expands {NAME} placeholders of a command line from `values`. Throws
/// InputError ("WHERE: controller.command: unknown placeholder {x} (known: ...)")
/// for a name `values` lacks or an unclosed brace.
std::vector<std::string> ExpandCommand(const std::vector<std::string>& command,
                                       const std::map<std::string, std::string>& values, const std::string& where);

/// The folder holding the running executable ("" when unknown).
std::string ExecutableDir();

}  // namespace vlab::lab
