// The run log as a MATLAB file (log.mat), MAT 5 with zlib compression
// (MATLAB's -v7), written here with zlib (no MAT library).
//
// One variable per column group (ColumnGroup: "pa10.q.S1" is in pa10.q): a
// 1x1 struct with fields `data` (rows x columns, double), `names` and `units`
// (char matrices, one blank-padded row per column; cellstr() makes them
// cells), named after the group with every
// character MATLAB does not take in a name replaced by '_' (pa10_q, jr3,
// controller_p_des). Not MAT 7.3: Octave 7's `load` of a MAT 7.3 file as
// libmatio writes it reads char arrays as uint16 and skips cell arrays. MAT 5
// holds at most 4 GiB per variable (refused by name beyond that).
//
// A variable is one zlib stream of column-major data, so it cannot be written
// before the run's last row. During the run the writer thread compresses each
// column on its own (a raw deflate stream per column, level 1, 4 KiB window)
// and spills the compressed bytes to a hidden file beside the .mat
// (.NAME.part); Close ends each column's stream byte-aligned without a final
// block, compresses each variable's head (its sizes are known now) and tail
// (names, units), and writes head, columns and tail back to back as one
// deflate stream, its Adler-32 combined from the pieces' (adler32_combine).
// The compression thus runs beside the step loop, and the end of the run only
// copies bytes. The same rows give the same file (no date in its header).
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

/// Creates the hidden file of compressed pieces beside `path` for a .mat of
/// `columns`; Close writes `path`. Throws std::runtime_error naming the path
/// when that file cannot be created.
std::unique_ptr<LogSink> OpenMatSink(const std::string& path, const std::vector<std::string>& columns);

}  // namespace vlab::lab
