#include "bridge/bridge_protocol.h"

#include <cmath>
#include <cstring>

#include "bridge/bridge_layouts.h"

namespace vlab::bridge {

void PutDouble(double v, unsigned char* out) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  for (int i = 0; i < 8; ++i) out[i] = static_cast<unsigned char>(bits >> (8 * i));
}

double GetDouble(const unsigned char* in) {
  std::uint64_t bits = 0;
  for (int i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(in[i]) << (8 * i);
  double v;
  std::memcpy(&v, &bits, sizeof(v));
  return v;
}

bool IsWhole(double v, double lo, double hi) { return v >= lo && v <= hi && v == std::floor(v); }

namespace {

// payload positions of the wrench and sim fields (bridge_layouts.h), compile-time constants
constexpr int kWrenchFx = StateIndex(DeviceKind::kWrench, "Fx");
constexpr int kWrenchMz = StateIndex(DeviceKind::kWrench, "Mz");
constexpr int kWrenchFilter = StateIndex(DeviceKind::kWrench, "filter");
constexpr int kWrenchSaturated = StateIndex(DeviceKind::kWrench, "saturated");
constexpr int kSimSimTime = StateIndex(DeviceKind::kSim, "sim_time");
constexpr int kSimMode = StateIndex(DeviceKind::kSim, "mode");
constexpr int kSimClock = StateIndex(DeviceKind::kSim, "clock");
constexpr int kSimPeriods = StateIndex(DeviceKind::kSim, "periods");
constexpr int kSimRefusedPackets = StateIndex(DeviceKind::kSim, "refused_packets");
constexpr int kSimMissedDeadlines = StateIndex(DeviceKind::kSim, "missed_deadlines");
constexpr int kSimRealtimeFactor = StateIndex(DeviceKind::kSim, "realtime_factor");
constexpr int kSimMaxLateness = StateIndex(DeviceKind::kSim, "max_lateness");
constexpr int kSimCommandOp = CommandIndex(DeviceKind::kSim, "op");
constexpr int kSimCommandArg = CommandIndex(DeviceKind::kSim, "arg");
constexpr int kWrenchValues = ValueCount(LayoutOf(DeviceKind::kWrench).state);
constexpr int kSimValues = ValueCount(LayoutOf(DeviceKind::kSim).state);
constexpr int kSimCommandValues = ValueCount(LayoutOf(DeviceKind::kSim).command);
constexpr int kWrenchAxes = 6;  // Fx Fy Fz Mx My Mz, the first six values
static_assert(kWrenchFx == 0 && kWrenchMz == kWrenchAxes - 1, "wrench axes first");

DecodeError Expect(const Header& h, DeviceKind kind, MessageType type) {
  if (h.kind != static_cast<int>(kind)) return DecodeError::kBadKind;
  if (h.type != static_cast<int>(type)) return DecodeError::kBadType;
  return DecodeError::kNone;
}

}  // namespace

const char* DecodeErrorName(DecodeError e) {
  switch (e) {
    case DecodeError::kNone:
      return "ok";
    case DecodeError::kTooShort:
      return "too short";
    case DecodeError::kTooLong:
      return "too long";
    case DecodeError::kBadMagic:
      return "bad magic";
    case DecodeError::kBadVersion:
      return "bad version";
    case DecodeError::kBadKind:
      return "wrong device kind";
    case DecodeError::kBadType:
      return "wrong message type";
    case DecodeError::kBadLength:
      return "bad length";
    case DecodeError::kNotFinite:
      return "non-finite value";
    case DecodeError::kBadValue:
      return "value out of domain";
  }
  return "unknown";
}

void EncodePacket(const Header& h, const double* payload, int count, std::vector<unsigned char>* out) {
  out->resize(static_cast<std::size_t>(kHeaderValues + count) * sizeof(double));
  const double header[kHeaderValues] = {kMagic,
                                        static_cast<double>(kProtocolVersion),
                                        static_cast<double>(h.kind),
                                        static_cast<double>(h.type),
                                        h.seq,
                                        h.time,
                                        static_cast<double>(count)};
  unsigned char* p = out->data();
  for (double v : header) {
    PutDouble(v, p);
    p += 8;
  }
  for (int i = 0; i < count; ++i, p += 8) PutDouble(payload[i], p);
}

DecodeError DecodePacket(const unsigned char* data, std::size_t size, Header* h, std::vector<double>* payload) {
  if (size < kHeaderBytes || size % sizeof(double) != 0) return DecodeError::kTooShort;
  const std::size_t values = size / sizeof(double);
  if (values > static_cast<std::size_t>(kMaxPacketValues)) return DecodeError::kTooLong;
  double header[kHeaderValues];
  for (int i = 0; i < kHeaderValues; ++i) header[i] = GetDouble(data + 8 * i);
  if (header[0] != kMagic) return DecodeError::kBadMagic;
  if (header[1] != kProtocolVersion) return DecodeError::kBadVersion;
  for (double v : header) {
    if (!std::isfinite(v)) return DecodeError::kNotFinite;
  }
  // 0: a describe request to any kind (+0 only: -0 would not survive the round trip through an int)
  if (!IsWhole(header[2], 0, 255) || std::signbit(header[2])) return DecodeError::kBadKind;
  if (!IsWhole(header[3], 1, kMaxMessageType)) return DecodeError::kBadType;
  if (!IsWhole(header[4], 0, 9007199254740992.0)) return DecodeError::kBadValue;
  if (header[6] != static_cast<double>(values - kHeaderValues)) return DecodeError::kBadLength;
  h->kind = static_cast<int>(header[2]);
  h->type = static_cast<int>(header[3]);
  h->seq = header[4];
  h->time = header[5];
  h->length = static_cast<int>(header[6]);
  // the payload last: a sound header is known even when a payload value is not finite
  for (std::size_t i = kHeaderValues; i < values; ++i) {
    if (!std::isfinite(GetDouble(data + 8 * i))) return DecodeError::kNotFinite;
  }
  payload->resize(static_cast<std::size_t>(h->length));
  for (int i = 0; i < h->length; ++i) (*payload)[i] = GetDouble(data + 8 * (kHeaderValues + i));
  return DecodeError::kNone;
}

namespace {

// writes a packet value by value into `out` (sized once; no temporary payload)
class PacketWriter {
 public:
  PacketWriter(DeviceKind kind, MessageType type, double seq, double time, std::size_t count,
               std::vector<unsigned char>* out)
      : out_(out) {
    out->resize((kHeaderValues + count) * sizeof(double));
    for (double v : {kMagic, static_cast<double>(kProtocolVersion), static_cast<double>(kind),
                     static_cast<double>(type), seq, time, static_cast<double>(count)}) {
      Put(v);
    }
  }
  void Put(double v) {
    PutDouble(v, out_->data() + at_);
    at_ += sizeof(double);
  }
  void Put(const std::vector<double>& values) {
    for (double v : values) Put(v);
  }

 private:
  std::vector<unsigned char>* out_;
  std::size_t at_ = 0;
};

}  // namespace

void EncodeArmState(double seq, double time, const ArmStateMsg& m, std::vector<unsigned char>* out) {
  PacketWriter w(DeviceKind::kArm, MessageType::kState, seq, time, 1 + m.q.size() + m.qd.size() + m.tau.size(), out);
  w.Put(static_cast<double>(m.status));
  w.Put(m.q);
  w.Put(m.qd);
  w.Put(m.tau);
}

void EncodeArmCommand(double seq, double time, const ArmCommandMsg& m, std::vector<unsigned char>* out) {
  PacketWriter w(DeviceKind::kArm, MessageType::kCommand, seq, time, 1 + m.value.size(), out);
  w.Put(m.mode);
  w.Put(m.value);
}

void EncodeWrenchState(double seq, double time, const WrenchStateMsg& m, std::vector<unsigned char>* out) {
  double v[kWrenchValues];
  for (int i = 0; i < kWrenchAxes; ++i) v[kWrenchFx + i] = m.wrench[i];
  v[kWrenchFilter] = m.filter;
  v[kWrenchSaturated] = m.saturated ? 1.0 : 0.0;
  PacketWriter w(DeviceKind::kWrench, MessageType::kState, seq, time, kWrenchValues, out);
  for (double x : v) w.Put(x);
}

void EncodeSimState(double seq, double time, const SimStateMsg& m, std::vector<unsigned char>* out) {
  double v[kSimValues];
  v[kSimSimTime] = m.sim_time;
  v[kSimMode] = m.mode;
  v[kSimClock] = m.clock;
  v[kSimPeriods] = m.periods;
  v[kSimRefusedPackets] = m.refused_packets;
  v[kSimMissedDeadlines] = m.missed_deadlines;
  v[kSimRealtimeFactor] = m.realtime_factor;
  v[kSimMaxLateness] = m.max_lateness;
  PacketWriter w(DeviceKind::kSim, MessageType::kState, seq, time, kSimValues, out);
  for (double x : v) w.Put(x);
}

void EncodeSimCommand(double seq, double time, const SimCommandMsg& m, std::vector<unsigned char>* out) {
  double v[kSimCommandValues];
  v[kSimCommandOp] = m.op;
  v[kSimCommandArg] = m.arg;
  PacketWriter w(DeviceKind::kSim, MessageType::kCommand, seq, time, kSimCommandValues, out);
  for (double x : v) w.Put(x);
}

DecodeError ParseArmState(const Header& h, const std::vector<double>& p, int joints, ArmStateMsg* m) {
  if (DecodeError e = Expect(h, DeviceKind::kArm, MessageType::kState); e != DecodeError::kNone) return e;
  const int n = joints >= 0 ? joints : (h.length - 1) / 3;
  if (n < 1 || h.length != 1 + 3 * n) return DecodeError::kBadLength;
  if (!IsWhole(p[0], 0, 4294967295.0)) return DecodeError::kBadValue;
  m->status = static_cast<std::uint32_t>(p[0]);
  m->q.assign(p.begin() + 1, p.begin() + 1 + n);
  m->qd.assign(p.begin() + 1 + n, p.begin() + 1 + 2 * n);
  m->tau.assign(p.begin() + 1 + 2 * n, p.begin() + 1 + 3 * n);
  return DecodeError::kNone;
}

DecodeError ParseArmCommand(const Header& h, const std::vector<double>& p, int joints, ArmCommandMsg* m) {
  if (DecodeError e = Expect(h, DeviceKind::kArm, MessageType::kCommand); e != DecodeError::kNone) return e;
  const int n = joints >= 0 ? joints : h.length - 1;
  if (n < 1 || h.length != 1 + n) return DecodeError::kBadLength;
  if (!IsWhole(p[0], 0, 3)) return DecodeError::kBadValue;
  m->mode = static_cast<int>(p[0]);
  m->value.assign(p.begin() + 1, p.end());
  return DecodeError::kNone;
}

DecodeError ParseWrenchState(const Header& h, const std::vector<double>& p, WrenchStateMsg* m) {
  if (DecodeError e = Expect(h, DeviceKind::kWrench, MessageType::kState); e != DecodeError::kNone) return e;
  if (h.length != kWrenchValues) return DecodeError::kBadLength;
  const double filter = p[kWrenchFilter], saturated = p[kWrenchSaturated];
  if (!IsWhole(filter, 0, 6) || !IsWhole(saturated, 0, 1)) return DecodeError::kBadValue;
  for (int i = 0; i < kWrenchAxes; ++i) m->wrench[i] = p[kWrenchFx + i];
  m->filter = static_cast<int>(filter);
  m->saturated = saturated != 0.0;
  return DecodeError::kNone;
}

DecodeError ParseSimState(const Header& h, const std::vector<double>& p, SimStateMsg* m) {
  if (DecodeError e = Expect(h, DeviceKind::kSim, MessageType::kState); e != DecodeError::kNone) return e;
  if (h.length != kSimValues) return DecodeError::kBadLength;
  const double mode = p[kSimMode], clock = p[kSimClock];
  if (!IsWhole(mode, 0, 1) || !IsWhole(clock, 0, 2)) return DecodeError::kBadValue;
  m->sim_time = p[kSimSimTime];
  m->mode = static_cast<int>(mode);
  m->clock = static_cast<int>(clock);
  m->periods = p[kSimPeriods];
  m->refused_packets = p[kSimRefusedPackets];
  m->missed_deadlines = p[kSimMissedDeadlines];
  m->realtime_factor = p[kSimRealtimeFactor];
  m->max_lateness = p[kSimMaxLateness];
  return DecodeError::kNone;
}

DecodeError ParseSimCommand(const Header& h, const std::vector<double>& p, SimCommandMsg* m) {
  if (DecodeError e = Expect(h, DeviceKind::kSim, MessageType::kCommand); e != DecodeError::kNone) return e;
  if (h.length != kSimCommandValues) return DecodeError::kBadLength;
  // check everything before writing: *m is untouched on error
  const double op_value = p[kSimCommandOp], arg = p[kSimCommandArg];
  if (!IsWhole(op_value, 1, 5)) return DecodeError::kBadValue;
  const int op = static_cast<int>(op_value);
  if (op == static_cast<int>(SimOp::kStep) && !IsWhole(arg, 1, 1e9)) return DecodeError::kBadValue;
  if (op == static_cast<int>(SimOp::kSetRealtimeFactor) && !(arg > 0 && arg <= 1000)) return DecodeError::kBadValue;
  m->op = op;
  m->arg = arg;
  return DecodeError::kNone;
}

const char* KindName(int kind) {
  const KindLayout* k = FindKindLayout(kind);
  return k != nullptr ? k->name : "unknown";
}

int KindFromName(const std::string& name) {
  const KindLayout* k = FindKindLayout(std::string_view(name));
  return k != nullptr ? static_cast<int>(k->kind) : 0;
}

}  // namespace vlab::bridge
