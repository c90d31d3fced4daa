// A run's record: what it ran, so that a sweep resumed later can tell a result
// that is still current from one that an edit has made stale.
//
// summary.json carries it as "record": the scenario file's text after the --set
// overrides (re-emitted as YAML: comments and layout left out, values as the
// run read them), the seed, the duration and vlab's version, with a hash of the
// four. Files the scenario names (the scene's MJCF, a controller's program) are
// not part of it.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

/// What one run was.
struct RunRecord {
  std::string vlab;           ///< vlab's version
  std::string scenario_yaml;  ///< Scenario::resolved_yaml
  std::uint64_t seed = 0;
  double duration_s = 0;
};

/// The record of `scenario` as it will run (its seed and duration final).
RunRecord RecordOf(const Scenario& scenario);

/// "fnv1a64:" and 16 hex digits over the four fields: an identifier for a
/// change, not a signature (resume compares the fields themselves).
std::string RecordHash(const RunRecord& record);

/// The record as summary.json's "record": vlab, seed, duration_s, scenario, hash.
nlohmann::json RecordJson(const RunRecord& record);

/// Why the run that wrote `summary` (a parsed summary.json) is not the run
/// `want` describes, in words ("the scenario changed since it ran"); "" when
/// its record is the same. A summary without a record (an older vlab's) differs.
std::string RecordChange(const nlohmann::json& summary, const RunRecord& want);

}  // namespace vlab::lab
