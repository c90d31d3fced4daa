#include "identify/identify_plant.h"

#include <charconv>
#include <random>
#include <vector>

#include "core/core_errors.h"
#include "core/core_output_file.h"
#include "scene/scene_csv.h"

namespace vlab::identify {

void ScaleBodyMass(mjModel* m, const std::string& body, double factor) {
  const int b = mj_name2id(m, mjOBJ_BODY, body.c_str());
  if (b < 0) throw InputError("no body named '" + body + "' in the model");
  m->body_mass[b] *= factor;
  for (int k = 0; k < 3; ++k) m->body_inertia[3 * b + k] *= factor;
}

void WriteNoisyLog(const std::string& in, const std::string& out, const std::string& columns, double sigma,
                   unsigned seed) {
  const scene::CsvTable table = scene::ReadCsvTable(in);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::string text;
  for (std::size_t c = 0; c < table.columns.size(); ++c) text += (c ? "," : "") + table.columns[c];
  text += "\n";
  char buffer[32];
  for (const std::vector<double>& row : table.rows) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      double v = row[c];
      if (table.columns[c].find(columns) != std::string::npos) v += noise(rng);
      text += (c ? "," : "") + std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, v).ptr);
    }
    text += "\n";
  }
  WriteOutputFile(out, text);
}

}  // namespace vlab::identify
