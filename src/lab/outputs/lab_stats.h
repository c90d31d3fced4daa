// Small statistics for run reports and benchmarks.
#pragma once

#include <vector>

namespace vlab::lab {

/// p-th percentile (0..100) of a sample by nearest rank; NaN for an empty sample.
double Percentile(std::vector<double> sample, double p);

}  // namespace vlab::lab
