#include "lab/sweep/lab_collect.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_plot.h"

namespace vlab::lab {

namespace fs = std::filesystem;

namespace {

std::string Text(const nlohmann::json& v) {
  if (v.is_null()) return "nan";
  if (v.is_number_float()) return FormatDouble(v.get<double>());
  if (v.is_number()) return v.dump();
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  return v.dump();
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

void AddColumn(std::vector<std::string>& columns, const std::string& name) {
  if (std::find(columns.begin(), columns.end(), name) == columns.end()) columns.push_back(name);
}

}  // namespace

int CollectedTable::Column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
}

CollectedTable CollectRuns(const std::string& dir, bool timings) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": not a folder");
  std::vector<std::string> ids;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_directory() && fs::is_regular_file(e.path() / "summary.json")) ids.push_back(e.path().filename().string());
  }
  std::sort(ids.begin(), ids.end());
  if (ids.empty()) throw InputError(dir + ": no run folders (DIR/ID/summary.json)");
  // every run's values by column name; the columns in order of first appearance
  std::vector<std::map<std::string, std::string>> values;
  std::vector<std::string> sets, checks;
  CollectedTable t;
  for (const std::string& id : ids) {
    const std::string file = dir + "/" + id + "/summary.json";
    const nlohmann::json s =
        nlohmann::json::parse(ReadInputFile(file, "'" + file + "'", kMaxJsonBytes), nullptr, false);
    if (s.is_discarded() || !s.is_object()) throw InputError(file + ": not a summary.json (not JSON)");
    std::map<std::string, std::string> v;
    v["id"] = id;
    v["scenario"] = Text(s.value("scenario", nlohmann::json("")));
    v["seed"] = Text(s.value("seed", nlohmann::json(nullptr)));
    v["duration_s"] = Text(s.value("duration_s", nlohmann::json(nullptr)));
    const std::string result = s.value("result", "");
    v["result"] = result;
    v["exit_code"] = Text(s.value("exit_code", nlohmann::json(nullptr)));
    (result == "pass" ? t.pass : result == "interrupted" ? t.interrupted : t.failed) += 1;
    if (s.contains("overrides") && s["overrides"].is_object()) {
      for (const auto& [key, value] : s["overrides"].items()) {
        AddColumn(sets, "set:" + key);
        v["set:" + key] = Text(value);
      }
    }
    if (s.contains("checks") && s["checks"].is_array()) {
      for (const auto& c : s["checks"]) {
        const std::string name = c.value("name", "?");
        AddColumn(checks, name);
        v[name] = Text(c.value("value", nlohmann::json(nullptr)));
        v[name + ".verdict"] = c.contains("skipped") ? "skip" : c.value("pass", false) ? "pass" : "fail";
      }
    }
    if (timings && s.contains("timings")) {
      for (const char* k : {"sim_time_s", "loop_wall_s", "total_wall_s", "steps_per_s"}) {
        v[k] = Text(s["timings"].value(k, nlohmann::json(nullptr)));
      }
    }
    values.push_back(std::move(v));
  }
  t.columns = {"id", "scenario", "seed", "duration_s", "result", "exit_code"};
  t.columns.insert(t.columns.end(), sets.begin(), sets.end());
  for (const std::string& c : checks) {
    t.columns.push_back(c);
    t.columns.push_back(c + ".verdict");
  }
  if (timings) {
    for (const char* k : {"sim_time_s", "loop_wall_s", "total_wall_s", "steps_per_s"}) t.columns.push_back(k);
  }
  for (const auto& v : values) {
    std::vector<std::string> row;
    for (const std::string& c : t.columns) {
      const auto it = v.find(c);
      row.push_back(it == v.end() ? "" : it->second);
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

std::string CollectedCsv(const CollectedTable& table) {
  std::string out;
  for (std::size_t i = 0; i < table.columns.size(); ++i) out += (i ? "," : "") + CsvField(table.columns[i]);
  out += "\n";
  for (const auto& row : table.rows) {
    for (std::size_t i = 0; i < row.size(); ++i) out += (i ? "," : "") + CsvField(row[i]);
    out += "\n";
  }
  return out;
}

void PlotCollected(const CollectedTable& table, const std::string& key, const std::string& check,
                   const std::string& png) {
  const std::string x_column = key == "seed" ? "seed" : "set:" + key;
  const int xi = table.Column(x_column), yi = table.Column(check);
  if (xi < 0) throw InputError("--x " + key + ": no run overrides it (collected columns: set:KEY for each --set KEY)");
  const bool verdict = check.size() > 8 && check.compare(check.size() - 8, 8, ".verdict") == 0;
  if (yi < 0 || verdict) {
    throw InputError("--y " + check + ": no check of that name in the runs");
  }
  // one line per group: the seed, or (x = seed) the other overrides
  std::map<std::string, std::map<double, std::string>> lines;
  std::set<double> xs;
  for (const auto& row : table.rows) {
    char* end = nullptr;
    const double x = std::strtod(row[xi].c_str(), &end);
    if (row[xi].empty() || *end != '\0' || !std::isfinite(x)) {
      throw InputError("--x " + key + ": value '" + row[xi] + "' of run " + row[0] + " is not a number");
    }
    std::string group;
    if (key == "seed") {
      for (std::size_t c = 0; c < table.columns.size(); ++c) {
        if (table.columns[c].rfind("set:", 0) == 0)
          group += (group.empty() ? "" : " ") + table.columns[c].substr(4) + "=" + row[c];
      }
      if (group.empty()) group = "runs";
    } else {
      group = "seed " + row[table.Column("seed")];
    }
    lines[group][x] = row[yi];
    xs.insert(x);
  }
  if (xs.size() < 2) throw InputError("--x " + key + ": fewer than two values to draw against");
  // the plot's CSV beside the PNG, drawn, then removed
  const fs::path target = fs::absolute(png);
  const std::string data = target.filename().string() + ".data-" + std::to_string(::getpid()) + ".csv";
  PlotConfig plot;
  plot.file = target.filename().string();
  plot.csv = data;
  plot.x = key;
  plot.title = check + " against " + key;
  plot.ylabel = check;
  std::string csv = key;
  for (const auto& [group, points] : lines) {
    plot.y.push_back(group);
    csv += "," + CsvField(group);
  }
  csv += "\n";
  for (double x : xs) {
    csv += FormatDouble(x);
    for (const auto& [group, points] : lines) {
      const auto it = points.find(x);
      csv += "," + (it == points.end() ? std::string("nan") : it->second);
    }
    csv += "\n";
  }
  const std::string data_path = (target.parent_path() / data).string();
  {
    std::ofstream out(data_path);
    if (!out) throw InputError(data_path + ": cannot write (the plot's folder must exist)");
    out << csv;
  }
  try {
    WritePlot(target.parent_path().string(), plot);
  } catch (...) {
    fs::remove(data_path);
    throw;
  }
  fs::remove(data_path);
}

}  // namespace vlab::lab
