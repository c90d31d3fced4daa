// The run log in HDF5 (log.h5), with Debian's libhdf5 (C API).
//
// One dataset, /log: float64, rows x columns, grown by each block of rows the
// log's writer thread hands over (chunks of kHdf5ChunkRows rows x 1 column,
// byte-shuffled and deflated, so each column compresses on its own). Its
// attributes `columns` and `units` hold the column names and units
// (variable-length UTF-8 strings, ColumnUnit). The file is flushed after each
// block, so an interrupted run (even one killed) leaves a valid file of every
// block written; the lab's normal end, an interrupt included, writes the rest.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lab/outputs/lab_log.h"
#include "scene/scene_csv.h"

namespace vlab::lab {

/// Rows per HDF5 chunk (a chunk holds one column).
inline constexpr int kHdf5ChunkRows = 1024;

/// Creates `path` (replacing a file there) with an empty /log of
/// columns.size() columns and its attributes. Throws std::runtime_error
/// naming the path when it cannot be created.
std::unique_ptr<LogSink> OpenHdf5Sink(const std::string& path, const std::vector<std::string>& columns);

/// Reads a log.h5 back whole: its /log dataset and `columns` attribute (the
/// table's file is `path`). Throws InputError naming the path when it is not
/// an HDF5 file, or has no /log of doubles with one name per column.
scene::CsvTable ReadHdf5Log(const std::string& path);

}  // namespace vlab::lab
