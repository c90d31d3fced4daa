// The run log as a MATLAB file (log.mat), with Debian's libmatio.
//
// One variable per column group (ColumnGroup: "pa10.q.S1" is in pa10.q): a
// 1x1 struct with fields `data` (rows x columns, double), `names` and `units`
// (char matrices, one blank-padded row per column; cellstr() makes them
// cells), named after the group with every
// character MATLAB does not take in a name replaced by '_' (pa10_q, jr3,
// controller_p_des). MAT 5 with zlib compression (MATLAB's -v7), not MAT 7.3:
// Octave 7's `load` of a MAT 7.3 file that libmatio writes reads char arrays
// as uint16 and skips cell arrays. MAT 5 holds at most 2 GiB per variable.
//
// A .mat variable is written whole, so during the run the writer thread
// appends the raw rows (float64, native order) to a hidden file beside the
// .mat (.NAME.rows, flushed each block); Close builds the .mat from it, a group
// at a time (memory: one group's matrix), and removes it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lab/outputs/lab_log.h"

namespace vlab::lab {

/// The MAT version written: "5 (compressed)".
std::string MatFileVersion();

/// The MATLAB variable name of a column group: [A-Za-z0-9_] kept, anything
/// else '_', a leading non-letter prefixed with "v", at most 63 characters.
std::string MatVariableName(const std::string& group);

/// Creates the hidden rows file beside `path` for a .mat of `columns`; Close
/// writes `path`. Throws std::runtime_error naming the path when the rows
/// file cannot be created.
std::unique_ptr<LogSink> OpenMatSink(const std::string& path, const std::vector<std::string>& columns);

}  // namespace vlab::lab
