// The C++ client of the vlab wire protocol (docs/protocol.md): typed handles
// for the devices an external controller talks to, and a fixed-rate loop.
//
//   Arm    input  command [mode, v_1..v_n]     output state [status, q, qd, tau]
//   Wrench input  none                         output state [F (N), M (N m), filter, saturated]
//   Sim    input  command [op, arg]            output state [sim_time, mode, clock, ...]
//
// Connecting makes a session (docs/protocol.md, "Sessions"): the client gets
// its cookie, the describe reply and a subscription; from then on the device
// sends it one state per control period. Destroying a handle unsubscribes it. A controller's
// loop is Read (or ReadLatest) -> compute -> Write(..., seq = state.seq); the
// seq of a command must be the seq of the state it answers. Read and Connect
// block up to their timeout; Write never blocks. A Read waits as the lab
// does: it polls for up to kClientSpin_s (yielding the CPU between polls),
// then sleeps; a lockstep state, which comes tens of microseconds after the
// command, is then taken without a thread wake-up (docs/protocol.md).
//
// Threading: a handle is not thread-safe; use one from one thread at a time.
// Errors (bridge_errors.h): NetworkError, ProtocolError, VersionMismatch,
// TimeoutError; std::invalid_argument for a caller's own mistake (wrong
// number of values, non-finite values, negative seq).
#pragma once

#include "bridge/bridge_loop.h"  // FixedRateLoop, for client programs

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

namespace vlab::bridge {
/// How long a client's Read polls before it sleeps, s (the lab spins as long).
inline constexpr double kClientSpin_s = 200e-6;
}  // namespace vlab::bridge

#include "bridge/bridge_errors.h"
#include "bridge/bridge_messages.h"
#include "bridge/bridge_payload.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"
#include "bridge/bridge_udp.h"

namespace vlab::bridge {

/// What every device handle shares: its socket, the describe reply and the
/// reception of states. Movable, not copyable; a moved-from handle may only be
/// destroyed or assigned to.
class DeviceClient {
 public:
  DeviceClient(DeviceClient&&) noexcept;
  DeviceClient& operator=(DeviceClient&&) noexcept;
  virtual ~DeviceClient();

  /// The device's describe reply (JSON object), as received at connect.
  const nlohmann::json& describe() const;
  /// The device's name from its describe reply ("pa10"), or "" if it has none.
  const std::string& name() const { return name_; }
  DeviceKind kind() const { return kind_; }
  /// The device's address and port.
  const Endpoint& device_endpoint() const { return device_; }
  /// "arm 'pa10' at 127.0.0.1:50010", for messages.
  std::string Label() const;
  /// The local UDP port the client receives states on.
  int local_port() const;

  /// Renews the subscription without waiting for the reply (Read skips
  /// it). A passive client (one that never writes) must do this now and then
  /// to stay subscribed: the device drops subscribers silent for a
  /// scenario-defined time (10 s by default). False if the send failed.
  bool KeepAlive();

  /// Asks for a receive buffer of `bytes` on the client's socket (forced where
  /// the process may: SetSocketBuffer), so that states wait there while the
  /// program is not scheduled instead of being dropped; a recorder asks for
  /// one. Returns the size the kernel granted (getsockopt's figure), or -1.
  int GrowReceiveBuffer(int bytes);

  /// Datagrams Read/ReadLatest skipped: describe and session replies and
  /// datagrams from other ports than the device's.
  long skipped() const { return skipped_; }

 protected:
  /// Opens a socket on bind_address, port 0 (any free port), and makes a
  /// session with address:port (cookie, describe reply, subscription) within
  /// timeout_s, skipping states that arrive meanwhile. Checks "protocol" and
  /// "kind" of the reply.
  DeviceClient(DeviceKind kind, const std::string& address, int port, double timeout_s,
               const std::string& bind_address);

  /// Turns one framed state of this device's kind into the derived class's
  /// message; returns kNone or why the layout is wrong.
  virtual DecodeError ParseState(const Header& header, const std::vector<double>& payload) = 0;
  /// Waits up to timeout_s for the next state and parses it (ParseState);
  /// with `latest`, then also parses whatever states are already queued, so
  /// the newest wins. Returns its header. Throws TimeoutError, ProtocolError.
  const Header& ReceiveState(double timeout_s, bool latest);
  /// Encodes nothing: sends an already encoded packet. False if the send failed.
  bool Send(const std::vector<unsigned char>& packet);
  /// Seconds since connect on the monotonic clock: the time field of commands.
  double ClientTime() const;
  /// Checks a command seq (a whole number >= 0 that fits the wire); throws
  /// std::invalid_argument.
  static void CheckSeq(std::int64_t seq);
  /// Waits up to timeout_s for a session reply carrying `yes` or `no` and
  /// returns which; skips everything else (states too: counted in skipped()).
  /// Throws TimeoutError naming `what`. (bridge_client_payload.cc)
  SessionResult AwaitSessionResult(SessionResult yes, SessionResult no, double timeout_s, const std::string& what);
  /// The kept describe reply, for a handle that learns a fact the device now reports.
  nlohmann::json& mutable_describe() { return *describe_; }

  std::vector<unsigned char> packet_;  ///< scratch for encoding

 private:
  /// Parses and checks the describe reply ("protocol", "kind"), keeps it.
  void CheckDescribe(const unsigned char* json, long size);
  /// Receives one datagram from the device within the deadline; false on timeout.
  bool ReceiveFromDevice(std::chrono::steady_clock::time_point deadline, long* size);
  /// Checks one received datagram: false for a describe reply (skipped),
  /// true for a state of this kind (parsed when `parse`); throws
  /// VersionMismatch or ProtocolError on anything else.
  bool AcceptState(long size, bool parse);

  DeviceKind kind_;
  Endpoint device_;
  std::unique_ptr<UdpSocket> socket_;
  std::unique_ptr<ClientSession> session_;
  std::unique_ptr<nlohmann::json> describe_;  // the full JSON type stays in the .cc
  std::string name_;
  std::chrono::steady_clock::time_point start_;
  std::vector<unsigned char> buffer_;
  std::vector<double> payload_;
  Header header_;
  long skipped_ = 0;
};

/// A robot arm: n joints, commanded in hold, position, velocity or torque mode.
class Arm : public DeviceClient {
 public:
  /// One state, sampled by the device at the end of control period `seq`.
  struct State {
    std::int64_t seq = 0;      ///< control period k; answer with Write(..., seq)
    double time = 0;           ///< simulated time of the sample, s
    std::uint32_t status = 0;  ///< ArmStatusBit flags (bridge_protocol.h)
    Eigen::VectorXd q;         ///< joint positions, rad
    Eigen::VectorXd qd;        ///< joint velocities, rad/s
    Eigen::VectorXd tau;       ///< applied joint torques, N m
  };

  /// Connects to the arm device at address:port (numeric IPv4/IPv6 or a host
  /// name; port 1..65535): describes it and subscribes to its states.
  /// Throws NetworkError (bad address, no socket), TimeoutError (no reply
  /// within timeout_s, s), VersionMismatch (another protocol version),
  /// ProtocolError (not an arm, or a malformed reply).
  static Arm Connect(const std::string& address, int port, double timeout_s = 1.0,
                     const std::string& bind_address = "0.0.0.0");

  /// Number of joints, from the describe reply.
  int joints() const { return static_cast<int>(joint_names_.size()); }
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  /// Limits from the describe reply, one per joint, or empty where the device
  /// has none: positions (rad), |velocity| (rad/s), |torque| (N m).
  const std::vector<double>& position_min() const { return position_min_; }
  const std::vector<double>& position_max() const { return position_max_; }
  const std::vector<double>& velocity_max() const { return velocity_max_; }
  const std::vector<double>& torque_max() const { return torque_max_; }

  /// Waits up to timeout_s (s) for the next state. Throws TimeoutError, or
  /// ProtocolError when the device sends a malformed state.
  State Read(double timeout_s);
  /// The same into `state` (no allocation once its vectors have the size).
  void Read(double timeout_s, State* state);
  /// Waits up to timeout_s for at least one state, then drains the queue and
  /// returns the newest: what a real-time controller wants. Throws as Read.
  State ReadLatest(double timeout_s);
  void ReadLatest(double timeout_s, State* state);

  /// Sends a command answering the state `seq`: mode and one value per joint
  /// (rad, rad/s or N m by mode; ignored for hold). Never blocks; false if the
  /// datagram could not be sent. Throws std::invalid_argument on a wrong
  /// value count, a non-finite value or a negative seq. Whether the device
  /// accepted it shows in the status bits of the next states.
  bool Write(ArmMode mode, const Eigen::VectorXd& values, std::int64_t seq);

  /// Declares the load at the flange (mass kg, centre of mass m and inertia
  /// kg m^2 about it, flange frame: docs/protocol.md, "Arm payload") and waits
  /// up to timeout_s for the device's answer; in force from the device's next
  /// control period. States that arrive meanwhile are skipped (a lockstep
  /// device sends none before this client's next command). Each payload sent
  /// carries the next value of this handle's own payload counter (1, 2, 3,
  /// ...) as its seq, so that the device can refuse a late or replayed copy
  /// of an older one. Throws std::invalid_argument naming the field for a
  /// payload that is no rigid body (not finite, negative mass, inertia not
  /// positive semi-definite or breaking the triangle inequality),
  /// RefusedError when the device refuses it (another client owns the arm),
  /// TimeoutError when no answer came, NetworkError when it could not be
  /// sent. (bridge_client_payload.cc)
  void SetPayload(const ArmPayloadMsg& payload, double timeout_s = 1.0);
  /// The payload the device reports: its describe reply's at connect, or the
  /// last one SetPayload set (zero mass when the reply has none).
  ArmPayloadMsg payload() const;

 private:
  Arm(const std::string& address, int port, double timeout_s, const std::string& bind_address);
  DecodeError ParseState(const Header& header, const std::vector<double>& payload) override;
  void CopyState(const Header& header, State* state) const;

  std::vector<std::string> joint_names_;
  std::vector<double> position_min_, position_max_, velocity_max_, torque_max_;
  ArmStateMsg message_;
  std::vector<double> command_payload_;  ///< [mode, v_1..v_n], sized at connect
  std::int64_t payload_seq_ = 0;         ///< seq of the last payload sent (its own counter)
};

/// A force/torque sensor: output only.
class Wrench : public DeviceClient {
 public:
  struct State {
    std::int64_t seq = 0;  ///< control period k
    double time = 0;       ///< simulated time of the sample, s
    /// Fx Fy Fz (N), Mx My Mz (N m), sensor frame
    Eigen::Matrix<double, 6, 1> wrench = Eigen::Matrix<double, 6, 1>::Zero();
    int filter = 0;          ///< filter index the values come from (0 unfiltered)
    bool saturated = false;  ///< an axis was beyond its range during the period
  };

  /// Connects to the wrench device at address:port; throws as Arm::Connect.
  static Wrench Connect(const std::string& address, int port, double timeout_s = 1.0,
                        const std::string& bind_address = "0.0.0.0");
  /// Next state / newest state; throw as Arm::Read. A wrench client never
  /// writes, so call KeepAlive() now and then to stay subscribed.
  State Read(double timeout_s);
  State ReadLatest(double timeout_s);

 private:
  Wrench(const std::string& address, int port, double timeout_s, const std::string& bind_address);
  DecodeError ParseState(const Header& header, const std::vector<double>& payload) override;
  State Copy(const Header& header) const;
  WrenchStateMsg message_;
};

/// The simulation's own control device: pause, resume, step, reset, pace.
class Sim : public DeviceClient {
 public:
  /// SimStateMsg's fields (sim_time s, mode 0 running / 1 paused, clock
  /// ClockCode, periods, refused_packets, missed_deadlines, realtime_factor,
  /// max_lateness s) plus the header's seq and time.
  struct State : SimStateMsg {
    std::int64_t seq = 0;
    double time = 0;  ///< s
  };

  /// Connects to the sim device at address:port; throws as Arm::Connect.
  static Sim Connect(const std::string& address, int port, double timeout_s = 1.0,
                     const std::string& bind_address = "0.0.0.0");
  State Read(double timeout_s);
  State ReadLatest(double timeout_s);
  /// Sends an operation answering state `seq` (arg: periods for kStep, the
  /// factor for kSetRealtimeFactor, else 0). Never blocks; false if not sent.
  /// Throws std::invalid_argument on a non-finite arg or negative seq.
  bool Write(SimOp op, double arg, std::int64_t seq);

 private:
  Sim(const std::string& address, int port, double timeout_s, const std::string& bind_address);
  DecodeError ParseState(const Header& header, const std::vector<double>& payload) override;
  State Copy(const Header& header) const;
  SimStateMsg message_;
};

}  // namespace vlab::bridge
