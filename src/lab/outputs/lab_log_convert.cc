#include "lab/outputs/lab_log_convert.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include "core/core_errors.h"
#include "core/core_input_file.h"

#include "lab/outputs/lab_log_hdf5.h"
#include "lab/outputs/lab_log_mcap.h"
#include "lab/outputs/lab_output.h"
#include "lab/outputs/lab_output_fs.h"
#include "scene/scene_csv.h"
#include "scene/scene_messages.h"

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

// what log.mcap carries besides the log, read from the run folder: the poses of
// scene.json's bodies in poses.bin, the frames of each CAMERA/ folder with frames.csv
struct RunExtras {
  McapLogContent content;
  std::vector<std::pair<double, std::vector<float>>> poses;
  std::vector<std::vector<double>> frame_times;  // per camera, in content.cameras' order
};

RunExtras ReadRunExtras(const std::string& run_dir) {
  RunExtras x;
  const std::string scene = (fs::path(run_dir) / "scene.json").string();
  const std::string poses = (fs::path(run_dir) / "poses.bin").string();
  if (Exists(poses)) {
    if (!Exists(scene)) throw InputError(poses + ": no scene.json beside it to name its bodies");
    nlohmann::json j =
        nlohmann::json::parse(ReadInputFile(scene, "scene '" + scene + "'", kMaxJsonBytes), nullptr, false);
    if (!j.is_object() || !j["bodies"].is_array()) throw InputError(scene + ": no list of bodies");
    for (const auto& body : j["bodies"]) {
      if (!body.is_string()) throw InputError(scene + ": a body's name is not a string");
      x.content.bodies.push_back(body.get<std::string>());
    }
    std::string update;  // the /scene message: a geometry it cannot encode is refused here, by name
    try {
      scene::EncodeSceneUpdate(0.0, j, nullptr, &update);
    } catch (const std::exception& e) {
      throw InputError(scene + ": not a scene's geometry (bodies, geoms): " + e.what());
    }
    x.content.scene = std::make_shared<const nlohmann::json>(std::move(j));
    CheckInputFile(poses, "poses '" + poses + "'", kMaxCsvBytes);
    std::ifstream in(poses, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw InputError(poses + ": cannot read");
    const std::size_t frame = 16 + 28 * x.content.bodies.size();
    if (bytes.size() % frame != 0) {
      throw InputError(poses + ": " + std::to_string(bytes.size()) + " bytes are not whole frames of " +
                       std::to_string(frame) + " (16 + 28 x " + std::to_string(x.content.bodies.size()) +
                       " bodies of scene.json)");
    }
    for (std::size_t at = 0; at < bytes.size(); at += frame) {
      auto& [t, values] = x.poses.emplace_back();
      std::memcpy(&t, bytes.data() + at, 8);
      values.resize(7 * x.content.bodies.size());
      std::memcpy(values.data(), bytes.data() + at + 16, 4 * values.size());
      if (!std::isfinite(t) || t < 0) throw InputError(poses + ": frame " + std::to_string(at / frame) + ": bad time");
    }
  }
  // the cameras, in name order (as a run writes them)
  std::vector<std::string> cameras;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(run_dir, ec)) {
    if (entry.is_directory() && Exists((entry.path() / "frames.csv").string())) {
      cameras.push_back(entry.path().filename().string());
    }
  }
  std::sort(cameras.begin(), cameras.end());
  for (const std::string& camera : cameras) {
    const fs::path folder = fs::path(run_dir) / camera;
    const scene::CsvTable frames = scene::ReadCsvTable((folder / "frames.csv").string());
    if (frames.columns != std::vector<std::string>{"frame", "time"}) {
      throw InputError((folder / "frames.csv").string() + ": expected the columns frame,time");
    }
    std::vector<double> times;
    for (std::size_t n = 0; n < frames.rows.size(); ++n) {
      char name[32];
      std::snprintf(name, sizeof(name), "rgb_%06zu.png", n);
      const double t = frames.rows[n][1];
      if (frames.rows[n][0] != static_cast<double>(n) || !std::isfinite(t) || t < 0) {
        throw InputError((folder / "frames.csv").string() + ":" + std::to_string(n + 2) + ": expected frame " +
                         std::to_string(n) + " at a time >= 0");
      }
      if (!Exists((folder / name).string())) {
        if (n == 0) break;  // a camera of depth or segmentation frames only
        throw InputError((folder / name).string() + ": missing (frames.csv lists frame " + std::to_string(n) + ")");
      }
      CheckInputFile((folder / name).string(), "frame '" + (folder / name).string() + "'", kMaxCsvBytes);
      times.push_back(t);
    }
    if (times.empty() && !frames.rows.empty()) continue;
    x.content.cameras.push_back({camera, folder.string(), 0});
    x.frame_times.push_back(std::move(times));
  }
  return x;
}

// log.mcap of `table` and the run folder's poses and frames
void WriteMcap(const std::string& path, const scene::CsvTable& table, const RunExtras& x) {
  const auto time = std::find(table.columns.begin(), table.columns.end(), "time");
  if (time == table.columns.end()) throw InputError(table.file + ": no column 'time'");
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const double t = table.rows[r][time - table.columns.begin()];
    if (!std::isfinite(t) || t < 0) throw InputError(table.file + ": row " + std::to_string(r + 1) + ": time < 0");
  }
  std::unique_ptr<McapLog> log = McapLog::Open(path, table.columns, x.content);
  for (const auto& [t, values] : x.poses) log->AddPoses(t, values.data());
  for (std::size_t c = 0; c < x.frame_times.size(); ++c) {
    for (std::size_t n = 0; n < x.frame_times[c].size(); ++n) {
      log->AddFrame(static_cast<int>(c), static_cast<long>(n), x.frame_times[c][n]);
    }
  }
  std::string why;
  for (const std::vector<double>& row : table.rows) {
    why = log->AddRows(row.data(), 1);
    if (!why.empty()) break;
  }
  const std::string closed = log->Close();
  if (!why.empty() || !closed.empty()) throw std::runtime_error(why.empty() ? closed : why);
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
  // to csv: from log.h5; to hdf5: from log.csv; to mat, mcap: log.csv, else log.h5
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
  RunExtras extras;
  if (to == LogFormat::kMcap) extras = ReadRunExtras(run_dir);  // (bad input refused before anything is written)

  // written under a temporary name, renamed into place
  const std::string temporary = (fs::path(run_dir) / ("." + name + ".tmp-" + std::to_string(::getpid()))).string();
  try {
    if (to == LogFormat::kMcap) {
      WriteMcap(temporary, table, extras);
    } else {
      std::unique_ptr<LogSink> sink = OpenLogSink(to, temporary, table.columns);
      WriteAll(table, *sink);
    }
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
