#include "bridge/bridge_client.h"

#include <sched.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <ctime>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

namespace vlab::bridge {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kMaxSeq = 9007199254740992.0;  // 2^53: the largest whole seq a double holds exactly

Clock::time_point After(Clock::time_point t, double s) {
  return t + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s > 0 ? s : 0));
}

// a json array of numbers with `n` entries, or empty; throws ProtocolError
std::vector<double> Limits(const nlohmann::json& limits, const char* field, std::size_t n, const std::string& label) {
  if (!limits.is_object() || !limits.contains(field)) return {};
  const nlohmann::json& a = limits[field];
  const bool ok = a.is_array() && (a.empty() || a.size() == n) &&
                  std::all_of(a.begin(), a.end(), [](const nlohmann::json& v) { return v.is_number(); });
  if (!ok) {
    throw ProtocolError(label + ": describe field limits." + field + " is not an array of " + std::to_string(n) +
                        " numbers");
  }
  return a.get<std::vector<double>>();
}

}  // namespace

// ---- DeviceClient ---------------------------------------------------------------

const nlohmann::json& DeviceClient::describe() const { return *describe_; }

DeviceClient::DeviceClient(DeviceClient&&) noexcept = default;
DeviceClient& DeviceClient::operator=(DeviceClient&&) noexcept = default;

DeviceClient::DeviceClient(DeviceKind kind, const std::string& address, int port, double timeout_s,
                           const std::string& bind_address)
    : kind_(kind), device_(UdpSocket::Resolve(address, port)), start_(Clock::now()), buffer_(kDatagramBufferBytes) {
  payload_.reserve(kMaxPacketValues);
  // an IPv6 device needs an IPv6 socket
  const bool any_v4 = bind_address == "0.0.0.0";
  socket_ = UdpSocket::Bind(any_v4 && device_.address().is_v6() ? "::" : bind_address, 0);
  session_ = std::make_unique<ClientSession>(kind_, Label());
  // the handshake: the cookie, then the describe reply and the subscription;
  // states arriving meanwhile are checked for their kind and skipped
  session_->Connect(
      *socket_, device_, timeout_s, &buffer_,
      [this](const unsigned char* json, long size) { CheckDescribe(json, size); },
      [this](long size) { AcceptState(size, false); }, &skipped_);
}

DeviceClient::~DeviceClient() {
  if (session_ && socket_) session_->Leave(*socket_, device_);
}

void DeviceClient::CheckDescribe(const unsigned char* json, long size) {
  try {
    describe_ = std::make_unique<nlohmann::json>(nlohmann::json::parse(json, json + size));
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError(Label() + ": describe reply is not valid JSON: " + e.what());
  }
  if (!describe_->is_object()) throw ProtocolError(Label() + ": describe reply is not a JSON object");
  const nlohmann::json version = describe_->value("protocol", nlohmann::json());
  if (!version.is_number()) throw ProtocolError(Label() + ": describe reply has no numeric \"protocol\"");
  if (version.get<double>() != kProtocolVersion) {
    throw VersionMismatch(Label() + ": the device speaks protocol version " + version.dump() +
                          ", this client speaks version " + std::to_string(kProtocolVersion));
  }
  const std::string want = KindName(static_cast<int>(kind_));
  const nlohmann::json kind = describe_->value("kind", nlohmann::json());
  if (!kind.is_string() || kind.get<std::string>() != want) {
    throw ProtocolError(Label() + ": the device is of kind " + kind.dump() + ", not \"" + want + "\"");
  }
  const nlohmann::json name = describe_->value("name", nlohmann::json());
  if (name.is_string()) name_ = name.get<std::string>();
}

std::string DeviceClient::Label() const {
  std::string label = KindName(static_cast<int>(kind_));
  if (!name_.empty()) label += " '" + name_ + "'";
  return label + " at " + EndpointText(device_);
}

int DeviceClient::local_port() const { return socket_->local_port(); }

bool DeviceClient::KeepAlive() { return session_->KeepAlive(*socket_, device_); }

int DeviceClient::GrowReceiveBuffer(int bytes) { return SetSocketBuffer(socket_->fd(), SO_RCVBUF, bytes); }

bool DeviceClient::Send(const std::vector<unsigned char>& packet) {
  return socket_->SendTo(packet.data(), packet.size(), device_);
}

double DeviceClient::ClientTime() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

void DeviceClient::CheckSeq(std::int64_t seq) {
  if (seq < 0 || static_cast<double>(seq) > kMaxSeq) {
    throw std::invalid_argument("command seq " + std::to_string(seq) + " out of range 0..2^53");
  }
}

bool DeviceClient::ReceiveFromDevice(Clock::time_point deadline, long* size) {
  // poll briefly first (a lockstep answer comes within tens of microseconds, and a
  // sleeping thread's wake-up costs as much again), yielding so a peer on this core runs
  const Clock::time_point spin_until =
      std::min(deadline, Clock::now() +
                             std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kClientSpin_s)));
  for (;;) {
    Endpoint from;
    long n = socket_->Receive(buffer_.data(), buffer_.size(), &from, 0.0);
    if (n < 0 && Clock::now() < spin_until) {
      ::sched_yield();
      continue;
    }
    if (n < 0) {
      const double left_s = std::chrono::duration<double>(deadline - Clock::now()).count();
      n = socket_->Receive(buffer_.data(), buffer_.size(), &from, left_s > 0 ? left_s : 0);
    }
    if (n < 0) return false;
    // a multi-homed device may answer from another address, never from another port
    if (from.port() != device_.port()) {
      ++skipped_;
      continue;
    }
    *size = n;
    return true;
  }
}

bool DeviceClient::AcceptState(long size, bool parse) {
  if ((size > 0 && buffer_[0] == '{') || IsSessionReply(buffer_.data(), static_cast<std::size_t>(size))) {
    ++skipped_;  // a describe reply, or the answer to a renewal
    return false;
  }
  Header header;
  DecodeError e = DecodePacket(buffer_.data(), static_cast<std::size_t>(size), &header, &payload_);
  if (e == DecodeError::kBadVersion) {
    throw VersionMismatch(Label() + ": the device sent a packet of protocol version " +
                          ErrorNumber(GetDouble(buffer_.data() + 8)) + ", this client speaks version " +
                          std::to_string(kProtocolVersion));
  }
  if (e == DecodeError::kNone && header.kind != static_cast<int>(kind_)) e = DecodeError::kBadKind;
  if (e == DecodeError::kNone && header.type != static_cast<int>(MessageType::kState)) e = DecodeError::kBadType;
  // (not while connecting: the layout, e.g. the joint count, is not known yet)
  if (e == DecodeError::kNone && parse) e = ParseState(header, payload_);
  if (e != DecodeError::kNone) {
    throw ProtocolError(Label() + ": malformed state datagram (" + std::to_string(size) +
                        " bytes): " + DecodeErrorName(e));
  }
  header_ = header;
  return true;
}

const Header& DeviceClient::ReceiveState(double timeout_s, bool latest) {
  const Clock::time_point deadline = After(Clock::now(), timeout_s);
  for (;;) {
    long size = 0;
    if (!ReceiveFromDevice(deadline, &size))
      throw TimeoutError(Label() + ": no state within " + ErrorSeconds(timeout_s));
    if (AcceptState(size, true)) break;
  }
  // drain what is already queued: the newest state wins
  for (long size = 0; latest && ReceiveFromDevice(Clock::now(), &size);) AcceptState(size, true);
  return header_;
}

// ---- Arm --------------------------------------------------------------------------

Arm::Arm(const std::string& address, int port, double timeout_s, const std::string& bind_address)
    : DeviceClient(DeviceKind::kArm, address, port, timeout_s, bind_address) {
  const nlohmann::json& d = describe();
  const nlohmann::json joints = d.value("joints", nlohmann::json());
  const bool ok = joints.is_array() && !joints.empty() &&
                  std::all_of(joints.begin(), joints.end(), [](const nlohmann::json& j) { return j.is_string(); });
  if (!ok) throw ProtocolError(Label() + ": describe reply has no \"joints\" array of names");
  joint_names_ = joints.get<std::vector<std::string>>();
  const std::size_t n = joint_names_.size();
  const nlohmann::json limits = d.value("limits", nlohmann::json::object());
  position_min_ = Limits(limits, "position_min", n, Label());
  position_max_ = Limits(limits, "position_max", n, Label());
  velocity_max_ = Limits(limits, "velocity_max", n, Label());
  torque_max_ = Limits(limits, "torque_max", n, Label());
  command_payload_.resize(1 + n);
}

Arm Arm::Connect(const std::string& address, int port, double timeout_s, const std::string& bind_address) {
  return Arm(address, port, timeout_s, bind_address);
}

DecodeError Arm::ParseState(const Header& header, const std::vector<double>& payload) {
  return ParseArmState(header, payload, joints(), &message_);
}

void Arm::CopyState(const Header& header, State* state) const {
  const int n = joints();
  state->seq = static_cast<std::int64_t>(header.seq);
  state->time = header.time;
  state->status = message_.status;
  state->q = Eigen::Map<const Eigen::VectorXd>(message_.q.data(), n);
  state->qd = Eigen::Map<const Eigen::VectorXd>(message_.qd.data(), n);
  state->tau = Eigen::Map<const Eigen::VectorXd>(message_.tau.data(), n);
}

Arm::State Arm::Read(double timeout_s) {
  State state;
  Read(timeout_s, &state);
  return state;
}

void Arm::Read(double timeout_s, State* state) { CopyState(ReceiveState(timeout_s, false), state); }

Arm::State Arm::ReadLatest(double timeout_s) {
  State state;
  ReadLatest(timeout_s, &state);
  return state;
}

void Arm::ReadLatest(double timeout_s, State* state) { CopyState(ReceiveState(timeout_s, true), state); }

bool Arm::Write(ArmMode mode, const Eigen::VectorXd& values, std::int64_t seq) {
  const int n = joints();
  const bool hold = mode == ArmMode::kHold;
  if (!(hold && values.size() == 0) && values.size() != n) {
    throw std::invalid_argument(Label() + ": command has " + std::to_string(values.size()) + " values, the arm has " +
                                std::to_string(n) + " joints");
  }
  if (!values.allFinite()) throw std::invalid_argument(Label() + ": command has a non-finite value");
  CheckSeq(seq);
  command_payload_[0] = static_cast<double>(mode);
  for (int i = 0; i < n; ++i) command_payload_[1 + i] = values.size() == 0 ? 0.0 : values[i];
  Header header;
  header.kind = static_cast<int>(DeviceKind::kArm);
  header.type = static_cast<int>(MessageType::kCommand);
  header.seq = static_cast<double>(seq);
  header.time = ClientTime();
  EncodePacket(header, command_payload_.data(), 1 + n, &packet_);
  return Send(packet_);
}

// ---- Wrench -----------------------------------------------------------------------

Wrench::Wrench(const std::string& address, int port, double timeout_s, const std::string& bind_address)
    : DeviceClient(DeviceKind::kWrench, address, port, timeout_s, bind_address) {}

Wrench Wrench::Connect(const std::string& address, int port, double timeout_s, const std::string& bind_address) {
  return Wrench(address, port, timeout_s, bind_address);
}

DecodeError Wrench::ParseState(const Header& header, const std::vector<double>& payload) {
  return ParseWrenchState(header, payload, &message_);
}

Wrench::State Wrench::Copy(const Header& header) const {
  State state;
  state.seq = static_cast<std::int64_t>(header.seq);
  state.time = header.time;
  for (int i = 0; i < 6; ++i) state.wrench[i] = message_.wrench[i];
  state.filter = message_.filter;
  state.saturated = message_.saturated;
  return state;
}

Wrench::State Wrench::Read(double timeout_s) { return Copy(ReceiveState(timeout_s, false)); }
Wrench::State Wrench::ReadLatest(double timeout_s) { return Copy(ReceiveState(timeout_s, true)); }

// ---- Sim --------------------------------------------------------------------------

Sim::Sim(const std::string& address, int port, double timeout_s, const std::string& bind_address)
    : DeviceClient(DeviceKind::kSim, address, port, timeout_s, bind_address) {}

Sim Sim::Connect(const std::string& address, int port, double timeout_s, const std::string& bind_address) {
  return Sim(address, port, timeout_s, bind_address);
}

DecodeError Sim::ParseState(const Header& header, const std::vector<double>& payload) {
  return ParseSimState(header, payload, &message_);
}

Sim::State Sim::Copy(const Header& header) const {
  State state;
  static_cast<SimStateMsg&>(state) = message_;
  state.seq = static_cast<std::int64_t>(header.seq);
  state.time = header.time;
  return state;
}

Sim::State Sim::Read(double timeout_s) { return Copy(ReceiveState(timeout_s, false)); }
Sim::State Sim::ReadLatest(double timeout_s) { return Copy(ReceiveState(timeout_s, true)); }

bool Sim::Write(SimOp op, double arg, std::int64_t seq) {
  if (!std::isfinite(arg)) throw std::invalid_argument(Label() + ": sim command arg is not finite");
  CheckSeq(seq);
  EncodeSimCommand(static_cast<double>(seq), ClientTime(), {static_cast<int>(op), arg}, &packet_);
  return Send(packet_);
}

}  // namespace vlab::bridge
