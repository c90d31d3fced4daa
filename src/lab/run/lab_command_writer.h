// Command sources: everything that writes a device's command input, and the
// one rule between them (one claimant per device).
//
// A command source is a CommandWriter. The lab has four kinds of them today:
//   the wire        a served device's UDP clients (an external program, a
//                   `vlab serve` peer): LabBridge's newest accepted command
//   the built-in    controller type joint_pd and its kin: one arm
//   task programs   controller type task: each program's robot arm
//   devices         a device that drives another (point, tool: their arm)
// Each names the devices it writes (Claims()). The lab puts every claim into
// one ClaimTable when the lab is made (the wire's when its sockets are bound):
// a second claim on a device is refused there, with a message that names both
// claimants. Nothing else checks who writes what.
//
// Each control period the run asks every source, in a fixed order (the wire,
// the built-in controller, the task programs, the devices in scenario order),
// to write its commands (Write); the physics of the period follows.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

namespace vlab::lab {

struct RunOptions;
struct RunResult;

/// What a source gets each period, the same for every source.
struct CommandPeriod {
  long k = 0;                    ///< the period's index (0: the run's first period, and row 0)
  double t_s = 0.0;              ///< its start, k T, s
  double* columns = nullptr;     ///< the controller's log columns of the period's row (task, built-in)
  const mjData* data = nullptr;  ///< the state at t_s (read only: the period's physics has not begun)
  double pace_s = 0.0;           ///< wall seconds per period of a realtime clock (0 otherwise): the wire's watchdog
  const RunOptions* options = nullptr;  ///< the run's options (replay, record)
  RunResult* result = nullptr;          ///< the run's result (recordings)
};

/// One device's command input claimed by a source.
struct Claim {
  std::string device;  ///< the device whose command input is written
  std::string who;     ///< how messages name the claimant: "point device 'hand'", "the built-in controller"
  std::string where;   ///< "FILE:LINE" of the scenario entry that makes the claim
};

/// Writes the command input of the devices it claims. The period path
/// (Write) never throws and never allocates.
class CommandWriter {
 public:
  virtual ~CommandWriter() = default;
  /// The devices whose command input it writes, with who claims each.
  virtual std::vector<Claim> Claims() const = 0;
  /// Before row 0 of a run: starts again, and writes its view of the initial
  /// state into period.columns. False on a failure: *failure says why.
  virtual bool Restart(const CommandPeriod& period, std::string* failure) {
    (void)period;
    (void)failure;
    return true;
  }
  /// Writes the commands of period k (after the clock let it begin, before
  /// its physics). False on a failure that ends the run: *failure says why.
  virtual bool Write(const CommandPeriod& period, std::string* failure) = 0;
};

/// One claimant per device's command input: the ownership rule, checked once.
class ClaimTable {
 public:
  /// Claims every device of writer.Claims(). Throws InputError "WHERE: WHO:
  /// device 'D' is driven by OTHER (OTHER_WHERE) already: one owner at a
  /// time" when another claimant holds D.
  void Add(const CommandWriter& writer);
  /// Claims one device's command input; throws as Add.
  void Add(const Claim& claim);
  /// The claim on `device`, or null when nobody claimed it.
  const Claim* Holder(const std::string& device) const;

 private:
  std::map<std::string, Claim> holders_;
};

}  // namespace vlab::lab
