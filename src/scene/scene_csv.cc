#include "scene/scene_csv.h"

#include <cerrno>
#include <cstdlib>
#include <sstream>

#include "core/core_errors.h"
#include "core/core_input_file.h"

namespace vlab::scene {

namespace {

std::vector<std::string> SplitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

}  // namespace

int CsvTable::Column(const std::string& name) const {
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i] == name) return static_cast<int>(i);
  }
  return -1;
}

CsvTable ReadCsvTable(const std::string& path) {
  std::istringstream in(ReadInputFile(path, "CSV log '" + path + "'", kMaxCsvBytes));
  CsvTable t;
  t.file = path;
  std::string line;
  if (!std::getline(in, line) || line.empty()) throw InputError(path + ":1: expected a header line of column names");
  t.columns = SplitFields(line);
  long number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    const std::vector<std::string> fields = SplitFields(line);
    if (fields.size() != t.columns.size()) {
      throw InputError(path + ":" + std::to_string(number) + ": " + std::to_string(fields.size()) +
                       " fields, the header has " + std::to_string(t.columns.size()));
    }
    std::vector<double> row(fields.size());
    for (std::size_t i = 0; i < fields.size(); ++i) {
      char* end = nullptr;
      errno = 0;
      row[i] = std::strtod(fields[i].c_str(), &end);
      if (fields[i].empty() || *end != '\0') {
        throw InputError(path + ":" + std::to_string(number) + ": " + t.columns[i] + ": not a number: '" + fields[i] +
                         "'");
      }
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

}  // namespace vlab::scene
