// Tests the DeviceEndpoint rules that keep a run in its controller's hands:
// the command gate (the lab's sim device in a driven run: refused ops are
// answered with result 5 and counted), the state a new subscriber gets at
// once (kStatusNotOwner where another owns the input), and the watchdog of a
// paced clock, which counts the wall time a state was out, not the periods a
// late lab ran back to back. Over real loopback sockets, on a test clock.
#include <vector>

#include <gtest/gtest.h>

#include "bridge/endpoint_fixture.h"

namespace vlab::bridge::endpoint_gate_test {
namespace {

EndpointConfig SimConfig(const double* now_s) {
  EndpointConfig c;
  c.name = "sim";
  c.kind = DeviceKind::kSim;
  c.describe_json = R"({"name":"sim","kind":"sim"})";
  c.clock = [now_s] { return *now_s; };
  return c;
}

void PublishSim(DeviceEndpoint& e, UdpSocket& device, double seq) {
  Bytes packet;
  EncodeSimState(seq, 0, SimStateMsg{}, &packet);
  e.Publish(packet, device);
}

using EndpointGateTest = EndpointTest;

TEST_F(EndpointGateTest, AGateRefusesABystandersOpsAndLetsTheDriverTakeOver) {
  double now = 10;
  CommandGate for_client = CommandGate::kOpen, for_other = CommandGate::kOpen;
  EndpointConfig c = SimConfig(&now);
  const Endpoint client = client_->local_endpoint();
  c.gate = [&](const Endpoint& from) { return from == client ? for_client : for_other; };
  DeviceEndpoint e(c);
  Subscribe(e, *client_);
  Subscribe(e, *other_);
  PublishSim(e, *device_, 0);
  const int sim = static_cast<int>(DeviceKind::kSim);
  const double pause = static_cast<double>(SimOp::kPause);
  // nobody drives: the first op claims the sim
  EXPECT_TRUE(Send(e, *other_, sim, 0, {pause, 0}, 0));
  EXPECT_TRUE(e.owner() && *e.owner() == other_->local_endpoint());
  // a controller drives now: the bystander is refused, and told so
  for_other = CommandGate::kRefuse;
  for_client = CommandGate::kTakeOver;
  PublishSim(e, *device_, 1);
  Drain(*other_);
  EXPECT_FALSE(Send(e, *other_, sim, 1, {static_cast<double>(SimOp::kReset), 0}, 1));
  Endpoint from;
  const long n = other_->Receive(buffer_, sizeof buffer_, &from, 0.5);
  ASSERT_GT(n, 0) << "no answer to the refused op";
  EXPECT_EQ(n, static_cast<long>(kHeaderBytes + 2 * sizeof(double)));  // no larger than the op
  EXPECT_EQ(Reply(n).second, SessionResult::kRefused);
  EXPECT_EQ(e.counters().refused_not_owner, 1);
  // the driver's op takes the sim over from the bystander
  EXPECT_TRUE(Send(e, *client_, sim, 1, {static_cast<double>(SimOp::kResume), 0}, 1));
  EXPECT_TRUE(e.owner() && *e.owner() == client);
  EXPECT_EQ(e.counters().owners_released, 1);
  EXPECT_EQ(e.counters().accepted, 2);
}

TEST_F(EndpointGateTest, TheFirstStateOfANewSubscriberCarriesNotOwner) {
  EndpointConfig c = BaseConfig();
  DeviceEndpoint e(c);
  Subscribe(e, *client_);
  PublishBase(e, 1);
  ASSERT_TRUE(Send(e, *client_, static_cast<int>(DeviceKind::kBase), 1, {0, 0, 0, 0}, 1));
  Subscribe(e, *other_);
  Bytes latest;
  Header h;
  h.kind = static_cast<int>(DeviceKind::kBase);
  h.type = static_cast<int>(MessageType::kState);
  h.seq = 1;
  const double state[7] = {0, 1, 2, 3, 4, 5, 6};
  EncodePacket(h, state, 7, &latest);
  const auto status_sent = [&](UdpSocket& to) {
    Drain(to);
    e.SendLatest(latest, to.local_endpoint(), *device_);
    Endpoint from;
    const long n = to.Receive(buffer_, sizeof buffer_, &from, 0.5);
    EXPECT_EQ(n, static_cast<long>(latest.size()));
    return n > 0 ? static_cast<std::uint32_t>(GetDouble(buffer_ + kHeaderBytes)) : 0xffffffffu;
  };
  EXPECT_EQ(status_sent(*other_), static_cast<std::uint32_t>(kStatusNotOwner));
  EXPECT_EQ(status_sent(*client_), 0u);  // the owner's own state is unmarked
}

TEST_F(EndpointGateTest, APacedWatchdogCountsWallTimeNotPeriodsRunBackToBack) {
  const double period_s = 0.002;  // wall seconds per period (realtime, factor 1)
  double now = 5;
  DeviceEndpoint paced(BaseConfig(&now)), counted(BaseConfig(&now));
  const int base = static_cast<int>(DeviceKind::kBase);
  for (DeviceEndpoint* e : {&paced, &counted}) {
    Subscribe(*e, *client_);
    PublishBase(*e, 1);
    ASSERT_TRUE(Send(*e, *client_, base, 1, {0, 0, 0, 0}, 1));
  }
  // the lab fell behind: periods 2..6 run back to back, each state out for no wall time
  bool paced_held = false, counted_held = false;
  for (long k = 2; k <= 6; ++k) {
    PublishBase(paced, static_cast<double>(k));
    PublishBase(counted, static_cast<double>(k));
    paced_held = paced.BeginPeriod(k, period_s) || paced_held;
    counted_held = counted.BeginPeriod(k) || counted_held;
  }
  EXPECT_TRUE(counted_held);  // counting periods only: the lab's lateness earns a hold
  EXPECT_FALSE(paced_held);
  EXPECT_EQ(paced.counters().watchdog_holds, 0);
  // at the realtime pace, a client silent since state 1: state 2 out for 2 periods of wall time
  now += (3 - 1) * period_s - 1e-6;
  PublishBase(paced, 7);
  EXPECT_FALSE(paced.BeginPeriod(7, period_s));
  now += 2e-6;
  PublishBase(paced, 8);
  EXPECT_TRUE(paced.BeginPeriod(8, period_s));
  EXPECT_EQ(paced.counters().watchdog_holds, 1);
}

}  // namespace
}  // namespace vlab::bridge::endpoint_gate_test
