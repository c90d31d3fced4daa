// Device side of the wire: what a device does with the datagrams it receives
// and whom it sends its states to. Shared by every server of a device kind —
// the lab's MuJoCo devices and the kinematic simulator — so that they all
// answer with the same bytes and the same rules.
//
// Ports
//   input   datagrams from clients: commands, describe and subscribe requests (Handle)
//   output  state datagrams to every subscriber, once per control period
//           (Publish); describe replies (JSON) to the requester
//   rate    driven by its owner: Handle whenever a datagram arrives,
//           BeginPeriod/Publish once per control period
// Rules
//   - sessions (bridge_session.h): states go to subscribers only; a client
//     subscribes with a subscribe request after proving its address (the
//     cookie handshake), and a describe request is answered with the JSON only
//     when it carries the cookie; a subscriber silent for
//     subscriber_timeout_s (wall clock) is dropped; a full table makes room
//     for a newcomer by dropping the subscriber heard from least recently
//     that is not the owner (so sockets that only subscribe cannot lock a
//     controller out); only a table that holds nothing but the owner refuses;
//   - a malformed datagram is refused and counted by reason; nothing else changes;
//   - commands (arm, sim and the other commanded kinds) are taken from
//     subscribers only (others: refused_not_subscribed); the subscriber of
//     the first accepted command owns the command input; others are refused
//     (status bit kStatusNotOwner in the states they receive) until the owner
//     has been silent for owner_timeout_s of the wall clock, in every state of
//     the lab (paused too): then the owner is released (ReleaseSilentOwner)
//     and the next accepted command takes over; an owner that unsubscribes
//     gives its input up at once;
//   - a gate (EndpointConfig::gate; the lab's sim device) may refuse a
//     subscriber's commands whoever owns the input, or let one take the input
//     over from its owner; a refused sim op is answered with a session reply
//     kRefused;
//   - a command's seq must be one of the newest kSeqWindow + 1 states the
//     device published (Publish) and higher than the owner's last accepted
//     one: lower is stale, equal a duplicate, not yet published is from the
//     future; all ignored and counted;
//   - arm commands are checked against the joint count and the position,
//     velocity and torque limits; a refused command sets kStatusRefused and
//     leaves the previous command in force;
//   - other commanded kinds (base, gripper, point) have a fixed command length
//     and a check of their own (EndpointConfig::command_length, check_command);
//   - an arm also takes a payload (type 6, bridge_payload.h) through the same
//     subscriber and owner rules as its commands (an accepted payload makes
//     its sender the owner of an arm that has none, as a first command does);
//     it is not a period's command: it feeds no watchdog and answers no
//     lockstep period. Its seq is the sender's own payload counter (1, 2,
//     3, ...): a whole number >= 1 (0: malformed) above the owner's last
//     accepted payload seq (reset when the owner changes), else it is stale
//     (a late or replayed copy) and changes nothing. It must have 10 finite
//     values that make a rigid body (EndpointConfig::check_payload). Every
//     payload from a subscriber is answered with a session reply, kPayloadSet
//     or kPayloadRefused; a refused one is counted like any refused datagram
//     (not owner, malformed; a stale one as stale), sets kStatusRefused when
//     it came from the owner, and changes nothing; an accepted one is taken
//     at the start of the next period (TakePayload) and the describe reply
//     reports it from then on. Any other kind refuses type 6 unanswered;
//   - watchdog: an arm (or other commanded device) that received no accepted command for more than
//     watchdog_periods consecutive periods (3: hold at the start of the 4th,
//     like the PA10's servo link after 3 missed cycles) holds its position
//     (kStatusWatchdog) until the next accepted command. Paced (BeginPeriod's
//     pace_s > 0: a realtime lab), it also takes the oldest state the owner
//     left unanswered to have been out for watchdog_periods - 1 periods of
//     wall time: periods the lab runs back to back to catch up count once;
//   - every subscriber gets the same state; the owner's status bits (refused,
//     watchdog) are in it, and non-owners also get kStatusNotOwner (in the
//     state sent at once to a new subscriber too: SendLatest).
// Never throws and never blocks in Handle, BeginPeriod or Publish.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bridge/bridge_payload.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"
#include "bridge/bridge_udp.h"

namespace vlab::bridge {

/// Counters of a device endpoint (reported by the sim device and in summary.json).
struct EndpointCounters {
  long received = 0;                ///< datagrams received
  long requests = 0;                ///< well-formed describe and subscribe requests (answered, or limited)
  long accepted = 0;                ///< commands accepted
  long describes = 0;               ///< describe requests answered
  long refused = 0;                 ///< all refusals: malformed + limits + not owner (stale and duplicate apart)
  long refused_malformed = 0;       ///< size, magic, version, kind, type, length, NaN/Inf, domain
  long refused_limits = 0;          ///< wrong joint count or a value beyond a limit
  long refused_not_owner = 0;       ///< commands from a non-owner
  long refused_not_subscribed = 0;  ///< commands from a source that is no subscriber
  long stale = 0;                   ///< seq lower than the last accepted, or older than the window (ignored);
                                    ///< payloads: seq not above the owner's last accepted one (refused, answered)
  long stale_window = 0;            ///< of stale: commands older than the window (a controller more than
                                    ///< kSeqWindow periods behind, e.g. catching up after a free run)
  long duplicate = 0;               ///< seq equal to the last accepted (ignored)
  long future = 0;                  ///< seq of a state not published yet (ignored)
  long watchdog_holds = 0;          ///< times the watchdog put the arm on hold
  long owners_released = 0;         ///< owners released after falling silent (or by the lab)
  long payloads = 0;                ///< arm payloads accepted (type 6)
  SessionCounters sessions;         ///< handshakes, subscriptions, rate limits
};

/// What a gate says about a subscriber's command (EndpointConfig::gate).
enum class CommandGate {
  kOpen,      ///< the usual owner rules
  kRefuse,    ///< refused (counted as not owner), whoever owns the input
  kTakeOver,  ///< accepted checks permitting, and it takes the input over from any owner
};

/// Verdict of a kind's command check.
enum class CommandCheck {
  kAccept,
  kMalformed,  ///< a value outside its domain (an unknown mode): counted as malformed
  kLimits,     ///< a value beyond a limit of the device
};

struct EndpointConfig {
  std::string name;
  DeviceKind kind = DeviceKind::kArm;
  std::string describe_json;         ///< the device's describe reply
  double owner_timeout_s = 1;        ///< wall clock
  double subscriber_timeout_s = 10;  ///< wall clock
  int watchdog_periods = 3;          ///< arm only; 0 disables
  // arm only: one entry per joint (empty: no limit of that kind)
  int joints = 0;
  std::vector<double> position_min, position_max, velocity_max, torque_max;
  int max_subscribers = kDefaultMaxSubscribers;
  /// Who may command besides the owner rules (null: anyone, by those rules).
  /// Called in Handle: must not block, throw or allocate.
  std::function<CommandGate(const Endpoint& from)> gate;
  /// Other kinds that take commands (base, gripper, point): the command
  /// payload's length (0: the kind takes no commands, like wrench or feet) ...
  int command_length = 0;
  /// ... and its check of a well-framed payload (null: any finite values).
  std::function<CommandCheck(const std::vector<double>& payload)> check_command;
  /// The state's first payload value is a status word (arm, base, gripper):
  /// non-owners get kStatusNotOwner in it.
  bool status_first = false;
  /// Arm only: the payload at the flange when the device starts (its
  /// describe reply reports it, then every payload accepted) ...
  ArmPayloadMsg payload;
  /// ... and whether a new one is a load the device can take (null:
  /// CheckArmPayload). Called in Handle: must not block or throw.
  std::function<bool(const ArmPayloadMsg& payload)> check_payload;
  /// Wall clock, s (null: the monotonic clock). Tests pass their own.
  std::function<double()> clock;
};

class DeviceEndpoint {
 public:
  explicit DeviceEndpoint(EndpointConfig config);

  /// What one datagram was.
  enum class Received { kOther, kCommand, kSubscribed, kPayload };

  /// Handles one datagram received at period `period` (replies to describe
  /// and subscribe requests through `socket`). Returns kCommand for an
  /// accepted command, kSubscribed for a new subscriber (which the caller
  /// may send the latest state at once).
  Received Handle(const unsigned char* data, std::size_t size, const Endpoint& from, long period, UdpSocket& socket);

  /// Starts period k: runs the arm watchdog. True when the arm must hold.
  /// pace_s: wall seconds per period of a paced (realtime) clock, 0 for
  /// none: then only periods are counted.
  bool BeginPeriod(long period, double pace_s = 0);
  /// Releases an owner silent for owner_timeout_s; true when it did. Call
  /// it now and then in every state (the lab: every period and while paused).
  bool ReleaseSilentOwner();

  /// The newest accepted command not yet taken.
  bool TakeArmCommand(ArmCommandMsg* command);
  bool TakeSimCommand(SimCommandMsg* command);
  /// The newest accepted command of a kind with EndpointConfig::command_length.
  bool TakeCommand(std::vector<double>* payload);
  /// An arm's payload accepted since the last call (the newest); false if none.
  bool TakePayload(ArmPayloadMsg* payload);
  /// The arm's payload: the newest accepted, or the configured one.
  const ArmPayloadMsg& payload() const { return arm_payload_; }
  /// The describe reply as sent now (an arm's: with its payload).
  const std::string& describe_json() const { return describe_json_; }
  /// seq of the last accepted command (-1 if none since the owner took over).
  double last_accepted_seq() const { return last_seq_; }
  /// seq of the last accepted command, whoever sent it, kept when its owner is
  /// released (-1: none yet).
  double newest_accepted_seq() const { return watch_seq_; }
  /// seq of the owner's last accepted payload (0 if none since it took over):
  /// a payload must carry a higher one.
  double last_payload_seq() const { return last_payload_seq_; }
  bool has_owner() const { return owner_.has_value(); }
  /// The owner's address and port (empty when none).
  const std::optional<Endpoint>& owner() const { return owner_; }
  /// Frees the command input now (the lab does this when a lockstep owner
  /// stopped answering): the next sender becomes the owner.
  void ReleaseOwner();

  /// Status bits the endpoint adds for the owner (refused, watchdog).
  std::uint32_t status_bits() const;

  /// Sends one encoded state to every subscriber (and drops the silent
  /// ones). For arm states, subscribers other than the owner get
  /// kStatusNotOwner set when an owner exists. Its seq is the newest a
  /// command may answer.
  void Publish(const std::vector<unsigned char>& state_packet, UdpSocket& socket);
  /// Sends the latest encoded state to one (new) subscriber, with
  /// kStatusNotOwner when another owns the input.
  void SendLatest(const std::vector<unsigned char>& state_packet, const Endpoint& to, UdpSocket& socket);

  const EndpointCounters& counters() const;
  int subscribers() const { return static_cast<int>(sessions_.sessions().size()); }
  /// The cookie of a source (what its challenge carries), for tests.
  double cookie(const Endpoint& from) const { return sessions_.Cookie(from); }
  const EndpointConfig& config() const { return config_; }

 private:
  bool CheckArmLimits(const ArmCommandMsg& command) const;
  // a payload from a subscriber the owner rules let through; `finite`: no NaN or infinity in it
  Received HandlePayload(const Endpoint& from, bool finite, UdpSocket& socket);
  // the state for a non-owner (kStatusNotOwner set) in not_owner_packet_; false when it is the same
  bool MarkNotOwner(const std::vector<unsigned char>& packet);
  // whether the oldest state the owner left unanswered has been out for the watchdog's wall time
  bool UnansweredLongEnough(double pace_s) const;
  static constexpr int kPublishedRing = 128;  // publication times kept, by seq

  EndpointConfig config_;
  mutable EndpointCounters counters_;  // (its sessions part is copied in by counters())
  SessionTable sessions_;
  std::optional<Endpoint> owner_;
  double owner_heard_s_ = 0;
  double last_seq_ = -1;
  double last_payload_seq_ = 0;  // the owner's last accepted payload seq (its own counter)
  double newest_seq_ = -1;       // seq of the newest state published
  long last_command_period_ = 0;
  double watch_seq_ = -1;  // seq of the last accepted command (kept when the owner is released)
  std::array<double, kPublishedRing> published_s_{};  // wall time each recent seq was first published
  bool ever_commanded_ = false;
  bool refused_flag_ = false;
  bool watchdog_hold_ = false;
  bool has_command_ = false;
  ArmCommandMsg arm_command_, parsed_;
  SimCommandMsg sim_command_;
  std::vector<double> command_;  // other kinds
  ArmPayloadMsg arm_payload_;    // arm: the newest accepted payload ...
  bool has_payload_ = false;     // ... not yet taken
  std::string describe_json_;
  // scratch, sized at construction
  Header header_;
  std::vector<double> payload_;
  std::vector<unsigned char> not_owner_packet_;
};

}  // namespace vlab::bridge
