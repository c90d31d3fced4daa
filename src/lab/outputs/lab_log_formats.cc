#include "lab/outputs/lab_log_formats.h"

#include <stdexcept>
#include <utility>

#include "core/core_errors.h"
#include "lab/outputs/lab_log_hdf5.h"
#include "lab/outputs/lab_log_mat.h"

namespace vlab::lab {

namespace {

// quantity (the name's part after the device) -> unit; a vector quantity's axis (p.x) counts its group
const std::pair<const char*, const char*> kUnits[] = {
    {"q", "rad"},                // arm joints (revolute; a prismatic joint's would be m)
    {"qd", "rad/s"},             //
    {"tau", "N*m"},              // joint torques
    {"following_error", "rad"},  //
    {"limit_violation", "rad"},  // how far past a joint limit
    {"Fx", "N"},
    {"Fy", "N"},
    {"Fz", "N"},  // wrench sensors
    {"Mx", "N*m"},
    {"My", "N*m"},
    {"Mz", "N*m"},
    {"position_error", "m"},       // controllers
    {"orientation_error", "rad"},  //
    {"p", "m"},
    {"p_des", "m"},  // positions (per axis)
    {"x", "m"},
    {"y", "m"},
    {"z", "m"},  // body positions
    {"vx", "m/s"},
    {"vy", "m/s"},
    {"vz", "m/s"},
    {"wx", "rad/s"},
    {"wy", "rad/s"},
    {"wz", "rad/s"},
    {"spin_rpm", "1/min"},
    {"rpm", "1/min"},
    {"revolutions", "turns"},
    {"precess_rate", "rad/s"},
    {"string_force", "N"},
    {"force", "N"},
    {"opening", "m"},
    {"opening_velocity", "m/s"},
    {"error_deg", "deg"},
    {"yaw_error", "deg"},
    {"pos_error", "m"},
    {"u", "px"},
    {"v", "px"},
};

// each format's scenario name and file in the output folder
struct FormatEntry {
  LogFormat format;
  const char* name;
  const char* file;
};
const FormatEntry kFormats[] = {
    {LogFormat::kCsv, "csv", "log.csv"},
    {LogFormat::kMat, "mat", "log.mat"},
    {LogFormat::kHdf5, "hdf5", "log.h5"},
    {LogFormat::kMcap, "mcap", "log.mcap"},
};

const char* UnitOf(const std::string& quantity) {
  for (const auto& [name, unit] : kUnits) {
    if (quantity == name) return unit;
  }
  return nullptr;
}

}  // namespace

LogFormat ParseLogFormat(const std::string& name, const std::string& where) {
  for (const FormatEntry& entry : kFormats) {
    if (name == entry.name) return entry.format;
  }
  throw InputError(where + ": unknown log format '" + name + "' (csv, mat, hdf5 or mcap)");
}

std::vector<std::string> LogFormatNames() {
  std::vector<std::string> names;
  for (const FormatEntry& entry : kFormats) names.emplace_back(entry.name);
  return names;
}

const char* LogFileName(LogFormat format) {
  for (const FormatEntry& entry : kFormats) {
    if (entry.format == format) return entry.file;
  }
  return "?";
}

std::string ColumnGroup(const std::string& column) {
  const std::size_t dot = column.rfind('.');
  return dot == std::string::npos ? column : column.substr(0, dot);
}

std::string ColumnUnit(const std::string& column) {
  if (column == "time") return "s";
  // the part before the last names the quantity (pa10.q.S1, controller.p.x), else the last does (jr3.Fx)
  const std::size_t last = column.rfind('.');
  if (last == std::string::npos) return "";
  const std::size_t before = last == 0 ? std::string::npos : column.rfind('.', last - 1);
  if (before != std::string::npos) {
    if (const char* unit = UnitOf(column.substr(before + 1, last - before - 1))) return unit;
  }
  const char* unit = UnitOf(column.substr(last + 1));
  return unit ? unit : "";
}

std::vector<ColumnGroupIndex> GroupColumns(const std::vector<std::string>& columns) {
  std::vector<ColumnGroupIndex> groups;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const std::string name = ColumnGroup(columns[i]);
    ColumnGroupIndex* group = nullptr;
    for (ColumnGroupIndex& g : groups) {
      if (g.name == name) group = &g;
    }
    if (!group) group = &groups.emplace_back(ColumnGroupIndex{name, {}});
    group->columns.push_back(static_cast<int>(i));
  }
  return groups;
}

std::unique_ptr<LogSink> OpenLogSink(LogFormat format, const std::string& path,
                                     const std::vector<std::string>& columns) {
  switch (format) {
    case LogFormat::kCsv:
      return OpenCsvSink(path, columns);
    case LogFormat::kMat:
      return OpenMatSink(path, columns);
    case LogFormat::kHdf5:
      return OpenHdf5Sink(path, columns);
    case LogFormat::kMcap:
      return std::make_unique<McapLogSink>(path, columns, McapLogContent{});
  }
  throw std::logic_error("log format " + std::to_string(static_cast<int>(format)));
}

std::vector<std::unique_ptr<LogSink>> OpenLogSinks(const std::string& folder, const std::vector<LogFormat>& formats,
                                                   const std::vector<std::string>& columns) {
  std::vector<std::unique_ptr<LogSink>> sinks;
  for (LogFormat format : formats) sinks.push_back(OpenLogSink(format, folder + "/" + LogFileName(format), columns));
  return sinks;
}

std::unique_ptr<RunLog> OpenRunLog(const std::string& folder, const std::vector<std::string>& formats,
                                   const std::vector<std::string>& columns, const McapLogContent& mcap,
                                   McapLogSink** mcap_sink) {
  std::vector<LogFormat> parsed;
  for (const std::string& name : formats) parsed.push_back(ParseLogFormat(name, "outputs.log.format"));
  const std::string first = folder + "/" + (parsed.empty() ? "log.csv" : LogFileName(parsed.front()));
  if (mcap_sink) *mcap_sink = nullptr;
  std::vector<std::unique_ptr<LogSink>> sinks;
  for (LogFormat format : parsed) {
    const std::string path = folder + "/" + LogFileName(format);
    if (format != LogFormat::kMcap) {
      sinks.push_back(OpenLogSink(format, path, columns));
      continue;
    }
    auto sink = std::make_unique<McapLogSink>(path, columns, mcap);
    if (mcap_sink) *mcap_sink = sink.get();
    sinks.push_back(std::move(sink));
  }
  return RunLog::Open(std::move(sinks), first, columns);
}

}  // namespace vlab::lab
