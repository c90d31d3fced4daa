#include "lab/outputs/lab_run_record.h"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "lab/outputs/lab_log.h"

#ifndef VLAB_VERSION
#define VLAB_VERSION "0.0.0"
#endif

namespace vlab::lab {

namespace {

// the fields in a fixed order, each behind its name and a NUL, so that no two
// records make the same bytes
std::string Canonical(const RunRecord& r) {
  char duration[40];
  std::snprintf(duration, sizeof duration, "%.17g", r.duration_s);
  std::string text;
  for (const auto& [name, value] : std::vector<std::pair<const char*, std::string>>{{"vlab", r.vlab},
                                                                                    {"seed", std::to_string(r.seed)},
                                                                                    {"duration_s", duration},
                                                                                    {"scenario", r.scenario_yaml}}) {
    text += name;
    text += '\0';
    text += std::to_string(value.size());
    text += '\0';
    text += value;
  }
  return text;
}

std::string Seconds(double s) { return FormatDouble(s) + " s"; }

}  // namespace

RunRecord RecordOf(const Scenario& scenario) {
  return {VLAB_VERSION, scenario.resolved_yaml, scenario.seed, scenario.duration_s};
}

std::string RecordHash(const RunRecord& record) {
  // FNV-1a, 64 bits (offset basis and prime of the FNV specification)
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : Canonical(record)) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return std::string("fnv1a64:") + hex;
}

nlohmann::json RecordJson(const RunRecord& record) {
  return {{"vlab", record.vlab},
          {"seed", record.seed},
          {"duration_s", record.duration_s},
          {"scenario", record.scenario_yaml},
          {"hash", RecordHash(record)}};
}

std::string RecordChange(const nlohmann::json& summary, const RunRecord& want) {
  if (!summary.is_object() || !summary.contains("record") || !summary["record"].is_object()) {
    return "it has no record of what it ran (written by an older vlab)";
  }
  const nlohmann::json& had = summary["record"];
  std::vector<std::string> why;
  const auto text = [&had](const char* key) {
    return had.contains(key) && had[key].is_string() ? had[key].get<std::string>() : std::string("?");
  };
  if (text("vlab") != want.vlab) why.push_back("vlab changed since it ran (" + text("vlab") + " -> " + want.vlab + ")");
  if (text("scenario") != want.scenario_yaml) why.push_back("the scenario changed since it ran");
  const nlohmann::json seed = had.value("seed", nlohmann::json(nullptr));
  if (!seed.is_number_unsigned() || seed.get<std::uint64_t>() != want.seed) {
    why.push_back("the seed changed since it ran (" + seed.dump() + " -> " + std::to_string(want.seed) + ")");
  }
  const nlohmann::json duration = had.value("duration_s", nlohmann::json(nullptr));
  if (!duration.is_number() || duration.get<double>() != want.duration_s) {
    why.push_back("the duration changed since it ran (" +
                  (duration.is_number() ? Seconds(duration.get<double>()) : std::string("?")) + " -> " +
                  Seconds(want.duration_s) + ")");
  }
  if (why.empty() && had.value("hash", "") != RecordHash(want)) why.push_back("its record's hash does not match");
  std::string joined;
  for (const std::string& w : why) joined += (joined.empty() ? "" : "; ") + w;
  return joined;
}

}  // namespace vlab::lab
