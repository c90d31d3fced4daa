// The run log's file formats (outputs.log.format): CSV (log.csv), HDF5
// (log.h5, lab_log_hdf5.h), MATLAB .mat (log.mat, lab_log_mat.h) and MCAP
// (log.mcap, lab_log_mcap.h: signals, poses and camera frames), and
// what the binary formats store beside the numbers: each column's unit and
// its group (the column name less its last '.' part).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_log_mcap.h"

namespace vlab::lab {

enum class LogFormat { kCsv, kMat, kHdf5, kMcap };

/// The format a name gives: "csv", "mat", "hdf5", "mcap". Throws InputError
/// naming `where` for any other name.
LogFormat ParseLogFormat(const std::string& name, const std::string& where);
/// The names of the formats, CSV's first ("csv", "mat", "hdf5", "mcap").
std::vector<std::string> LogFormatNames();
/// The log's file name in the output folder: log.csv, log.mat, log.h5 or
/// log.mcap.
const char* LogFileName(LogFormat format);

/// The unit of a column, from its quantity (the name's part after the
/// device): "s" for time, "rad" for q, "N" for Fx, ... (docs/scenarios.md
/// lists them); "" when the name does not tell (a flag, a count, an
/// unknown quantity).
std::string ColumnUnit(const std::string& column);
/// The group a column belongs to: the name less its last '.' part
/// ("pa10.q.S1": "pa10.q"; "jr3.Fx": "jr3"; "time": "time").
std::string ColumnGroup(const std::string& column);

/// The groups of `columns` in order of first appearance, each with the
/// indices of its columns.
struct ColumnGroupIndex {
  std::string name;
  std::vector<int> columns;
};
std::vector<ColumnGroupIndex> GroupColumns(const std::vector<std::string>& columns);

/// Opens the sink of `format` writing `path` (a CSV, .mat, HDF5 or MCAP log
/// of `columns`; MCAP: signals only). Throws std::runtime_error naming the
/// file when it cannot be created.
std::unique_ptr<LogSink> OpenLogSink(LogFormat format, const std::string& path,
                                     const std::vector<std::string>& columns);
/// Opens one sink per format, each at folder/LogFileName(format). Throws
/// std::runtime_error naming the file when one cannot be created (the ones
/// created before it are closed).
std::vector<std::unique_ptr<LogSink>> OpenLogSinks(const std::string& folder, const std::vector<LogFormat>& formats,
                                                   const std::vector<std::string>& columns);

/// The run's log in folder/: one file per format name ("csv", "mat",
/// "hdf5", "mcap"; ParseLogFormat), written by one writer thread; log.mcap
/// also carries `mcap` (its sink in *mcap_sink when not null; null without
/// mcap). Throws InputError for an unknown name, std::runtime_error naming
/// the file when one cannot be created.
std::unique_ptr<RunLog> OpenRunLog(const std::string& folder, const std::vector<std::string>& formats,
                                   const std::vector<std::string>& columns, const McapLogContent& mcap = {},
                                   McapLogSink** mcap_sink = nullptr);

}  // namespace vlab::lab
