#include "lab/outputs/lab_log_convert.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "lab/outputs/lab_log_hdf5.h"
#include "lab/outputs/lab_output.h"
#include "lab/outputs/lab_output_fs.h"
#include "scene/scene_csv.h"

namespace vlab::lab {

namespace {

namespace fs = std::filesystem;

bool Exists(const std::string& path) {
  struct stat status {};
  return ::lstat(path.c_str(), &status) == 0;
}

// the rows of `table` into `sink`, a block at a time, then closed
void WriteAll(const scene::CsvTable& table, LogSink& sink) {
  const std::size_t n = table.columns.size();
  std::vector<double> block;
  for (std::size_t r0 = 0; r0 < table.rows.size(); r0 += RunLog::kRowsPerBlock) {
    block.clear();
    const std::size_t end = std::min(table.rows.size(), r0 + RunLog::kRowsPerBlock);
    for (std::size_t r = r0; r < end; ++r) block.insert(block.end(), table.rows[r].begin(), table.rows[r].end());
    const std::string why = sink.Write(block.data(), static_cast<int>(block.size() / (n ? n : 1)));
    if (!why.empty()) throw std::runtime_error(why);
  }
  const std::string why = sink.Close();
  if (!why.empty()) throw std::runtime_error(why);
}

}  // namespace

ConvertResult ConvertLog(const std::string& run_dir, LogFormat to, bool force) {
  std::error_code ec;
  if (!fs::is_directory(run_dir, ec)) throw InputError("run folder '" + run_dir + "': not a folder");
  ConvertResult result;
  const std::string name = LogFileName(to);
  result.target = (fs::path(run_dir) / name).string();
  const std::string csv = (fs::path(run_dir) / "log.csv").string();
  const std::string h5 = (fs::path(run_dir) / "log.h5").string();
  // to csv: from log.h5; to hdf5: from log.csv; to mat: log.csv, else log.h5
  result.source = to == LogFormat::kCsv ? h5 : to == LogFormat::kHdf5 ? csv : Exists(csv) ? csv : h5;
  if (!Exists(result.source)) {
    const std::string from = to == LogFormat::kCsv    ? "log.h5"
                             : to == LogFormat::kHdf5 ? "log.csv"
                                                      : "log.csv or log.h5";
    throw InputError("run folder '" + run_dir + "': no " + from + " to convert");
  }

  // the target: absent, or (with force) a regular file vlab's list names
  if (Exists(result.target)) {
    if (!force) throw InputError(result.target + ": exists (--force replaces it, if vlab wrote it)");
    const auto list = output_fs::ReadManifest(run_dir);
    struct stat status {};
    ::lstat(result.target.c_str(), &status);
    if (!S_ISREG(status.st_mode) || !list || !list->count(name)) {
      throw InputError(result.target + ": exists and vlab did not write it (not in the run folder's " +
                       std::string(kOutputMarker) + " list): not replaced, even with --force");
    }
  }

  // the source, read whole (InputError naming the file and line)
  scene::CsvTable table;
  if (result.source == csv) {
    table = scene::ReadCsvTable(csv);
  } else {
    CheckInputFile(h5, "HDF5 log '" + h5 + "'", kMaxCsvBytes);
    table = ReadHdf5Log(h5);
  }

  // written under a temporary name, renamed into place
  const std::string temporary = (fs::path(run_dir) / ("." + name + ".tmp-" + std::to_string(::getpid()))).string();
  try {
    std::unique_ptr<LogSink> sink = OpenLogSink(to, temporary, table.columns);
    WriteAll(table, *sink);
  } catch (...) {
    ::unlink(temporary.c_str());
    throw;
  }
  const int rc = force ? (::rename(temporary.c_str(), result.target.c_str()) == 0 ? 0 : errno)
                       : output_fs::RenameNoReplace(temporary, result.target);
  if (rc != 0) {
    ::unlink(temporary.c_str());
    throw std::runtime_error(result.target + ": cannot rename the written file into place: " + std::strerror(rc));
  }
  const std::string unlisted = AddToOutputList(run_dir, name);
  if (!unlisted.empty()) result.note = "not added to the run folder's list of vlab's files: " + unlisted;
  return result;
}

}  // namespace vlab::lab
