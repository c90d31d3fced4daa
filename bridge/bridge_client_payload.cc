// The arm handle's payload request (bridge_client.h, Arm::SetPayload): one
// datagram out, one session reply back.
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client.h"
#include "bridge/bridge_payload.h"

namespace vlab::bridge {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

SessionResult DeviceClient::AwaitSessionResult(SessionResult yes, SessionResult no, double timeout_s,
                                               const std::string& what) {
  const Clock::time_point deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                        std::chrono::duration<double>(std::max(0.0, timeout_s)));
  Header header;
  std::vector<double> values;
  for (;;) {
    long size = 0;
    if (!ReceiveFromDevice(deadline, &size)) {
      throw TimeoutError(Label() + ": no answer to the " + what + " within " + ErrorSeconds(timeout_s));
    }
    double cookie = 0;
    SessionResult result = SessionResult::kChallenge;
    const bool reply =
        IsSessionReply(buffer_.data(), static_cast<std::size_t>(size)) &&
        DecodePacket(buffer_.data(), static_cast<std::size_t>(size), &header, &values) == DecodeError::kNone &&
        ParseSessionReply(header, values, &cookie, &result);
    if (reply && (result == yes || result == no)) return result;
    ++skipped_;  // a state, a describe reply or the answer to a renewal
  }
}

void Arm::SetPayload(const ArmPayloadMsg& payload, double timeout_s) {
  const char* field = nullptr;
  const char* reason = nullptr;
  if (!CheckArmPayload(payload, &field, &reason)) {
    throw std::invalid_argument(Label() + ": payload " + field + " " + reason);
  }
  // the next value of this handle's payload counter: the device refuses any seq not above the last it took
  EncodeArmPayload(static_cast<double>(++payload_seq_), ClientTime(), payload, &packet_);
  if (!Send(packet_)) throw NetworkError(Label() + ": cannot send the payload");
  if (AwaitSessionResult(SessionResult::kPayloadSet, SessionResult::kPayloadRefused, timeout_s, "payload") ==
      SessionResult::kPayloadRefused) {
    throw RefusedError(Label() + ": the device refused the payload (another client owns the arm, or the device " +
                       "found it no rigid body or its seq not above the last one it took)");
  }
  mutable_describe()["payload"] = {
      {"mass", payload.mass_kg}, {"com", payload.com_m}, {"inertia", payload.inertia_kgm2}};
}

ArmPayloadMsg Arm::payload() const {
  ArmPayloadMsg p;
  PayloadFromDescribe(describe().dump(), &p);
  return p;
}

}  // namespace vlab::bridge
