// The fixture of the DeviceEndpoint tests: a base device's config, and a
// device socket and clients on loopback that send commands and requests and
// read the replies.
#pragma once

#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_layouts.h"

namespace vlab::bridge {

using Bytes = std::vector<unsigned char>;

// A base: [frame, vx, vy, wz], frame 0 or 1, |v| <= 1 m/s, |wz| <= 2 rad/s.
inline EndpointConfig BaseConfig(const double* now_s = nullptr) {
  EndpointConfig c;
  c.name = "nomad";
  c.kind = DeviceKind::kBase;
  c.describe_json = R"({"name":"nomad","kind":"base"})";
  c.command_length = CommandLength(DeviceKind::kBase);
  c.status_first = true;
  c.watchdog_periods = 3;
  c.check_command = [](const std::vector<double>& p) {
    const auto at = [&p](const char* field) { return p[CommandIndex(DeviceKind::kBase, field)]; };
    if (at("frame") != 0 && at("frame") != 1) return CommandCheck::kMalformed;
    if (std::abs(at("vx")) > 1 || std::abs(at("vy")) > 1 || std::abs(at("wz")) > 2) return CommandCheck::kLimits;
    return CommandCheck::kAccept;
  };
  if (now_s) c.clock = [now_s] { return *now_s; };
  return c;
}

class EndpointTest : public ::testing::Test {
 protected:
  std::unique_ptr<UdpSocket> device_ = UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<UdpSocket> client_ = UdpSocket::Bind("127.0.0.1", 0);
  std::unique_ptr<UdpSocket> other_ = UdpSocket::Bind("127.0.0.1", 0);
  unsigned char buffer_[2048];

  using Received = DeviceEndpoint::Received;

  bool Send(DeviceEndpoint& e, UdpSocket& from, int kind, double seq, std::vector<double> payload, long period) {
    Header h;
    h.kind = kind;
    h.type = static_cast<int>(MessageType::kCommand);
    h.seq = seq;
    h.length = static_cast<int>(payload.size());
    Bytes packet;
    EncodePacket(h, payload.data(), h.length, &packet);
    return e.Handle(packet.data(), packet.size(), from.local_endpoint(), period, *device_) == Received::kCommand;
  }
  // hands a request from `from` to the endpoint; returns the reply's size (-1: none within 0.5 s)
  long Request(DeviceEndpoint& e, UdpSocket& from, const Bytes& request, Received* what = nullptr) {
    Drain(from);  // (states published before)
    const Received r = e.Handle(request.data(), request.size(), from.local_endpoint(), 0, *device_);
    if (what) *what = r;
    Endpoint sender;
    return from.Receive(buffer_, sizeof buffer_, &sender, 0.5);
  }
  // the session reply in buffer_: cookie and result
  std::pair<double, SessionResult> Reply(long size) {
    Header h;
    std::vector<double> payload;
    EXPECT_EQ(DecodePacket(buffer_, static_cast<std::size_t>(size), &h, &payload), DecodeError::kNone);
    double cookie = 0;
    SessionResult result = SessionResult::kLimited;
    EXPECT_TRUE(ParseSessionReply(h, payload, &cookie, &result));
    return {cookie, result};
  }
  // the whole handshake of `from`: its cookie
  double Subscribe(DeviceEndpoint& e, UdpSocket& from) {
    const DeviceKind kind = e.config().kind;
    Bytes request;
    EncodeSubscribeRequest(kind, 0, 1, &request);
    const long n = Request(e, from, request);
    EXPECT_EQ(n, static_cast<long>(request.size()));  // the challenge is no larger than the request
    const double cookie = Reply(n).first;
    EncodeSubscribeRequest(kind, cookie, 1, &request);
    const int before = e.subscribers();
    Received what;
    EXPECT_EQ(Reply(Request(e, from, request, &what)).second, SessionResult::kSubscribed);
    // a newcomer is reported (the lab sends it the latest state at once), a renewal is not
    EXPECT_EQ(what, e.subscribers() > before ? Received::kSubscribed : Received::kOther);
    return cookie;
  }
  // publishes a base state of seq `seq` (the newest a command may answer)
  void PublishBase(DeviceEndpoint& e, double seq) {
    Header h;
    h.kind = static_cast<int>(DeviceKind::kBase);
    h.type = static_cast<int>(MessageType::kState);
    h.seq = seq;
    const double state[7] = {0, 1, 2, 3, 4, 5, 6};
    Bytes packet;
    EncodePacket(h, state, 7, &packet);
    e.Publish(packet, *device_);
  }
  // drops whatever is queued at a client
  void Drain(UdpSocket& s) {
    Endpoint from;
    while (s.Receive(buffer_, sizeof buffer_, &from, 0.0) >= 0) {
    }
  }
};

}  // namespace vlab::bridge
