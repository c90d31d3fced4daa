// Coverage-guided fuzzer (libFuzzer, clang) for the bridge's wire protocol and
// its device-side handler. Built and run by tests/fuzz/run_fuzz.sh.
//
// Each input is one datagram. It goes through
//   1. DecodePacket and, when the framing is valid, every Parse* (arm joint
//      counts -1, 1 and 7). The framing is re-encoded and must give back the
//      input's bytes; whatever parses is re-encoded and must decode and parse
//      to the same message, bit for bit;
//   2. a fresh arm, sim and wrench DeviceEndpoint in a fixed scenario: two
//      clients subscribed (the cookie handshake), an accepted command
//      pending, then the datagram comes from the owner, again (a duplicate),
//      from the second subscriber, from it once the owner timed out (on the
//      endpoint's wall clock, a fake one here), from a third client that never
//      subscribed, and from the first once the others' subscriptions lapsed.
//      A finding there reproduces from the input alone;
//   3. long-lived endpoints that see every input, from two alternating
//      clients, with the period advancing every few inputs (BeginPeriod,
//      Take*Command, Publish), so ownership, watchdog and subscriber code run
//      across inputs (a finding there may need the inputs before it).
// In a describe or subscribe request, cookie 1 stands for the sender's real
// cookie (the harness puts it in), so that the fuzzer reaches the paths past
// the handshake; any other cookie is what the input says.
// After each step the endpoint's invariants are checked: the counters add up,
// only a well-formed command answering a published state is accepted, only a
// well-formed payload (type 6: 10 finite values of a rigid body, a seq >= 1
// above the owner's last) is taken by an arm, and by no other kind, the
// subscribers never outnumber the table, and a taken command is one the
// device accepts. A broken invariant or round trip aborts with a message; that,
// and any sanitizer report, is a finding.
//
// Network: one device socket and three client sockets, all bound by this
// process on 127.0.0.1 (port 0) and never read, so describe replies and
// published states stay on loopback and reach no other program.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_payload.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_udp.h"

namespace vlab::bridge {
namespace {

constexpr int kArmJoints = 7;
constexpr int kInputsPerPeriod = 4;  // long-lived endpoints: inputs between two periods

[[noreturn]] void Fail(const char* what) {
  std::fprintf(stderr, "packet_fuzzer: invariant broken: %s\n", what);
  std::abort();
}

void Check(bool ok, const char* what) {
  if (!ok) Fail(what);
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }
bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// ---- 1. decode, parse, round trip --------------------------------------------

// decodes re-encoded bytes; they must carry header `h` unchanged
void DecodeAgain(const std::vector<unsigned char>& bytes, const Header& h, Header* h2, std::vector<double>* p2) {
  Check(DecodePacket(bytes.data(), bytes.size(), h2, p2) == DecodeError::kNone, "re-encoded packet does not decode");
  Check(h2->kind == h.kind && h2->type == h.type && SameBits(h2->seq, h.seq) && SameBits(h2->time, h.time) &&
            h2->length == h.length,
        "header changed in a round trip");
}

void CheckArmRoundTrips(const Header& h, const std::vector<double>& p, int joints) {
  std::vector<unsigned char> bytes;
  Header h2;
  std::vector<double> p2;
  ArmStateMsg s, s2;
  if (ParseArmState(h, p, joints, &s) == DecodeError::kNone) {
    Check(joints < 0 || s.q.size() == static_cast<std::size_t>(joints), "arm state: joint count not honoured");
    EncodeArmState(h.seq, h.time, s, &bytes);
    DecodeAgain(bytes, h, &h2, &p2);
    Check(ParseArmState(h2, p2, joints, &s2) == DecodeError::kNone && s2.status == s.status && SameBits(s2.q, s.q) &&
              SameBits(s2.qd, s.qd) && SameBits(s2.tau, s.tau),
          "arm state round trip");
  }
  ArmCommandMsg c, c2;
  if (ParseArmCommand(h, p, joints, &c) == DecodeError::kNone) {
    Check(joints < 0 || c.value.size() == static_cast<std::size_t>(joints), "arm command: joint count not honoured");
    EncodeArmCommand(h.seq, h.time, c, &bytes);
    DecodeAgain(bytes, h, &h2, &p2);
    Check(
        ParseArmCommand(h2, p2, joints, &c2) == DecodeError::kNone && c2.mode == c.mode && SameBits(c2.value, c.value),
        "arm command round trip");
  }
}

void CheckRoundTrips(const unsigned char* data, std::size_t size, const Header& h, const std::vector<double>& p) {
  std::vector<unsigned char> bytes;
  Header h2;
  std::vector<double> p2;
  // framing: the input's own bytes, bar the sign of a zero length field
  EncodePacket(h, p.data(), h.length, &bytes);
  Check(bytes.size() == size, "re-encoded packet has another size");
  Check(std::memcmp(bytes.data(), data, 6 * sizeof(double)) == 0 &&
            std::memcmp(bytes.data() + kHeaderBytes, data + kHeaderBytes, size - kHeaderBytes) == 0,
        "re-encoded packet has other bytes");
  DecodeAgain(bytes, h, &h2, &p2);
  Check(SameBits(p2, p), "payload round trip");

  for (int joints : {-1, 1, kArmJoints}) CheckArmRoundTrips(h, p, joints);
  WrenchStateMsg w, w2;
  if (ParseWrenchState(h, p, &w) == DecodeError::kNone) {
    EncodeWrenchState(h.seq, h.time, w, &bytes);
    DecodeAgain(bytes, h, &h2, &p2);
    bool same =
        ParseWrenchState(h2, p2, &w2) == DecodeError::kNone && w2.filter == w.filter && w2.saturated == w.saturated;
    for (int i = 0; i < 6; ++i) same = same && SameBits(w2.wrench[i], w.wrench[i]);
    Check(same, "wrench state round trip");
  }
  SimStateMsg s, s2;
  if (ParseSimState(h, p, &s) == DecodeError::kNone) {
    EncodeSimState(h.seq, h.time, s, &bytes);
    DecodeAgain(bytes, h, &h2, &p2);
    Check(ParseSimState(h2, p2, &s2) == DecodeError::kNone && SameBits(s2.sim_time, s.sim_time) && s2.mode == s.mode &&
              s2.clock == s.clock && SameBits(s2.periods, s.periods) &&
              SameBits(s2.refused_packets, s.refused_packets) && SameBits(s2.missed_deadlines, s.missed_deadlines) &&
              SameBits(s2.realtime_factor, s.realtime_factor) && SameBits(s2.max_lateness, s.max_lateness),
          "sim state round trip");
  }
  SimCommandMsg c, c2;
  if (ParseSimCommand(h, p, &c) == DecodeError::kNone) {
    EncodeSimCommand(h.seq, h.time, c, &bytes);
    DecodeAgain(bytes, h, &h2, &p2);
    Check(ParseSimCommand(h2, p2, &c2) == DecodeError::kNone && c2.op == c.op && SameBits(c2.arg, c.arg),
          "sim command round trip");
  }
}

// ---- endpoints and their invariants --------------------------------------------

// the endpoints' wall clock: advanced by the harness
double g_now_s = 1000;

struct Net {
  std::unique_ptr<UdpSocket> device = UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<UdpSocket> client_a = UdpSocket::Bind("127.0.0.1", 0);  // a sink: never read
  std::unique_ptr<UdpSocket> client_b = UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<UdpSocket> client_c = UdpSocket::Bind("127.0.0.1", 0);
  Endpoint a = client_a->local_endpoint();
  Endpoint b = client_b->local_endpoint();
  Endpoint c = client_c->local_endpoint();
};

EndpointConfig ArmConfig() {
  ArmDescription d;
  d.name = "fuzz_arm";
  d.joints = {"j1", "j2", "j3", "j4", "j5", "j6", "j7"};
  d.position_min.assign(kArmJoints, -2.9);
  d.position_max.assign(kArmJoints, 2.9);
  d.velocity_max.assign(kArmJoints, 2.0);
  d.torque_max = {150, 150, 100, 100, 50, 30, 30};
  EndpointConfig c;
  c.name = d.name;
  c.kind = DeviceKind::kArm;
  c.describe_json = DescribeJson(d);
  c.owner_timeout_s = 0.04;
  c.subscriber_timeout_s = 0.08;
  c.clock = [] { return g_now_s; };
  c.watchdog_periods = 3;
  c.joints = kArmJoints;
  c.position_min = d.position_min;
  c.position_max = d.position_max;
  c.velocity_max = d.velocity_max;
  c.torque_max = d.torque_max;
  c.max_subscribers = 2;
  return c;
}

EndpointConfig SimConfig() {
  SimDescription d;
  d.name = "fuzz_sim";
  d.devices = {"fuzz_arm", "fuzz_wrench"};
  EndpointConfig c;
  c.name = d.name;
  c.kind = DeviceKind::kSim;
  c.describe_json = DescribeJson(d);
  c.owner_timeout_s = 0.04;
  c.subscriber_timeout_s = 0.08;
  c.clock = [] { return g_now_s; };
  c.max_subscribers = 1;  // the second client is refused: the table is full
  return c;
}

EndpointConfig WrenchConfig() {
  WrenchDescription d;
  d.name = "fuzz_wrench";
  d.full_scale = {200, 200, 400, 12, 12, 12};
  EndpointConfig c;
  c.name = d.name;
  c.kind = DeviceKind::kWrench;
  c.describe_json = DescribeJson(d);
  c.subscriber_timeout_s = 0.08;
  c.clock = [] { return g_now_s; };
  return c;
}

void CheckCounters(const DeviceEndpoint& ep) {
  const EndpointCounters& c = ep.counters();
  Check(c.refused == c.refused_malformed + c.refused_limits + c.refused_not_owner + c.refused_not_subscribed,
        "refused != sum of its reasons");
  Check(c.received == c.accepted + c.payloads + c.requests + c.refused + c.stale + c.duplicate + c.future,
        "received != accepted + payloads + requests + refused + stale + duplicate + future");
  Check(c.describes <= c.requests, "more describe replies than requests");
  Check(ep.subscribers() <= ep.config().max_subscribers, "more subscribers than the table holds");
}

// an accepted datagram is a well-formed command of the device's kind, now the last seq
void CheckAfterHandle(const DeviceEndpoint& ep, DeviceEndpoint::Received received, const unsigned char* data,
                      std::size_t size) {
  const bool accepted = received == DeviceEndpoint::Received::kCommand;
  CheckCounters(ep);
  if (ep.config().kind == DeviceKind::kWrench) Check(!accepted && !ep.has_owner(), "wrench accepted a command");
  Header h;
  std::vector<double> p;
  if (received == DeviceEndpoint::Received::kPayload) {  // a sound payload, now the arm's
    ArmPayloadMsg m;
    const char* field = nullptr;
    const char* reason = nullptr;
    Check(ep.config().kind == DeviceKind::kArm, "a device other than an arm took a payload");
    Check(DecodePacket(data, size, &h, &p) == DecodeError::kNone && ParseArmPayload(h, p, &m) == DecodeError::kNone,
          "took a malformed payload");
    Check(CheckArmPayload(m, &field, &reason), "took a payload that is no rigid body");
    Check(ep.payload() == m && ep.has_owner(), "took a payload, but the arm does not report it or has no owner");
    Check(h.seq >= kFirstPayloadSeq && h.seq == ep.last_payload_seq(),
          "took a payload, but its seq is below 1 or not the owner's last payload seq");
  }
  if (!accepted) return;
  Check(DecodePacket(data, size, &h, &p) == DecodeError::kNone, "accepted a malformed datagram");
  Check(h.kind == static_cast<int>(ep.config().kind) && h.type == static_cast<int>(MessageType::kCommand),
        "accepted something other than a command of its kind");
  Check(h.seq == ep.last_accepted_seq(), "accepted, but last_accepted_seq is not the command's seq");
  Check(ep.has_owner(), "accepted, but the device has no owner");
}

// the datagram as `from` sends it: cookie 1 in a request becomes from's real cookie
const unsigned char* WithCookie(const DeviceEndpoint& ep, const unsigned char* data, std::size_t size,
                                const Endpoint& from, std::vector<unsigned char>* patched) {
  Header h;
  std::vector<double> p;
  if (DecodePacket(data, size, &h, &p) != DecodeError::kNone || p.size() != 2 || p[0] != 1 ||
      (h.type != static_cast<int>(MessageType::kDescribe) && h.type != static_cast<int>(MessageType::kSubscribe))) {
    return data;
  }
  patched->assign(data, data + size);
  PutDouble(ep.cookie(from), patched->data() + kHeaderBytes);
  return patched->data();
}

DeviceEndpoint::Received HandleAs(DeviceEndpoint& ep, const unsigned char* data, std::size_t size, const Endpoint& from,
                                  long period, UdpSocket& device) {
  std::vector<unsigned char> patched;
  const unsigned char* bytes = WithCookie(ep, data, size, from, &patched);
  const DeviceEndpoint::Received r = ep.Handle(bytes, size, from, period, device);
  CheckAfterHandle(ep, r, bytes, size);
  return r;
}

// the handshake of `from`, as a client does it
void Subscribe(DeviceEndpoint& ep, const Endpoint& from, UdpSocket& device) {
  std::vector<unsigned char> request;
  EncodeSubscribeRequest(ep.config().kind, ep.cookie(from), 1, &request);
  CheckAfterHandle(ep, ep.Handle(request.data(), request.size(), from, 0, device), request.data(), request.size());
}

// a command taken from the endpoint must be one it accepts
void CheckTakenArm(const EndpointConfig& config, const ArmCommandMsg& c) {
  Check(c.mode >= 0 && c.mode <= 3, "taken arm command: mode out of domain");
  Check(c.value.size() == static_cast<std::size_t>(config.joints), "taken arm command: wrong joint count");
  for (std::size_t i = 0; i < c.value.size(); ++i) {
    const double v = c.value[i];
    Check(std::isfinite(v), "taken arm command: non-finite value");
    if (c.mode == 1) Check(v >= config.position_min[i] && v <= config.position_max[i], "taken arm command: position");
    if (c.mode == 2) Check(std::abs(v) <= config.velocity_max[i], "taken arm command: velocity beyond limit");
    if (c.mode == 3) Check(std::abs(v) <= config.torque_max[i], "taken arm command: torque beyond limit");
  }
}

void CheckTakenSim(const SimCommandMsg& c) {
  std::vector<unsigned char> bytes;
  EncodeSimCommand(1, 0, c, &bytes);
  Header h;
  std::vector<double> p;
  SimCommandMsg again;
  Check(DecodePacket(bytes.data(), bytes.size(), &h, &p) == DecodeError::kNone &&
            ParseSimCommand(h, p, &again) == DecodeError::kNone,
        "taken sim command is one the device refuses (op/arg out of domain)");
}

void TakeAndCheck(DeviceEndpoint& ep) {
  ArmCommandMsg arm;
  SimCommandMsg sim;
  if (ep.TakeArmCommand(&arm)) CheckTakenArm(ep.config(), arm);
  if (ep.TakeSimCommand(&sim)) CheckTakenSim(sim);
  ArmPayloadMsg payload;
  const char* field = nullptr;
  const char* reason = nullptr;
  if (ep.TakePayload(&payload)) {
    Check(ep.config().kind == DeviceKind::kArm, "taken payload: not an arm");
    Check(CheckArmPayload(payload, &field, &reason), "taken payload: no rigid body");
  }
}

// the state the device would publish this period
std::vector<unsigned char> StatePacket(const DeviceEndpoint& ep, long period) {
  std::vector<unsigned char> out;
  const double seq = static_cast<double>(period), time = 0.001 * static_cast<double>(period);
  switch (ep.config().kind) {
    case DeviceKind::kArm: {
      ArmStateMsg s;
      s.status = kStatusHolding | ep.status_bits();
      s.q.assign(kArmJoints, 0.1);
      s.qd.assign(kArmJoints, 0.0);
      s.tau.assign(kArmJoints, -1.5);
      EncodeArmState(seq, time, s, &out);
      break;
    }
    case DeviceKind::kWrench:
      EncodeWrenchState(seq, time, WrenchStateMsg{}, &out);
      break;
    case DeviceKind::kSim: {
      SimStateMsg s;
      s.sim_time = time;
      s.periods = seq;
      s.refused_packets = static_cast<double>(ep.counters().refused);
      EncodeSimState(seq, time, s, &out);
      break;
    }
    default:  // the configs above are arms, sims and wrenches only
      Check(false, "a state packet for a kind the fuzzer does not configure");
      break;
  }
  return out;
}

// ---- 2. one datagram in a fixed scenario, fresh endpoint -----------------------

void RunScenario(const EndpointConfig& config, const unsigned char* data, std::size_t size, Net& net) {
  g_now_s = 1000;
  DeviceEndpoint ep(config);
  long period = 0;
  auto handle = [&](const Endpoint& from) { HandleAs(ep, data, size, from, period, *net.device); };
  // clients a and b subscribed (b may find the table full), state 0 published;
  // a owns the device, with an accepted command (seq 0) not taken yet
  Subscribe(ep, net.a, *net.device);
  Subscribe(ep, net.b, *net.device);
  ep.Publish(StatePacket(ep, period), *net.device);
  std::vector<unsigned char> primer;
  if (config.kind == DeviceKind::kArm) {
    ArmCommandMsg hold;
    hold.value.assign(kArmJoints, 0.0);
    EncodeArmCommand(0, 0, hold, &primer);
  } else if (config.kind == DeviceKind::kSim) {
    EncodeSimCommand(0, 0, {static_cast<int>(SimOp::kPause), 0}, &primer);
  } else {
    EncodeDescribeRequest(static_cast<int>(config.kind), ep.cookie(net.a), &primer);
  }
  CheckAfterHandle(ep, ep.Handle(primer.data(), primer.size(), net.a, period, *net.device), primer.data(),
                   primer.size());
  handle(net.a);  // from the owner
  TakeAndCheck(ep);
  handle(net.a);  // the same again: a duplicate
  handle(net.b);  // from another subscriber while a owns the device
  period += 5;
  g_now_s += config.owner_timeout_s * 1.5;
  ep.BeginPeriod(period);  // the owner fell silent: watchdog
  ep.ReleaseSilentOwner();
  ep.Publish(StatePacket(ep, period), *net.device);
  handle(net.b);  // b takes over
  TakeAndCheck(ep);
  handle(net.c);  // a client that never subscribed
  period += 10;
  g_now_s += config.subscriber_timeout_s * 1.5;
  ep.Publish(StatePacket(ep, period), *net.device);  // the others fell silent: dropped as subscribers
  handle(net.a);
  TakeAndCheck(ep);
  ep.Publish(StatePacket(ep, period), *net.device);
}

// ---- 3. long-lived endpoints across inputs -------------------------------------

struct LongLived {
  DeviceEndpoint arm{ArmConfig()};
  DeviceEndpoint sim{SimConfig()};
  DeviceEndpoint wrench{WrenchConfig()};
  long inputs = 0;
  long period = 0;
  double now_s = 5000;  // its own time line (RunScenario resets the shared clock)
};

void RunLongLived(LongLived& l, const unsigned char* data, std::size_t size, Net& net) {
  g_now_s = l.now_s;
  const Endpoint& from = l.inputs % 2 == 0 ? net.a : net.b;
  for (DeviceEndpoint* ep : {&l.arm, &l.sim, &l.wrench}) {
    if (l.inputs % 64 == 0) Subscribe(*ep, from, *net.device);  // now and then, as clients renew
    HandleAs(*ep, data, size, from, l.period, *net.device);
  }
  if (++l.inputs % kInputsPerPeriod != 0) return;
  ++l.period;
  l.now_s += 0.002;
  g_now_s = l.now_s;
  for (DeviceEndpoint* ep : {&l.arm, &l.sim, &l.wrench}) {
    ep->BeginPeriod(l.period);
    TakeAndCheck(*ep);
    ep->Publish(StatePacket(*ep, l.period), *net.device);
  }
}

}  // namespace
}  // namespace vlab::bridge

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vlab::bridge;
  static Net net;
  static const EndpointConfig configs[] = {ArmConfig(), SimConfig(), WrenchConfig()};
  static LongLived long_lived;

  Header header;
  std::vector<double> payload;
  if (DecodePacket(data, size, &header, &payload) == DecodeError::kNone) {
    CheckRoundTrips(data, size, header, payload);
  }
  for (const EndpointConfig& config : configs) RunScenario(config, data, size, net);
  RunLongLived(long_lived, data, size, net);
  return 0;
}
