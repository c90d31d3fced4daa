// Writes the seed corpus of tests/fuzz/packet_fuzzer.cc: one valid datagram
// per file, built with the protocol's own encoders.
//
//   make_corpus DIR           writes (overwrites) the seeds into DIR
//   make_corpus --check DIR   exits 1 when a seed in DIR is missing or differs
//
// run_fuzz.sh builds this and runs --check on tests/fuzz/corpus, so a protocol
// change that invalidates the committed seeds fails the fuzz test. Regenerate:
//   build/fuzz/make_corpus tests/fuzz/corpus
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "bridge/bridge_payload.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"

namespace vlab::bridge {
namespace {

using Bytes = std::vector<unsigned char>;
using Seeds = std::vector<std::pair<std::string, Bytes>>;

constexpr int kJoints = 7;

ArmCommandMsg ArmCommand(int mode, int joints, double value) {
  ArmCommandMsg m;
  m.mode = mode;
  for (int i = 0; i < joints; ++i) m.value.push_back(value * (i % 2 == 0 ? 1 : -1));
  return m;
}

ArmStateMsg ArmState(int joints) {
  ArmStateMsg m;
  m.status = kStatusHolding | kStatusAtLimit;
  for (int i = 0; i < joints; ++i) {
    m.q.push_back(0.1 * i);
    m.qd.push_back(-0.01 * i);
    m.tau.push_back(2.5 - i);
  }
  return m;
}

Seeds MakeSeeds() {
  Seeds seeds;
  auto add = [&](const char* name, auto encode) {
    Bytes b;
    encode(&b);
    seeds.emplace_back(name, std::move(b));
  };
  // arm: a state, a command in each mode (within the fuzzer's limits), edge sizes
  add("arm_state_7", [](Bytes* b) { EncodeArmState(12, 0.012, ArmState(kJoints), b); });
  add("arm_command_hold_7", [](Bytes* b) { EncodeArmCommand(1, 100.0, ArmCommand(0, kJoints, 0.0), b); });
  add("arm_command_position_7", [](Bytes* b) { EncodeArmCommand(2, 100.001, ArmCommand(1, kJoints, 0.5), b); });
  add("arm_command_velocity_7", [](Bytes* b) { EncodeArmCommand(3, 100.002, ArmCommand(2, kJoints, 0.25), b); });
  add("arm_command_torque_7", [](Bytes* b) { EncodeArmCommand(4, 100.003, ArmCommand(3, kJoints, 10.0), b); });
  add("arm_command_position_1", [](Bytes* b) { EncodeArmCommand(5, 0.5, ArmCommand(1, 1, -1.0), b); });
  // the largest datagram: 7 header + 1 mode + 1016 values = kMaxPacketValues
  add("arm_command_max_length",
      [](Bytes* b) { EncodeArmCommand(6, 1.0, ArmCommand(2, kMaxPacketValues - kHeaderValues - 1, 0.125), b); });
  add("arm_state_max_joints",
      [](Bytes* b) { EncodeArmState(7, 2.0, ArmState((kMaxPacketValues - kHeaderValues - 1) / 3), b); });
  // framing-valid, but an arm command without a mode
  add("arm_command_empty", [](Bytes* b) {
    Header h;
    h.kind = static_cast<int>(DeviceKind::kArm);
    h.type = static_cast<int>(MessageType::kCommand);
    h.seq = 8;
    EncodePacket(h, nullptr, 0, b);
  });
  // wrench and sim states
  add("wrench_state", [](Bytes* b) {
    WrenchStateMsg m;
    const double wrench[6] = {1.5, -2.0, 30.25, 0.1, -0.2, 0.05};
    for (int i = 0; i < 6; ++i) m.wrench[i] = wrench[i];
    m.filter = 3;
    m.saturated = true;
    EncodeWrenchState(40, 0.04, m, b);
  });
  add("sim_state", [](Bytes* b) {
    SimStateMsg m;
    m.sim_time = 1.25;
    m.mode = 1;
    m.clock = static_cast<int>(ClockCode::kLockstep);
    m.periods = 1250;
    m.refused_packets = 3;
    m.missed_deadlines = 1;
    m.realtime_factor = 0.5;
    m.max_lateness = 0.002;
    EncodeSimState(1250, 1.25, m, b);
  });
  // sim commands, one per op
  add("sim_command_reset", [](Bytes* b) { EncodeSimCommand(1, 10.0, {static_cast<int>(SimOp::kReset), 0}, b); });
  add("sim_command_pause", [](Bytes* b) { EncodeSimCommand(2, 10.1, {static_cast<int>(SimOp::kPause), 0}, b); });
  add("sim_command_resume", [](Bytes* b) { EncodeSimCommand(3, 10.2, {static_cast<int>(SimOp::kResume), 0}, b); });
  add("sim_command_step", [](Bytes* b) { EncodeSimCommand(4, 10.3, {static_cast<int>(SimOp::kStep), 10}, b); });
  add("sim_command_set_realtime_factor", [](Bytes* b) {
    EncodeSimCommand(5, 10.4, {static_cast<int>(SimOp::kSetRealtimeFactor), 0.5}, b);
  });
  // describe and subscribe requests: [cookie, arg]; cookie 1 stands for the sender's real
  // cookie (the fuzzer puts it in), 0 asks for a challenge
  add("describe_arm", [](Bytes* b) { EncodeDescribeRequest(static_cast<int>(DeviceKind::kArm), 1, b); });
  add("describe_wrench", [](Bytes* b) { EncodeDescribeRequest(static_cast<int>(DeviceKind::kWrench), 1, b); });
  add("describe_sim", [](Bytes* b) { EncodeDescribeRequest(static_cast<int>(DeviceKind::kSim), 1, b); });
  add("describe_any_no_cookie", [](Bytes* b) { EncodeDescribeRequest(0, 0, b); });
  add("subscribe_arm_no_cookie", [](Bytes* b) { EncodeSubscribeRequest(DeviceKind::kArm, 0, 1, b); });
  add("subscribe_arm", [](Bytes* b) { EncodeSubscribeRequest(DeviceKind::kArm, 1, 1, b); });
  add("subscribe_sim", [](Bytes* b) { EncodeSubscribeRequest(DeviceKind::kSim, 1, 1, b); });
  add("unsubscribe_arm", [](Bytes* b) { EncodeSubscribeRequest(DeviceKind::kArm, 1, 0, b); });
  add("subscribe_wrong_cookie", [](Bytes* b) { EncodeSubscribeRequest(DeviceKind::kWrench, 123456789, 1, b); });
  // arm payloads (type 6): a rigid body, a wrong length, a negative mass, a broken triangle inequality
  auto payload = [](std::vector<double> v, Bytes* b) {
    Header h;
    h.kind = static_cast<int>(DeviceKind::kArm);
    h.type = static_cast<int>(MessageType::kPayload);
    h.seq = 1;
    EncodePacket(h, v.data(), static_cast<int>(v.size()), b);
  };
  add("arm_payload", [](Bytes* b) {
    ArmPayloadMsg m;
    m.mass_kg = 1.5;
    m.com_m = {0.1, 0, 0.05};
    m.inertia_kgm2 = {0.01, 0.012, 0.008, 0.001, 0, 0};
    EncodeArmPayload(1, 2.5, m, b);
  });
  add("arm_payload_9_values", [&](Bytes* b) { payload({1, 0, 0, 0, 0, 0, 0, 0, 0}, b); });
  add("arm_payload_negative_mass", [&](Bytes* b) { payload({-1, 0, 0, 0, 0, 0, 0, 0, 0, 0}, b); });
  add("arm_payload_not_rigid", [&](Bytes* b) { payload({1, 0, 0, 0, 0.01, 0.01, 0.03, 0, 0, 0}, b); });
  add("session_reply", [](Bytes* b) {
    const double payload[2] = {987654321, 1};
    Header h;
    h.kind = static_cast<int>(DeviceKind::kArm);
    h.type = static_cast<int>(MessageType::kSession);
    EncodePacket(h, payload, 2, b);
  });
  return seeds;
}

int Run(int argc, char** argv) {
  const bool check = argc == 3 && std::string(argv[1]) == "--check";
  if (!(argc == 2 || check)) {
    std::fprintf(stderr, "usage: make_corpus DIR | make_corpus --check DIR\n");
    return 2;
  }
  const std::string dir = argv[argc - 1];
  int differ = 0;
  for (const auto& [name, bytes] : MakeSeeds()) {
    const std::string path = dir + "/" + name;
    if (check) {
      std::ifstream in(path, std::ios::binary);
      const Bytes found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (!in.is_open() || found != bytes) {
        std::fprintf(stderr, "make_corpus: seed '%s' is missing or differs from the generator\n", path.c_str());
        ++differ;
      }
      continue;
    }
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) {
      std::fprintf(stderr, "make_corpus: cannot write '%s'\n", path.c_str());
      return 1;
    }
  }
  return differ == 0 ? 0 : 1;
}

}  // namespace
}  // namespace vlab::bridge

int main(int argc, char** argv) { return vlab::bridge::Run(argc, argv); }
