#include "lab/sweep/lab_sweep.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "lab/scenario/lab_overrides.h"
#include "lab/scenario/lab_scenario.h"
#include "lab/scenario/lab_yaml.h"
#include "lab/sweep/lab_sweep_text.h"

namespace vlab::lab {

namespace fs = std::filesystem;

namespace {

// refuses a key, name or path that holds a control character, at its line
void RefuseControl(const std::string& file, const YAML::Node& node, const std::string& path, const std::string& text) {
  if (HasControlCharacter(text)) {
    throw InputError(YamlError(file, node, path,
                               "'" + Printable(text) +
                                   "' holds a control character (0x01-0x1f, 0x7f), which a key, "
                                   "name or path may not (a value may, in double quotes)"));
  }
}

// one KEY=VALUE of a grid or list entry: the key checked, the value as one line of YAML
std::string SetText(const std::string& file, const YAML::Node& key, const YAML::Node& value, const std::string& path) {
  RefuseControl(file, key, path, key.Scalar());
  return key.Scalar() + "=" + ValueText(value, YamlWhere(file, value) + ": " + path);
}

// an entry of `set` (KEY=VALUE, VALUE as YAML text): a VALUE with a control
// character is read as YAML here and written back as one line
std::string CommonSet(const std::string& file, const YAML::Node& node, const std::string& path) {
  if (!node.IsScalar()) throw InputError(YamlError(file, node, path, "expected a string KEY=VALUE"));
  const std::string& text = node.Scalar();
  if (!HasControlCharacter(text)) return text;
  Override o;
  try {
    o = ParseOverride(text);
  } catch (const InputError&) {
    throw InputError(YamlError(file, node, path, "expected KEY=VALUE"));
  }
  RefuseControl(file, node, path, o.key);
  YAML::Node value;
  try {
    value = YAML::Load(o.value);
  } catch (const YAML::Exception& e) {
    throw InputError(YamlError(file, node, path, "the value is not valid YAML: " + e.msg));
  }
  return o.key + "=" + ValueText(value, YamlWhere(file, node) + ": " + path);
}

std::vector<long long> ReadSeeds(MapReader& r) {
  const YAML::Node n = r.Raw("seeds");
  std::vector<long long> seeds;
  if (!n.IsDefined()) return {-1};
  auto seed = [&](const YAML::Node& s, const std::string& path) {
    return static_cast<long long>(YamlSeed(r.file(), s, path));  // never rounded: 2^53 + 1 is refused
  };
  if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) seeds.push_back(seed(n[i], "seeds[" + std::to_string(i) + "]"));
  } else if (n.IsMap()) {
    MapReader m(r.file(), n, "seeds");
    const long long from = seed(m.Raw("from").IsDefined() ? m.Raw("from") : YAML::Node(1), "seeds.from");
    const int count = m.Integer("count", 0);
    if (count < 1 || count > 100000) m.Fail("count", "must be 1 to 100000");
    if (static_cast<unsigned long long>(from) + count - 1 > kMaxSeed) m.Fail("count", "takes the seeds past 2^53");
    m.Finish();
    for (int i = 0; i < count; ++i) seeds.push_back(from + i);
  } else {
    r.Fail("seeds", "expected a list of seeds or {from: N, count: M}");
  }
  if (seeds.empty()) r.Fail("seeds", "needs at least one seed");
  return seeds;
}

}  // namespace

Sweep LoadSweep(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  MapReader r(path, root, "");
  Sweep s;
  s.file = path;
  s.name = r.String("name", fs::path(path).stem().string());
  RefuseControl(path, r.Raw("name"), "name", s.name);
  if (s.name.empty() || s.name.find_first_of("/\\") != std::string::npos || s.name[0] == '.') {
    r.Fail("name", "must be a plain folder name");
  }
  RefuseControl(path, r.Raw("scenario"), "scenario", r.String("scenario"));
  s.scenario = ResolveScenarioPath((fs::path(path).parent_path() / r.String("scenario")).lexically_normal().string());
  if (!fs::is_regular_file(s.scenario)) r.Fail("scenario", "no such file: " + s.scenario);
  s.duration_s = r.Number("duration", 0.0);
  if (r.Has("duration") && !ValidDuration(s.duration_s)) r.Fail("duration", "must be > 0 s and at most 1e6 s");
  const std::vector<long long> seeds = ReadSeeds(r);
  std::vector<std::string> common;
  const YAML::Node set = r.Sequence("set");
  for (std::size_t i = 0; i < set.size(); ++i)
    common.push_back(CommonSet(path, set[i], "set[" + std::to_string(i) + "]"));

  // override sets: the grid's combinations, or the list's entries, or one empty set
  std::vector<std::vector<std::string>> sets = {{}};
  const YAML::Node grid = r.Raw("grid");
  const YAML::Node list = r.Raw("list");
  if (grid.IsDefined() && list.IsDefined()) r.Fail("list", "give either grid or list, not both");
  if (grid.IsDefined()) {
    MapReader g(path, grid, "grid");
    for (const auto& item : grid) {
      const std::string key = item.first.Scalar();
      RefuseControl(path, item.first, "grid", key);
      const YAML::Node values = g.Sequence(key);
      if (values.size() == 0) g.Fail(key, "expected a non-empty list of values");
      std::vector<std::string> texts;
      for (std::size_t i = 0; i < values.size(); ++i) {
        texts.push_back(SetText(path, item.first, values[i], "grid." + key + "[" + std::to_string(i) + "]"));
      }
      std::vector<std::vector<std::string>> next;
      for (const auto& partial : sets) {
        for (const std::string& text : texts) {
          next.push_back(partial);
          next.back().push_back(text);
        }
      }
      sets = std::move(next);
    }
    g.Finish();
  } else if (list.IsDefined()) {
    if (!list.IsSequence() || list.size() == 0) r.Fail("list", "expected a non-empty list of {KEY: VALUE, ...}");
    sets.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string where = "list[" + std::to_string(i) + "]";
      if (!list[i].IsMap()) throw InputError(YamlError(path, list[i], where, "expected a mapping {KEY: VALUE, ...}"));
      std::vector<std::string> one;
      for (const auto& kv : list[i]) {
        one.push_back(SetText(path, kv.first, kv.second, where + "." + Printable(kv.first.Scalar())));
      }
      sets.push_back(one);
    }
  }
  r.Finish();

  const int width = sets.size() > 100 ? static_cast<int>(std::to_string(sets.size() - 1).size()) : 2;
  for (std::size_t p = 0; p < sets.size(); ++p) {
    std::vector<std::string> all = common;
    all.insert(all.end(), sets[p].begin(), sets[p].end());
    // every override set must load: a typo fails here, before any run
    Scenario scenario;
    try {
      scenario = LoadScenario(s.scenario, all);
    } catch (const InputError& e) {
      throw InputError(path + ": override set " + std::to_string(p) + ": " + e.what());
    }
    // what `vlab run` makes of the arguments (cli_run.cc): --duration and --seed replace the file's
    if (s.duration_s > 0) scenario.duration_s = s.duration_s;
    s.records.push_back(RecordOf(scenario));
    std::string label;
    for (const std::string& one : sets[p]) label += (label.empty() ? "" : ", ") + one;
    char index[32];
    std::snprintf(index, sizeof index, "p%0*zu", width, p);
    for (long long seed : seeds) {
      SweepRun run;
      run.id = std::string(index) + (seed >= 0 ? "_s" + std::to_string(seed) : "");
      run.seed = seed;
      run.sets = all;
      run.label = label;
      run.set = p;
      s.runs.push_back(run);
    }
  }
  return s;
}

std::vector<std::string> RunArguments(const Sweep& sweep, const SweepRun& run, const std::string& out_dir) {
  std::vector<std::string> args = {"run", sweep.scenario};
  if (run.seed >= 0) {
    args.push_back("--seed");
    args.push_back(std::to_string(run.seed));
  }
  if (sweep.duration_s > 0) {
    std::ostringstream d;
    d.precision(17);
    d << sweep.duration_s;
    args.push_back("--duration");
    args.push_back(d.str());
  }
  for (const std::string& set : run.sets) {
    args.push_back("--set");
    args.push_back(set);
  }
  args.push_back("--out");
  args.push_back(out_dir + "/" + run.id);
  args.push_back("-q");
  return args;
}

RunRecord RecordOfRun(const Sweep& sweep, const SweepRun& run) {
  RunRecord record = sweep.records.at(run.set);
  if (run.seed >= 0) record.seed = static_cast<std::uint64_t>(run.seed);
  return record;
}

RunState CheckRun(const Sweep& sweep, const SweepRun& run, const std::string& run_dir) {
  RunState state;
  std::ifstream in(run_dir + "/summary.json");
  if (!in) {
    state.why = "not run yet";
    return state;
  }
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  if (summary.is_object() && summary.contains("result") && summary["result"].is_string()) {
    state.result = summary["result"].get<std::string>();
  }
  if (state.result.empty() || state.result == "interrupted") {
    state.why = state.result.empty() ? "its summary.json is unreadable" : "interrupted";
    return state;
  }
  state.why = RecordChange(summary, RecordOfRun(sweep, run));
  state.stale = !state.why.empty();
  state.current = !state.stale;
  return state;
}

}  // namespace vlab::lab
