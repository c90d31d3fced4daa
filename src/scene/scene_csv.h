// A CSV log of numbers read back whole (a run's log.csv): for the view's plot
// panels, the log comparison and the goldens.
#pragma once

#include <string>
#include <vector>

namespace vlab::scene {

/// A CSV log in memory: header and rows of numbers.
struct CsvTable {
  std::string file;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  /// Index of a column, -1 when absent.
  int Column(const std::string& name) const;
};

/// Reads a CSV log of numbers with a header line (log.csv). Throws InputError
/// naming the file and line on a missing file, a row of the wrong width or a
/// field that is not a number.
CsvTable ReadCsvTable(const std::string& path);

}  // namespace vlab::scene
