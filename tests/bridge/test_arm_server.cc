// A tiny arm device for client tests in other languages (python_client_test.py):
// one 7-joint arm served through DeviceEndpoint on 127.0.0.1.
//
//   test_arm_server PORT SECONDS [--follow]     (PORT 0: any free port)
//
// Ports
//   input   commands and describe requests on 127.0.0.1:PORT
//   output  a state every 2 ms: seq k, time 0.002 k, status from the endpoint;
//           scripted: q_i = 0.1 i + 0.001 k (rad), qd_i = -0.5 i (rad/s),
//           tau_i = 10 i (N m), i = 0..6;
//           --follow: a kinematic arm from the PA10 "ready" pose that follows
//           the last accepted command (position: q = v; velocity: q += v dt,
//           qd = v; hold: qd = 0), tau = 0 (for the joint_control examples)
// stdout (one line each, flushed)
//   listening 127.0.0.1:PORT                      once bound
//   command seq=S mode=M values=V1,...,V7         each accepted command
//   counters received=R accepted=A refused=F stale=S duplicate=D describes=N
//                                                 at the end (SECONDS, SIGTERM or SIGINT)
// Limits: velocity |qd| <= 2 rad/s, torque |tau| <= 50 N m, position +-3 rad.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bridge/bridge_describe.h"
#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_errors.h"
#include "bridge/bridge_signals.h"

namespace {

constexpr double kPeriod_s = 0.002;
constexpr int kJoints = 7;

vlab::bridge::EndpointConfig Config(int port) {
  using namespace vlab::bridge;
  ArmDescription d;
  d.name = "pa10";
  d.server = "test_arm_server";
  d.clock = "realtime";
  d.address = "127.0.0.1";
  d.port = port;
  d.control_hz = 1.0 / kPeriod_s;
  d.joints = {"S1", "S2", "S3", "E1", "E2", "W1", "W2"};
  d.position_min.assign(kJoints, -3.0);
  d.position_max.assign(kJoints, 3.0);
  d.velocity_max.assign(kJoints, 2.0);
  d.torque_max.assign(kJoints, 50.0);
  d.watchdog_periods = 0;
  EndpointConfig c;
  c.name = d.name;
  c.kind = DeviceKind::kArm;
  c.describe_json = DescribeJson(d);
  c.joints = kJoints;
  c.position_min = d.position_min;
  c.position_max = d.position_max;
  c.velocity_max = d.velocity_max;
  c.torque_max = d.torque_max;
  c.watchdog_periods = 0;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace vlab::bridge;
  using Clock = std::chrono::steady_clock;
  const bool follow = argc == 4 && std::string(argv[3]) == "--follow";
  if (argc != 3 && !follow) {
    std::fprintf(stderr, "usage: %s PORT SECONDS [--follow]\n", argv[0]);
    return 2;
  }
  const int port = std::atoi(argv[1]);
  const double seconds = std::atof(argv[2]);
  vlab::InstallStopSignals();
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  std::unique_ptr<UdpSocket> socket;
  try {
    socket = UdpSocket::Bind("127.0.0.1", port);
  } catch (const BridgeError& e) {
    std::fprintf(stderr, "test_arm_server: %s\n", e.what());
    return 2;
  }
  DeviceEndpoint endpoint(Config(socket->local_port()));
  std::printf("listening 127.0.0.1:%d\n", socket->local_port());

  std::vector<unsigned char> buffer(65536), packet;
  ArmCommandMsg command, active;  // active: the command in force (follow mode)
  ArmStateMsg state;
  state.q = {0, 0.523599, 0, 1.047198, 0, 1.570796, 0};
  state.qd.assign(kJoints, 0.0);
  state.tau.assign(kJoints, 0.0);
  const Clock::time_point start = Clock::now();
  for (long k = 0; !vlab::StopRequested(); ++k) {
    // handle what arrives until this period's end, then publish its state
    const Clock::time_point end = start + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(kPeriod_s * static_cast<double>(k + 1)));
    if (std::chrono::duration<double>(end - start).count() > seconds) break;
    for (;;) {
      const double left = std::chrono::duration<double>(end - Clock::now()).count();
      Endpoint from;
      const long n = socket->Receive(buffer.data(), buffer.size(), &from, left > 0 ? left : 0);
      if (n < 0) break;
      if (endpoint.Handle(buffer.data(), static_cast<std::size_t>(n), from, k, *socket) ==
              DeviceEndpoint::Received::kCommand &&
          endpoint.TakeArmCommand(&command)) {
        std::string values;
        char number[32];
        for (double v : command.value) {
          std::snprintf(number, sizeof(number), "%s%.17g", values.empty() ? "" : ",", v);
          values += number;
        }
        std::printf("command seq=%.17g mode=%d values=%s\n", endpoint.last_accepted_seq(), command.mode,
                    values.c_str());
        active = command;
      }
    }
    endpoint.BeginPeriod(k);
    state.status = endpoint.status_bits();
    for (int i = 0; i < kJoints; ++i) {
      if (!follow) {
        state.q[i] = 0.1 * i + 0.001 * static_cast<double>(k);
        state.qd[i] = -0.5 * i;
        state.tau[i] = 10.0 * i;
      } else if (active.mode == 1) {
        state.q[i] = active.value[i];
        state.qd[i] = 0;
      } else if (active.mode == 2) {
        state.q[i] += active.value[i] * kPeriod_s;
        state.qd[i] = active.value[i];
      } else {
        state.qd[i] = 0;
      }
    }
    EncodeArmState(static_cast<double>(k), kPeriod_s * static_cast<double>(k), state, &packet);
    endpoint.Publish(packet, *socket);
  }
  const EndpointCounters& c = endpoint.counters();
  std::printf("counters received=%ld accepted=%ld refused=%ld stale=%ld duplicate=%ld describes=%ld\n", c.received,
              c.accepted, c.refused, c.stale, c.duplicate, c.describes);
  return 0;
}
