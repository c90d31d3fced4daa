// Line plots (PNG) of a run's CSV files: the scenario's `outputs: plots:`.
//
// A plot reads one CSV of the output folder (a header line of column names,
// then numbers), draws every `y` column against the `x` column with axes,
// "nice" ticks, a grid, a legend and a title, and writes the PNG into the same
// folder. Drawn with OpenCV after the run, so it never touches the step loop.
#pragma once

#include <string>
#include <vector>

#include "lab/scenario/lab_scenario.h"

namespace vlab::lab {

/// Throws InputError naming the plot's scenario line when one of its columns
/// is not among `columns` and the plot reads log.csv (checked before a run).
void CheckPlotColumns(const PlotConfig& plot, const std::vector<std::string>& columns);

/// Reads dir/plot.csv and writes dir/plot.file. Throws std::runtime_error
/// naming the plot, the file and the column when the CSV is missing, lacks a
/// column or holds no number; nothing is written then.
void WritePlot(const std::string& dir, const PlotConfig& plot);

/// Tick positions for [lo, hi]: multiples of 1, 2 or 5 × 10^k, about `count` of them.
std::vector<double> NiceTicks(double lo, double hi, int count);

}  // namespace vlab::lab
