// The vlab wire protocol, version 2: one header shared by servers, clients,
// the kinematic simulator and the tests. docs/protocol.md is its contract.
//
// Every control-rate datagram is an array of little-endian IEEE-754 float64:
//
//   index  field         value
//   0      magic         1447838018 (the ASCII bytes "VLAB" read as a big-endian uint32)
//   1      version       2
//   2      kind          device kind: 1 arm, 2 wrench, 3 sim (4-17: see DeviceKind)
//   3      type          1 state (device -> client), 2 command (client -> device),
//                        3 describe request, 4 subscribe request (client -> device),
//                        5 session reply (device -> client): bridge_session.h,
//                        6 payload (client -> device, arm only): bridge_payload.h
//   4      seq           sequence number (see below)
//   5      time          seconds: simulated time of a state; the sender's clock in a command
//   6      length        number of payload values that follow
//   7...   payload       layout by kind and type (below)
//
// A describe reply is not a float64 array: it is one datagram of UTF-8 JSON
// (it starts with '{'), sent back to the requester's address and port.
//
// Sequence numbers: a state's seq is the control period k it closes (0, 1, 2,
// ...). A command's seq is the seq of the newest state its sender has read,
// i.e. the period it answers. A device accepts a command only when its seq is
// one of the newest kSeqWindow + 1 it published and higher than the owner's
// last accepted one: an older seq is stale, an equal one a duplicate, a seq
// the device has not published yet is from the future; all are ignored and
// counted. In lockstep the lab waits for the command whose seq equals the
// period it published.
//
// Payloads: the fields of every kind's state and command, in order, with
// their units, are the table of bridge_layouts.h (arm: [status, q_1..q_n,
// qd_1..qd_n, tau_1..tau_n] and [mode, value_1..value_n], n joints; wrench,
// sim and the others: fixed lists). Describe and subscribe requests carry
// [cookie, arg] (bridge_session.h).
//
// Decoding never trusts the datagram: sizes, magic, version, kind, type,
// length and finiteness are checked before any value is used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vlab::bridge {

inline constexpr double kMagic = 1447838018.0;  // "VLAB"
inline constexpr int kProtocolVersion = 2;
inline constexpr int kHeaderValues = 7;
inline constexpr std::size_t kHeaderBytes = kHeaderValues * sizeof(double);
/// Largest control-rate datagram accepted (values), header included.
inline constexpr int kMaxPacketValues = 1024;
/// A command may answer any of the newest kSeqWindow + 1 states a device published.
inline constexpr int kSeqWindow = 100;

/// Device kinds. 1-3 are described below; the others have their own headers
/// and sections of docs/protocol.md (camera frames are chunked, not float64).
enum class DeviceKind : int {
  kArm = 1,
  kWrench = 2,
  kSim = 3,
  kCamera = 4,    ///< bridge_camera.h
  kMarkers = 5,   ///< tracked marker poses (vision)
  kBase = 6,      ///< holonomic mobile base
  kGripper = 7,   ///< parallel gripper
  kFeet = 8,      ///< foot force-sensing resistors
  kImu = 9,       ///< gyro and accelerometer
  kPoint = 10,    ///< a commanded point (the yo-yo's hand)
  kYoyo = 11,     ///< yo-yo state
  kGaze = 12,     ///< ground-truth gaze of a camera on a target (lab only)
  kPose = 13,     ///< pose of a tracked frame, like a motion-capture system
  kCounter = 14,  ///< speed counter on a spinning joint (the PowerBall's rpm counter)
  kScene = 15,    ///< poses of every visual body, for viewers (vlab view)
  kWord = 16,     ///< lettered cubes against their slots: is the word spelled (lab only)
  kTool = 17,     ///< a commanded and measured tool pose (position and orientation)
};
inline constexpr int kMaxDeviceKind = 17;
enum class MessageType : int {
  kState = 1,
  kCommand = 2,
  kDescribe = 3,
  kSubscribe = 4,
  kSession = 5,
  kPayload = 6,  ///< an arm's payload at its flange (bridge_payload.h)
};
/// The highest message type a datagram may carry.
inline constexpr int kMaxMessageType = static_cast<int>(MessageType::kPayload);

/// Arm status bits (state payload value 0, as a whole number).
enum ArmStatusBit : std::uint32_t {
  kStatusHolding = 1u << 0,    ///< holding: no command yet, watchdog hold, or hold mode
  kStatusRefused = 1u << 1,    ///< the last command from the owner was refused (NaN, limits, size)
  kStatusSaturated = 1u << 2,  ///< a torque was clipped to its motor range this period
  kStatusAtLimit = 1u << 3,    ///< a joint is at or beyond a position limit
  kStatusWatchdog = 1u << 4,   ///< on hold because the owner fell silent
  kStatusNotOwner = 1u << 5,   ///< sent to a client whose commands are refused: another owns the arm
};

/// Sim device operations (command payload value 0).
enum class SimOp : int { kReset = 1, kPause = 2, kResume = 3, kStep = 4, kSetRealtimeFactor = 5 };
/// Clock codes in the sim state.
enum class ClockCode : int { kFast = 0, kLockstep = 1, kRealtime = 2 };

struct Header {
  int kind = 0;
  int type = 0;
  double seq = 0;
  double time = 0;
  int length = 0;
};

/// Why a datagram was refused.
enum class DecodeError {
  kNone = 0,
  kTooShort,  ///< fewer bytes than a header, or not a whole number of float64
  kTooLong,   ///< more than kMaxPacketValues values
  kBadMagic,
  kBadVersion,
  kBadKind,  ///< not the receiving device's kind
  kBadType,
  kBadLength,  ///< length field does not match the datagram, or the layout
  kNotFinite,  ///< a NaN or infinity anywhere in the datagram
  kBadValue,   ///< a value outside its domain (mode, op, seq not a whole number ≥ 0)
};
const char* DecodeErrorName(DecodeError error);

/// True when `v` is a whole number within [lo, hi] (a field of a decoded datagram).
bool IsWhole(double v, double lo, double hi);

/// One float64 to / from 8 little-endian bytes, whatever the host's byte order.
void PutDouble(double value, unsigned char* out);
double GetDouble(const unsigned char* in);

/// Writes a header and payload as little-endian float64 into `out` (resized).
void EncodePacket(const Header& header, const double* payload, int count, std::vector<unsigned char>* out);

/// Checks a datagram's framing (size, magic, version, finiteness, length
/// field) and splits it. On success fills `header` and `payload` (payload
/// values converted from little-endian) and returns kNone. When only a
/// payload value is not finite (the header is sound) it returns kNotFinite
/// with `header` filled, so that a device can tell the sender which request
/// it refused; `payload` is then left as it was.
DecodeError DecodePacket(const unsigned char* data, std::size_t size, Header* header, std::vector<double>* payload);

// ---- typed messages ----------------------------------------------------------

struct ArmStateMsg {
  std::uint32_t status = 0;
  std::vector<double> q, qd, tau;
};
struct ArmCommandMsg {
  int mode = 0;  ///< 0 hold, 1 position, 2 velocity, 3 torque
  std::vector<double> value;
};
struct WrenchStateMsg {
  double wrench[6] = {0, 0, 0, 0, 0, 0};
  int filter = 0;
  bool saturated = false;
};
struct SimStateMsg {
  double sim_time = 0;
  int mode = 0;   ///< 0 running, 1 paused
  int clock = 0;  ///< ClockCode
  double periods = 0;
  double refused_packets = 0;
  double missed_deadlines = 0;
  double realtime_factor = 1;
  double max_lateness = 0;
};
struct SimCommandMsg {
  int op = 0;
  double arg = 0;
};

/// Typed encoders: write into `out`, resized; no allocation once `out` has the
/// capacity of the packet.
void EncodeArmState(double seq, double time, const ArmStateMsg& m, std::vector<unsigned char>* out);
void EncodeArmCommand(double seq, double time, const ArmCommandMsg& m, std::vector<unsigned char>* out);
void EncodeWrenchState(double seq, double time, const WrenchStateMsg& m, std::vector<unsigned char>* out);
void EncodeSimState(double seq, double time, const SimStateMsg& m, std::vector<unsigned char>* out);
void EncodeSimCommand(double seq, double time, const SimCommandMsg& m, std::vector<unsigned char>* out);
// (describe and subscribe requests: bridge_session.h)

/// Payload -> message, with the layout checks of each kind (`joints` = the
/// arm's joint count, or -1 to take it from the length).
DecodeError ParseArmState(const Header& h, const std::vector<double>& payload, int joints, ArmStateMsg* m);
DecodeError ParseArmCommand(const Header& h, const std::vector<double>& payload, int joints, ArmCommandMsg* m);
DecodeError ParseWrenchState(const Header& h, const std::vector<double>& payload, WrenchStateMsg* m);
DecodeError ParseSimState(const Header& h, const std::vector<double>& payload, SimStateMsg* m);
DecodeError ParseSimCommand(const Header& h, const std::vector<double>& payload, SimCommandMsg* m);

/// Device kind name ("arm" .. "pose", from the table of bridge_layouts.h;
/// "unknown" outside 1..kMaxDeviceKind) and back (0 if unknown).
const char* KindName(int kind);
int KindFromName(const std::string& name);

}  // namespace vlab::bridge
