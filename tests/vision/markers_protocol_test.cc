// The markers device's codec (bridge/bridge_markers.h): layouts byte for
// byte, round trips, and every refusal reason; the dictionary table against
// OpenCV's own.
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/aruco.hpp>

#include "bridge/bridge_markers.h"

namespace vlab::bridge::markers_protocol_test {
namespace {

std::string Hex(const std::vector<unsigned char>& bytes) {
  std::string s;
  char two[3];
  for (unsigned char b : bytes) {
    std::snprintf(two, sizeof(two), "%02x", b);
    s += two;
  }
  return s;
}

MarkerRecordMsg Record(int dictionary, int id, bool world) {
  MarkerRecordMsg r;
  r.dictionary = dictionary;
  r.id = id;
  r.valid = true;
  r.reprojection_error_px = 0.125;
  const double t[16] = {0, -1, 0, 0.1, 1, 0, 0, -0.05, 0, 0, 1, 0.4, 0, 0, 0, 1};
  for (int i = 0; i < 16; ++i) r.T_camera[i] = t[i];
  r.world_valid = world;
  for (int i = 0; i < 16; ++i) r.T_world[i] = world ? (i % 5 == 0 ? 1.0 : 0.0) + (i == 3 ? 0.7 : 0.0) : 0.0;
  return r;
}

// encode -> frame -> parse
DecodeError RoundTrip(const std::vector<unsigned char>& packet, MarkersStateMsg* m) {
  Header h;
  std::vector<double> payload;
  const DecodeError e = DecodePacket(packet.data(), packet.size(), &h, &payload);
  return e != DecodeError::kNone ? e : ParseMarkersState(h, payload, m);
}

// a state packet with one value of its payload replaced
DecodeError WithValue(int index, double value) {
  MarkersStateMsg m;
  m.markers = {Record(0, 3, true)};
  std::vector<unsigned char> packet;
  EncodeMarkersState(5, 0.5, m, &packet);
  PutDouble(value, packet.data() + kHeaderBytes + 8 * index);
  MarkersStateMsg out;
  return RoundTrip(packet, &out);
}

TEST(MarkerDictionaries, MatchOpenCv) {
  ASSERT_EQ(MarkerDictionaries().size(), 21u);
  for (const MarkerDictionary& d : MarkerDictionaries()) {
    const cv::Ptr<cv::aruco::Dictionary> cv_dict = cv::aruco::getPredefinedDictionary(d.code);
    EXPECT_EQ(cv_dict->markerSize, d.bits) << d.name;
    EXPECT_EQ(cv_dict->bytesList.rows, d.markers) << d.name;
    EXPECT_EQ(FindMarkerDictionary(d.code), &d);
    EXPECT_EQ(FindMarkerDictionary(std::string("DICT_") + d.name), &d);
  }
  EXPECT_EQ(FindMarkerDictionary("apriltag_36H11")->code, cv::aruco::DICT_APRILTAG_36h11);
  EXPECT_EQ(FindMarkerDictionary("4x4_50")->code, cv::aruco::DICT_4X4_50);
  EXPECT_EQ(FindMarkerDictionary("4X4_51"), nullptr);
  EXPECT_EQ(FindMarkerDictionary(21), nullptr);
  EXPECT_EQ(FindMarkerDictionary(-1), nullptr);
}

TEST(MarkersCommand, WorkedExampleOfTheProtocolPage) {
  // docs/protocol_markers.md: marker 7 of 4X4_50, side 25 mm, answering state 42, sent at 1.5 s
  std::vector<unsigned char> packet;
  EncodeMarkersCommand(42, 1.5, {{0, 7, 0.025}}, &packet);
  EXPECT_EQ(Hex(packet),
            "000080501093d5410000000000000040000000000000144000000000000000400000000000004540000000000000f83f"
            "000000000000084000000000000000000000000000001c409a9999999999993f");
}

TEST(MarkersCommand, RoundTripAndRefusals) {
  std::vector<unsigned char> packet;
  const std::vector<MarkerDescriptionMsg> in = {{0, 49, 0.03}, {20, 586, 0.1}, {17, 0, 0.0}};
  EncodeMarkersCommand(3, 0.25, in, &packet);
  Header h;
  std::vector<double> payload;
  ASSERT_EQ(DecodePacket(packet.data(), packet.size(), &h, &payload), DecodeError::kNone);
  std::vector<MarkerDescriptionMsg> out;
  ASSERT_EQ(ParseMarkersCommand(h, payload, &out), DecodeError::kNone);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[1].dictionary, 20);
  EXPECT_EQ(out[1].id, 586);
  EXPECT_EQ(out[1].side_m, 0.1);
  EXPECT_EQ(out[2].side_m, 0.0);  // a removal

  auto refused = [&](std::vector<double> values) {
    Header hh = h;
    hh.length = static_cast<int>(values.size());
    std::vector<MarkerDescriptionMsg> kept = {{1, 2, 3}};
    const DecodeError e = ParseMarkersCommand(hh, values, &kept);
    EXPECT_EQ(kept.size(), 1u);  // untouched on error
    return e;
  };
  EXPECT_EQ(refused({0, 50, 0.03}), DecodeError::kBadValue);                         // id beyond 4X4_50
  EXPECT_EQ(refused({21, 0, 0.03}), DecodeError::kBadValue);                         // no such dictionary
  EXPECT_EQ(refused({0, 1.5, 0.03}), DecodeError::kBadValue);                        // id not whole
  EXPECT_EQ(refused({0, 1, -0.01}), DecodeError::kBadValue);                         // negative side
  EXPECT_EQ(refused({0, 1, 10.5}), DecodeError::kBadValue);                          // beyond 10 m
  EXPECT_EQ(refused({0, 1, 0.03, 0, 2, 0.03, 0, 99, 0.1}), DecodeError::kBadValue);  // one bad entry: all refused
  EXPECT_EQ(refused({0, 1}), DecodeError::kBadLength);
  EXPECT_EQ(refused({}), DecodeError::kBadLength);
  EXPECT_EQ(refused({0, 1, 0.03, 4}), DecodeError::kBadLength);
  Header state = h;
  state.type = static_cast<int>(MessageType::kState);
  EXPECT_EQ(ParseMarkersCommand(state, payload, &out), DecodeError::kBadType);
  Header arm = h;
  arm.kind = static_cast<int>(DeviceKind::kArm);
  EXPECT_EQ(ParseMarkersCommand(arm, payload, &out), DecodeError::kBadKind);

  // more than fit one datagram: the encoder keeps the first kMaxDescriptionsPerCommand
  std::vector<MarkerDescriptionMsg> many(kMaxDescriptionsPerCommand + 5, {0, 1, 0.02});
  EncodeMarkersCommand(0, 0, many, &packet);
  EXPECT_EQ(packet.size(), 8u * (kHeaderValues + 3 * kMaxDescriptionsPerCommand));
  EXPECT_LE(packet.size(), 8u * kMaxPacketValues);
  ASSERT_EQ(DecodePacket(packet.data(), packet.size(), &h, &payload), DecodeError::kNone);
}

TEST(MarkersState, LayoutAndRoundTrip) {
  MarkersStateMsg m;
  m.described = 36;
  m.unknown = 2;
  m.markers = {Record(0, 3, true), Record(20, 586, false)};
  std::vector<unsigned char> packet;
  EncodeMarkersState(17, 2.5, m, &packet);
  ASSERT_EQ(packet.size(), 8u * (kHeaderValues + kMarkersStatePrefix + 2 * kMarkerRecordValues));
  auto value = [&](int index) { return GetDouble(packet.data() + 8 * index); };
  EXPECT_EQ(value(2), 5.0);   // kind markers
  EXPECT_EQ(value(3), 1.0);   // state
  EXPECT_EQ(value(4), 17.0);  // seq = frame id
  EXPECT_EQ(value(5), 2.5);   // time = exposure
  EXPECT_EQ(value(6), 3.0 + 2 * 37);
  EXPECT_EQ(value(7), 2.0);   // count
  EXPECT_EQ(value(8), 36.0);  // described
  EXPECT_EQ(value(9), 2.0);   // unknown
  // record 0 from payload index 3: dictionary, id, valid, error, T_camera (row-major), world_valid, T_world
  EXPECT_EQ(value(10), 0.0);
  EXPECT_EQ(value(11), 3.0);
  EXPECT_EQ(value(12), 1.0);
  EXPECT_EQ(value(13), 0.125);
  EXPECT_EQ(value(14 + 3), 0.1);   // T_camera[0][3]: x translation
  EXPECT_EQ(value(14 + 11), 0.4);  // T_camera[2][3]: z translation
  EXPECT_EQ(value(14 + 15), 1.0);  // T_camera[3][3]
  EXPECT_EQ(value(30), 1.0);       // world_valid
  EXPECT_EQ(value(31 + 3), 0.7);   // T_world[0][3]
  // record 1: world invalid -> zeros
  EXPECT_EQ(value(10 + 37 + 1), 586.0);
  EXPECT_EQ(value(10 + 37 + 20), 0.0);
  for (int i = 0; i < 16; ++i) EXPECT_EQ(value(10 + 37 + 21 + i), 0.0);

  MarkersStateMsg out;
  ASSERT_EQ(RoundTrip(packet, &out), DecodeError::kNone);
  EXPECT_EQ(out.described, 36);
  EXPECT_EQ(out.unknown, 2);
  ASSERT_EQ(out.markers.size(), 2u);
  EXPECT_EQ(out.markers[1].dictionary, 20);
  EXPECT_EQ(out.markers[1].id, 586);
  EXPECT_FALSE(out.markers[1].world_valid);
  for (int i = 0; i < 16; ++i) {
    EXPECT_EQ(out.markers[0].T_camera[i], m.markers[0].T_camera[i]);
    EXPECT_EQ(out.markers[0].T_world[i], m.markers[0].T_world[i]);
  }

  // an empty frame: only the prefix
  EncodeMarkersState(18, 2.6, MarkersStateMsg{36, 0, {}}, &packet);
  ASSERT_EQ(RoundTrip(packet, &out), DecodeError::kNone);
  EXPECT_TRUE(out.markers.empty());
  EXPECT_EQ(out.described, 36);
}

TEST(MarkersState, AtMostOneDatagramOfMarkers) {
  MarkersStateMsg m;
  m.markers.assign(kMaxMarkersPerState + 3, Record(0, 1, true));
  std::vector<unsigned char> packet;
  EncodeMarkersState(0, 0, m, &packet);
  EXPECT_EQ(kMaxMarkersPerState, 27);
  EXPECT_LE(packet.size(), 8u * kMaxPacketValues);
  MarkersStateMsg out;
  ASSERT_EQ(RoundTrip(packet, &out), DecodeError::kNone);
  EXPECT_EQ(out.markers.size(), static_cast<std::size_t>(kMaxMarkersPerState));
}

TEST(MarkersState, EveryRefusalReason) {
  EXPECT_EQ(WithValue(0, 2), DecodeError::kBadLength);        // count says 2, one record follows
  EXPECT_EQ(WithValue(0, 0.5), DecodeError::kBadValue);       // count not whole
  EXPECT_EQ(WithValue(0, 28), DecodeError::kBadValue);        // count beyond one datagram
  EXPECT_EQ(WithValue(1, -1), DecodeError::kBadValue);        // described < 0
  EXPECT_EQ(WithValue(2, 1.5), DecodeError::kBadValue);       // unknown not whole
  EXPECT_EQ(WithValue(3, 22), DecodeError::kBadValue);        // dictionary
  EXPECT_EQ(WithValue(4, 50), DecodeError::kBadValue);        // id beyond 4X4_50
  EXPECT_EQ(WithValue(5, 0.5), DecodeError::kBadValue);       // valid not 0/1
  EXPECT_EQ(WithValue(6, -0.1), DecodeError::kBadValue);      // negative error
  EXPECT_EQ(WithValue(7 + 12, 0.1), DecodeError::kBadValue);  // T_camera last row
  EXPECT_EQ(WithValue(7 + 15, 2), DecodeError::kBadValue);
  EXPECT_EQ(WithValue(23, 2), DecodeError::kBadValue);         // world_valid not 0/1
  EXPECT_EQ(WithValue(24 + 14, 0.5), DecodeError::kBadValue);  // T_world last row
  EXPECT_EQ(WithValue(23, 0), DecodeError::kBadValue);         // world invalid, but a transform follows
  EXPECT_EQ(WithValue(6, std::numeric_limits<double>::quiet_NaN()), DecodeError::kNotFinite);
  EXPECT_EQ(WithValue(6, 0.3), DecodeError::kNone);  // (the helper itself accepts a good value)

  // framing of the kind: too short a payload, a wrong type or kind; *m untouched
  Header h;
  h.kind = static_cast<int>(DeviceKind::kMarkers);
  h.type = static_cast<int>(MessageType::kState);
  MarkersStateMsg kept{7, 1, {Record(0, 1, false)}};
  const std::vector<double> two = {0, 0};
  h.length = 2;
  EXPECT_EQ(ParseMarkersState(h, two, &kept), DecodeError::kBadLength);
  h.type = static_cast<int>(MessageType::kCommand);
  EXPECT_EQ(ParseMarkersState(h, two, &kept), DecodeError::kBadType);
  h.kind = static_cast<int>(DeviceKind::kCamera);
  EXPECT_EQ(ParseMarkersState(h, two, &kept), DecodeError::kBadKind);
  EXPECT_EQ(kept.described, 7);
  EXPECT_EQ(kept.markers.size(), 1u);
}

}  // namespace
}  // namespace vlab::bridge::markers_protocol_test
