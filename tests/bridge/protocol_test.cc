// Tests bridge/bridge_protocol.cc: every layout round-trips, every malformed
// datagram is refused with its reason, and the worked example of
// docs/protocol.md is exactly what EncodePacket writes.
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_layouts.h"

namespace vlab::bridge::protocol_test {
namespace {

using Bytes = std::vector<unsigned char>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// raw little-endian float64 datagram, no checks: for building bad ones
Bytes Raw(const std::vector<double>& values) {
  Bytes out(values.size() * 8);
  for (std::size_t i = 0; i < values.size(); ++i) PutDouble(values[i], out.data() + 8 * i);
  return out;
}

std::string Hex(const Bytes& bytes) {
  std::string s;
  char two[3];
  for (unsigned char b : bytes) {
    std::snprintf(two, sizeof(two), "%02x", b);
    s += two;
  }
  return s;
}

DecodeError Decode(const Bytes& bytes, Header* h = nullptr, std::vector<double>* payload = nullptr) {
  Header scratch_h;
  std::vector<double> scratch_p;
  return DecodePacket(bytes.data(), bytes.size(), h ? h : &scratch_h, payload ? payload : &scratch_p);
}

// a valid arm command datagram for 7 joints, as doubles, to corrupt one field at a time
std::vector<double> ArmCommandValues() { return {kMagic, 2, 1, 2, 42, 1.5, 8, 2, 0.5, -0.25, 0.125, 0, 1, -1, 0.0625}; }

TEST(ProtocolTest, DoublesAreLittleEndianWhateverTheHost) {
  unsigned char b[8];
  PutDouble(1.0, b);  // 0x3ff0000000000000
  const unsigned char one[8] = {0, 0, 0, 0, 0, 0, 0xf0, 0x3f};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(b[i], one[i]) << i;
  EXPECT_EQ(GetDouble(one), 1.0);
  PutDouble(-0.0625, b);
  EXPECT_EQ(GetDouble(b), -0.0625);
}

// docs/protocol.md, "A worked example", value by value (protocol_doc_test reads the page's hex)
TEST(ProtocolTest, WorkedExampleOfTheDocsMatchesEncodePacket) {
  const std::string documented =
      "000080501093d541"   // magic 1447838018
      "0000000000000040"   // version 2
      "000000000000f03f"   // kind 1 (arm)
      "0000000000000040"   // type 2 (command)
      "0000000000004540"   // seq 42
      "000000000000f83f"   // time 1.5
      "0000000000002040"   // length 8
      "0000000000000040"   // mode 2 (velocity)
      "000000000000e03f"   // 0.5
      "000000000000d0bf"   // -0.25
      "000000000000c03f"   // 0.125
      "0000000000000000"   // 0
      "000000000000f03f"   // 1
      "000000000000f0bf"   // -1
      "000000000000b03f";  // 0.0625
  ArmCommandMsg m;
  m.mode = 2;
  m.value = {0.5, -0.25, 0.125, 0, 1, -1, 0.0625};
  Bytes bytes;
  EncodeArmCommand(42, 1.5, m, &bytes);
  EXPECT_EQ(bytes.size(), 120u);
  EXPECT_EQ(Hex(bytes), documented);
  EXPECT_EQ(Hex(Raw(ArmCommandValues())), documented);
}

TEST(ProtocolTest, ArmStateRoundTrip) {
  ArmStateMsg in;
  in.status = kStatusHolding | kStatusNotOwner;
  in.q = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7};
  in.qd = {-1, -2, -3, -4, -5, -6, -7};
  in.tau = {10, 20, 30, 40, 50, 60, 70.5};
  Bytes bytes;
  EncodeArmState(17, 0.034, in, &bytes);
  EXPECT_EQ(bytes.size(), 8u * (7 + 22));
  Header h;
  std::vector<double> p;
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  EXPECT_EQ(h.kind, 1);
  EXPECT_EQ(h.type, 1);
  EXPECT_EQ(h.seq, 17);
  EXPECT_EQ(h.time, 0.034);
  EXPECT_EQ(h.length, 22);
  ArmStateMsg out;
  ASSERT_EQ(ParseArmState(h, p, 7, &out), DecodeError::kNone);
  EXPECT_EQ(out.status, in.status);
  EXPECT_EQ(out.q, in.q);
  EXPECT_EQ(out.qd, in.qd);
  EXPECT_EQ(out.tau, in.tau);
  ASSERT_EQ(ParseArmState(h, p, -1, &out), DecodeError::kNone);  // joints from the length
  EXPECT_EQ(out.tau, in.tau);
  EXPECT_EQ(ParseArmState(h, p, 6, &out), DecodeError::kBadLength);
}

TEST(ProtocolTest, ArmCommandRoundTripEveryMode) {
  for (int mode = 0; mode <= 3; ++mode) {
    ArmCommandMsg in;
    in.mode = mode;
    in.value = {1.25, -2.5, 3, 0, 0, 0, -7};
    Bytes bytes;
    EncodeArmCommand(9, 2.0, in, &bytes);
    Header h;
    std::vector<double> p;
    ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
    ArmCommandMsg out;
    ASSERT_EQ(ParseArmCommand(h, p, 7, &out), DecodeError::kNone) << mode;
    EXPECT_EQ(out.mode, mode);
    EXPECT_EQ(out.value, in.value);
    EXPECT_EQ(ParseArmCommand(h, p, 6, &out), DecodeError::kBadLength);
  }
}

TEST(ProtocolTest, WrenchStateRoundTrip) {
  WrenchStateMsg in;
  const double w[6] = {1.5, -2, 30, 0.25, -0.5, 0.125};
  for (int i = 0; i < 6; ++i) in.wrench[i] = w[i];
  in.filter = 4;
  in.saturated = true;
  Bytes bytes;
  EncodeWrenchState(3, 0.006, in, &bytes);
  EXPECT_EQ(bytes.size(), 8u * 15);
  Header h;
  std::vector<double> p;
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  WrenchStateMsg out;
  ASSERT_EQ(ParseWrenchState(h, p, &out), DecodeError::kNone);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(out.wrench[i], w[i]);
  EXPECT_EQ(out.filter, 4);
  EXPECT_TRUE(out.saturated);
}

TEST(ProtocolTest, SimStateAndCommandRoundTrip) {
  SimStateMsg in{12.5, 1, 2, 6250, 3, 4, 0.5, 0.0015};
  Bytes bytes;
  EncodeSimState(6250, 12.5, in, &bytes);
  Header h;
  std::vector<double> p;
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  SimStateMsg out;
  ASSERT_EQ(ParseSimState(h, p, &out), DecodeError::kNone);
  EXPECT_EQ(out.sim_time, 12.5);
  EXPECT_EQ(out.mode, 1);
  EXPECT_EQ(out.clock, 2);
  EXPECT_EQ(out.periods, 6250);
  EXPECT_EQ(out.refused_packets, 3);
  EXPECT_EQ(out.missed_deadlines, 4);
  EXPECT_EQ(out.realtime_factor, 0.5);
  EXPECT_EQ(out.max_lateness, 0.0015);

  const SimCommandMsg commands[] = {{1, 0}, {2, 0}, {3, 0}, {4, 10}, {5, 2.5}};
  for (const SimCommandMsg& c : commands) {
    EncodeSimCommand(7, 1.0, c, &bytes);
    ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
    SimCommandMsg back;
    ASSERT_EQ(ParseSimCommand(h, p, &back), DecodeError::kNone) << c.op;
    EXPECT_EQ(back.op, c.op);
    EXPECT_EQ(back.arg, c.arg);
  }
}

TEST(ProtocolTest, RequestsCarryCookieAndArgument) {
  Bytes bytes;
  EncodeDescribeRequest(2, 12345, &bytes);
  EXPECT_EQ(bytes.size(), kHeaderBytes + 16);  // 72 bytes: as large as the session reply it may get
  Header h;
  std::vector<double> p;
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  EXPECT_EQ(h.kind, 2);
  EXPECT_EQ(h.type, 3);
  EXPECT_EQ(p, (std::vector<double>{12345, 0}));
  EncodeDescribeRequest(0, 0, &bytes);  // kind 0: any device
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  EXPECT_EQ(h.kind, 0);
  EncodeSubscribeRequest(DeviceKind::kCamera, 7, 0, &bytes);
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  EXPECT_EQ(h.kind, 4);
  EXPECT_EQ(h.type, 4);
  EXPECT_EQ(p, (std::vector<double>{7, 0}));
  EXPECT_FALSE(IsSessionReply(bytes.data(), bytes.size()));
}

TEST(ProtocolTest, FramingErrors) {
  const Bytes good = Raw(ArmCommandValues());
  ASSERT_EQ(Decode(good), DecodeError::kNone);

  EXPECT_EQ(Decode(Bytes()), DecodeError::kTooShort);
  EXPECT_EQ(Decode(Bytes(good.begin(), good.begin() + 48)), DecodeError::kTooShort);  // 6 values
  EXPECT_EQ(Decode(Bytes(good.begin(), good.end() - 1)), DecodeError::kTooShort);     // odd size
  Bytes longer = good;
  longer.push_back(0);
  EXPECT_EQ(Decode(longer), DecodeError::kTooShort);

  std::vector<double> huge(kMaxPacketValues + 1, 0.0);
  huge[0] = kMagic;
  huge[1] = 2;
  huge[2] = 1;
  huge[3] = 2;
  huge[6] = kMaxPacketValues + 1 - kHeaderValues;
  EXPECT_EQ(Decode(Raw(huge)), DecodeError::kTooLong);
  huge.pop_back();
  huge[6] = kMaxPacketValues - kHeaderValues;
  EXPECT_EQ(Decode(Raw(huge)), DecodeError::kNone);  // the largest allowed

  auto with = [](int index, double value) {
    std::vector<double> v = ArmCommandValues();
    v[index] = value;
    return Decode(Raw(v));
  };
  EXPECT_EQ(with(0, 1447838019), DecodeError::kBadMagic);
  EXPECT_EQ(with(0, kNaN), DecodeError::kBadMagic);
  EXPECT_EQ(with(1, 1), DecodeError::kBadVersion);  // version 1: no sessions
  EXPECT_EQ(with(1, 3), DecodeError::kBadVersion);
  EXPECT_EQ(with(2, -1), DecodeError::kBadKind);  // (0 frames: a describe request to any kind)
  EXPECT_EQ(with(2, 1.5), DecodeError::kBadKind);
  EXPECT_EQ(with(2, 256), DecodeError::kBadKind);
  EXPECT_EQ(with(3, 0), DecodeError::kBadType);
  EXPECT_EQ(with(3, 7), DecodeError::kBadType);
  EXPECT_EQ(with(4, -1), DecodeError::kBadValue);    // seq below 0
  EXPECT_EQ(with(4, 2.5), DecodeError::kBadValue);   // seq not whole
  EXPECT_EQ(with(4, 1e17), DecodeError::kBadValue);  // seq beyond 2^53
  EXPECT_EQ(with(6, 7), DecodeError::kBadLength);
  EXPECT_EQ(with(6, 9), DecodeError::kBadLength);
  EXPECT_EQ(with(6, 8.5), DecodeError::kBadLength);
  // NaN and Inf anywhere after magic and version
  for (int i = 2; i < static_cast<int>(ArmCommandValues().size()); ++i) {
    EXPECT_EQ(with(i, kNaN), DecodeError::kNotFinite) << "NaN at " << i;
    EXPECT_EQ(with(i, kInf), DecodeError::kNotFinite) << "Inf at " << i;
    EXPECT_EQ(with(i, -kInf), DecodeError::kNotFinite) << "-Inf at " << i;
  }
}

TEST(ProtocolTest, ParseChecksKindTypeAndLayout) {
  Header h;
  std::vector<double> p;
  Bytes bytes;
  ArmStateMsg arm_state;
  ArmCommandMsg arm_command;
  WrenchStateMsg wrench;
  SimStateMsg sim_state;
  SimCommandMsg sim_command;

  // an arm command is no arm state, wrench or sim message
  ASSERT_EQ(Decode(Raw(ArmCommandValues()), &h, &p), DecodeError::kNone);
  EXPECT_EQ(ParseArmState(h, p, 7, &arm_state), DecodeError::kBadType);
  EXPECT_EQ(ParseWrenchState(h, p, &wrench), DecodeError::kBadKind);
  EXPECT_EQ(ParseSimState(h, p, &sim_state), DecodeError::kBadKind);
  EXPECT_EQ(ParseSimCommand(h, p, &sim_command), DecodeError::kBadKind);
  // a wrench state is no arm message, and a sim state no sim command
  EncodeWrenchState(0, 0, WrenchStateMsg{}, &bytes);
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  EXPECT_EQ(ParseArmState(h, p, -1, &arm_state), DecodeError::kBadKind);
  EXPECT_EQ(ParseArmCommand(h, p, -1, &arm_command), DecodeError::kBadKind);
  EncodeSimState(0, 0, SimStateMsg{}, &bytes);
  ASSERT_EQ(Decode(bytes, &h, &p), DecodeError::kNone);
  EXPECT_EQ(ParseSimCommand(h, p, &sim_command), DecodeError::kBadType);

  auto parse = [&](std::vector<double> v, auto parser) {
    Header hh;
    std::vector<double> pp;
    const DecodeError e = Decode(Raw(v), &hh, &pp);
    return e != DecodeError::kNone ? e : parser(hh, pp);
  };
  auto arm_command_parser = [&](const Header& hh, const std::vector<double>& pp) {
    return ParseArmCommand(hh, pp, 7, &arm_command);
  };
  auto arm_state_parser = [&](const Header& hh, const std::vector<double>& pp) {
    return ParseArmState(hh, pp, -1, &arm_state);
  };
  auto wrench_parser = [&](const Header& hh, const std::vector<double>& pp) {
    return ParseWrenchState(hh, pp, &wrench);
  };
  auto sim_state_parser = [&](const Header& hh, const std::vector<double>& pp) {
    return ParseSimState(hh, pp, &sim_state);
  };
  auto sim_command_parser = [&](const Header& hh, const std::vector<double>& pp) {
    return ParseSimCommand(hh, pp, &sim_command);
  };

  // arm command: mode 0..3 only
  constexpr int kMode = kHeaderValues + CommandIndex(DeviceKind::kArm, "mode");
  std::vector<double> v = ArmCommandValues();
  v[kMode] = 4;
  EXPECT_EQ(parse(v, arm_command_parser), DecodeError::kBadValue);
  v[kMode] = -1;
  EXPECT_EQ(parse(v, arm_command_parser), DecodeError::kBadValue);
  v[kMode] = 1.5;
  EXPECT_EQ(parse(v, arm_command_parser), DecodeError::kBadValue);
  // arm state: 1 + 3n values, status a whole number >= 0
  EXPECT_EQ(parse({kMagic, 2, 1, 1, 0, 0, 4, 0, 1, 2, 3}, arm_state_parser), DecodeError::kNone);
  EXPECT_EQ(parse({kMagic, 2, 1, 1, 0, 0, 3, 0, 1, 2}, arm_state_parser), DecodeError::kBadLength);
  EXPECT_EQ(parse({kMagic, 2, 1, 1, 0, 0, 1, 0}, arm_state_parser), DecodeError::kBadLength);
  EXPECT_EQ(parse({kMagic, 2, 1, 1, 0, 0, 4, -1, 1, 2, 3}, arm_state_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 1, 1, 0, 0, 4, 0.5, 1, 2, 3}, arm_state_parser), DecodeError::kBadValue);
  // wrench state: 8 values, filter 0..6, saturated 0/1
  EXPECT_EQ(parse({kMagic, 2, 2, 1, 0, 0, 8, 0, 0, 0, 0, 0, 0, 6, 1}, wrench_parser), DecodeError::kNone);
  EXPECT_EQ(parse({kMagic, 2, 2, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0}, wrench_parser), DecodeError::kBadLength);
  EXPECT_EQ(parse({kMagic, 2, 2, 1, 0, 0, 8, 0, 0, 0, 0, 0, 0, 7, 0}, wrench_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 2, 1, 0, 0, 8, 0, 0, 0, 0, 0, 0, 0, 2}, wrench_parser), DecodeError::kBadValue);
  // sim state: mode 0/1, clock 0..2
  EXPECT_EQ(parse({kMagic, 2, 3, 1, 0, 0, 8, 0, 2, 0, 0, 0, 0, 1, 0}, sim_state_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 1, 0, 0, 8, 0, 0, 3, 0, 0, 0, 1, 0}, sim_state_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 1}, sim_state_parser), DecodeError::kBadLength);
  // sim command: op 1..5, step a whole number of periods >= 1, factor in (0, 1000]
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 0, 0}, sim_command_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 6, 0}, sim_command_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 4, 0}, sim_command_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 4, 2.5}, sim_command_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 5, 0}, sim_command_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 5, 1001}, sim_command_parser), DecodeError::kBadValue);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 3, 1, 0, 0}, sim_command_parser), DecodeError::kBadLength);
  EXPECT_EQ(parse({kMagic, 2, 3, 2, 0, 0, 2, 4, 3}, sim_command_parser), DecodeError::kNone);
}

TEST(ProtocolTest, NamesOfKindsAndErrors) {
  EXPECT_STREQ(KindName(1), "arm");
  EXPECT_STREQ(KindName(2), "wrench");
  EXPECT_STREQ(KindName(3), "sim");
  EXPECT_STREQ(KindName(4), "camera");
  EXPECT_STREQ(KindName(11), "yoyo");
  EXPECT_STREQ(KindName(12), "gaze");
  EXPECT_STREQ(KindName(13), "pose");
  EXPECT_STREQ(KindName(14), "counter");
  EXPECT_STREQ(KindName(kMaxDeviceKind + 1), "unknown");
  EXPECT_STREQ(KindName(0), "unknown");
  EXPECT_EQ(KindFromName("sim"), 3);
  EXPECT_EQ(KindFromName("camera"), 4);
  EXPECT_EQ(KindFromName("webcam"), 0);
  EXPECT_STREQ(DecodeErrorName(DecodeError::kNotFinite), "non-finite value");
}

}  // namespace
}  // namespace vlab::bridge::protocol_test
