#include "bridge/bridge_payload.h"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "bridge/bridge_layouts.h"

namespace vlab::bridge {

static_assert(ValueCount(kArmPayloadLayout) == kArmPayloadValues, "the payload's layout has 10 values");

void EncodeArmPayload(double seq, double time, const ArmPayloadMsg& p, std::vector<unsigned char>* out) {
  const double values[kArmPayloadValues] = {p.mass_kg,         p.com_m[0],        p.com_m[1],        p.com_m[2],
                                            p.inertia_kgm2[0], p.inertia_kgm2[1], p.inertia_kgm2[2], p.inertia_kgm2[3],
                                            p.inertia_kgm2[4], p.inertia_kgm2[5]};
  Header h;
  h.kind = static_cast<int>(DeviceKind::kArm);
  h.type = static_cast<int>(MessageType::kPayload);
  h.seq = seq;
  h.time = time;
  EncodePacket(h, values, kArmPayloadValues, out);
}

DecodeError ParseArmPayload(const Header& h, const std::vector<double>& v, ArmPayloadMsg* p) {
  if (h.kind != static_cast<int>(DeviceKind::kArm)) return DecodeError::kBadKind;
  if (h.type != static_cast<int>(MessageType::kPayload)) return DecodeError::kBadType;
  if (h.length != kArmPayloadValues || v.size() != static_cast<std::size_t>(kArmPayloadValues)) {
    return DecodeError::kBadLength;
  }
  p->mass_kg = v[0];
  for (int i = 0; i < 3; ++i) p->com_m[i] = v[1 + i];
  for (int i = 0; i < 6; ++i) p->inertia_kgm2[i] = v[4 + i];
  return DecodeError::kNone;
}

bool CheckArmPayload(const ArmPayloadMsg& p, const char** field, const char** reason) {
  auto fail = [&](const char* f, const char* r) {
    *field = f;
    *reason = r;
    return false;
  };
  if (!std::isfinite(p.mass_kg) || p.mass_kg < 0) return fail("mass", "must be a finite number >= 0 kg");
  for (double v : p.com_m) {
    if (!std::isfinite(v)) return fail("com", "must be 3 finite numbers (m)");
  }
  for (double v : p.inertia_kgm2) {
    if (!std::isfinite(v)) return fail("inertia", "must be finite numbers (kg m^2)");
  }
  // principal moments: non-negative, and none larger than the sum of the others
  const auto& i = p.inertia_kgm2;
  Eigen::Matrix3d inertia;
  inertia << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia).eigenvalues();
  const double tolerance = 1e-12 + 1e-9 * std::abs(inertia.trace());
  if (moments.minCoeff() < -tolerance) return fail("inertia", "is not positive semi-definite");
  if (moments[2] > moments[0] + moments[1] + tolerance) {
    return fail("inertia", "principal moments break the triangle inequality (largest > sum of the others)");
  }
  return true;
}

std::string DescribeWithPayload(const std::string& describe_json, const ArmPayloadMsg& p) {
  nlohmann::json j = nlohmann::json::parse(describe_json, nullptr, false);
  if (!j.is_object()) return describe_json;
  j["payload"] = {{"mass", p.mass_kg}, {"com", p.com_m}, {"inertia", p.inertia_kgm2}};
  return j.dump();
}

bool PayloadFromDescribe(const std::string& describe_json, ArmPayloadMsg* out) {
  const nlohmann::json j = nlohmann::json::parse(describe_json, nullptr, false);
  if (!j.is_object() || !j.contains("payload") || !j["payload"].is_object()) return false;
  const nlohmann::json& p = j["payload"];
  const nlohmann::json mass = p.value("mass", nlohmann::json()), com = p.value("com", nlohmann::json()),
                       inertia = p.value("inertia", nlohmann::json());
  if (!mass.is_number() || !com.is_array() || com.size() != 3 || !inertia.is_array() || inertia.size() != 6) {
    return false;
  }
  ArmPayloadMsg m;
  m.mass_kg = mass.get<double>();
  for (std::size_t i = 0; i < 3; ++i) {
    if (!com[i].is_number()) return false;
    m.com_m[i] = com[i].get<double>();
  }
  for (std::size_t i = 0; i < 6; ++i) {
    if (!inertia[i].is_number()) return false;
    m.inertia_kgm2[i] = inertia[i].get<double>();
  }
  *out = m;
  return true;
}

}  // namespace vlab::bridge
