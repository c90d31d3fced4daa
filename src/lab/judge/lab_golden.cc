#include "lab/judge/lab_golden.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <unistd.h>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "lab/scenario/lab_yaml.h"

namespace vlab::lab {

namespace fs = std::filesystem;

GoldenSpec LoadGolden(const std::string& dir) {
  const std::string file = dir + "/golden.yaml";
  std::error_code ec;
  if (!fs::exists(file, ec)) {
    throw InputError(dir + ": not a golden folder (no golden.yaml; see docs/sweeps.md, golden runs)");
  }
  const YAML::Node root = LoadYamlFile(file, "golden");
  MapReader r(file, root, "");
  GoldenSpec g;
  g.dir = dir;
  g.scenario = (fs::path(dir) / r.String("scenario")).lexically_normal().string();
  if (!fs::exists(g.scenario, ec)) r.Fail("scenario", "no such file: " + g.scenario);
  try {
    CheckInputFile(g.scenario, "'" + g.scenario + "'", kMaxYamlBytes);
  } catch (const InputError& e) {
    r.Fail("scenario", e.what());
  }
  g.duration_s = r.Number("duration", 0.0);
  if (r.Has("duration") && !(g.duration_s > 0 && g.duration_s <= 1e6))
    r.Fail("duration", "must be > 0 s and at most 1e6 s");
  if (r.Has("seed")) g.seed = static_cast<long long>(YamlSeed(file, r.Raw("seed"), "seed"));
  g.sets = r.Strings("set", {});
  g.every = r.Integer("every", 1);
  if (g.every < 1) r.Fail("every", "must be >= 1");
  g.compare.from_s = r.Number("from", g.compare.from_s);
  g.compare.to_s = r.Number("to", g.compare.to_s);
  if (g.compare.to_s < g.compare.from_s) r.Fail("to", "must be >= from");
  g.compare.tolerances = ReadTolerances(file, r.Sequence("tolerances"), "tolerances");
  r.Finish();
  // the golden log, where there is one, is judged now, not after the run
  if (fs::exists(g.log(), ec) || fs::is_symlink(g.log(), ec)) {
    CheckInputFile(g.log(), "golden log '" + g.log() + "'", kMaxCsvBytes);
  }
  return g;
}

std::vector<ColumnTolerance> ReadTolerances(const std::string& file, const YAML::Node& tolerances,
                                            const std::string& path) {
  std::vector<ColumnTolerance> out;
  for (std::size_t i = 0; i < tolerances.size(); ++i) {
    MapReader t(file, tolerances[i], path + "[" + std::to_string(i) + "]");
    ColumnTolerance tol;
    tol.pattern = t.String("columns");
    tol.ignore = t.Bool("ignore", false);
    tol.abs = t.Number("abs", 0.0);
    tol.rel = t.Number("rel", 0.0);
    if (tol.abs < 0) t.Fail("abs", "must be >= 0");
    if (tol.rel < 0) t.Fail("rel", "must be >= 0");
    if (tol.ignore && (t.Has("abs") || t.Has("rel"))) t.Fail("ignore", "an ignored column has no tolerance");
    t.Finish();
    out.push_back(tol);
  }
  return out;
}

void WriteDecimatedLog(const std::string& from, const std::string& to, int every) {
  std::ifstream in(from);
  if (!in) throw std::runtime_error(from + ": cannot open file");
  const std::string tmp = to + ".partial-" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error(tmp + ": cannot create file");
    std::string line;
    long row = -1;  // the header
    while (std::getline(in, line)) {
      if (row < 0 || row % every == 0) out << line << '\n';
      ++row;
    }
    out.flush();
    if (!out) {
      std::error_code ignored;
      fs::remove(tmp, ignored);
      throw std::runtime_error(tmp + ": write error");
    }
  }
  std::error_code ec;
  fs::rename(tmp, to, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(to + ": cannot replace: " + ec.message());
  }
}

}  // namespace vlab::lab
