// RunSession's files: the first failed write stops the run, and whatever was
// written is kept (the output folder is committed as a failed run); the files
// of the run's end (log closed, images, poses, plots, summary.json).
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "lab/outputs/lab_plot.h"
#include "lab/run/lab_run_session.h"

namespace vlab::lab {

namespace {

// `text` with every `from` replaced by `to`
std::string ReplaceAll(std::string text, const std::string& from, const std::string& to) {
  if (from.empty()) return text;
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

}  // namespace

McapLogContent RunSession::McapContent() const {
  McapLogContent content;
  content.period_s = period_;
  if (poses_) {
    content.bodies = poses_->body_names();
    content.scene = std::make_shared<const nlohmann::json>(poses_->Geometry());
    content.poses_interval_s = poses_->interval_s();
  }
  for (const ImageOutputConfig& image : s_.scenario.outputs.images) {
    if (images_ && image.png) content.cameras.push_back({image.camera, out_->File(image.camera), image.every_s});
  }
  return content;
}

void RunSession::FeedMcap() {
  // lock-free, never waits (lab_log_mcap.h); a frame is handed over once its files are written
  if (poses_ && poses_->frames() > mcap_poses_) {
    mcap_->PushPoses(poses_->last_time_s(), poses_->poses().data());
    mcap_poses_ = poses_->frames();
  }
  for (McapCameraFeed& feed : mcap_cameras_) {
    const std::vector<double>& times = images_->frame_times(feed.output);
    for (; feed.frames < times.size(); ++feed.frames) {
      mcap_->PushFrame(feed.camera, static_cast<long>(feed.frames), times[feed.frames]);
    }
  }
}

bool RunSession::Recorded(double t) {
  try {
    RenderAfterPublish(t);
  } catch (const std::runtime_error& e) {  // a frame that could not be written or rendered
    if (!output_failed_) StopOnOutputFailure(e.what());
  }
  if (output_failed_) return false;
  // the log's writer thread and the pose file say so at once (a flag each, lock-free)
  if (log_ && log_->failed()) {
    StopOnOutputFailure(log_->error());
  } else if (poses_ && poses_->failed()) {
    StopOnOutputFailure(poses_->error());
  }
  return !output_failed_;
}

void RunSession::StopOnOutputFailure(const std::string& why) {
  output_failed_ = true;
  result_.failure = why + "; the run stopped at t = " + FormatDouble(k_ * period_) + " s of " +
                    FormatDouble(periods_ * period_) + " s";
  result_.exit_code = 1;
}

void RunSession::NoteWriteFailure(const std::string& why) {
  if (output_failed_) return;  // the first failure is the one that tells
  output_failed_ = true;
  result_.failure = why + (result_.failure.empty() ? "" : "; and: " + result_.failure);
  result_.exit_code = 1;
}

void RunSession::WriteOutputs() {
  // each file is attempted whatever failed before it: what can be written is kept
  const auto attempt = [this](const std::function<void()>& write) {
    try {
      write();
    } catch (const std::runtime_error& e) {
      NoteWriteFailure(e.what());
    }
  };
  // the image outputs' frame of the last state (`last`), before log.mcap closes with the log
  attempt([this] {
    if (!images_ || output_failed_ || diverged_) return;
    images_->ObserveLast(k_ * period_, d_);
    if (mcap_) FeedMcap();
  });
  attempt([this] {
    if (!log_) return;
    result_.log_waits = log_->waits();
    result_.log_wait_s = log_->wait_s();
    log_->Close();
  });
  if (!output_failed_) EvaluateGoldenChecks();  // (a log cut short by a failed write is not compared)
  attempt([this] {
    if (images_) images_->Finish();
  });
  attempt([this] {
    if (poses_) poses_->Finish();
  });
  // the task programs' print() lines and a script error's first line, with the simulated time
  attempt([this] {
    if (!s_.task) return;
    const std::string path = out_->File("task.log");
    std::ofstream file(path, std::ios::binary);
    file << result_.task_output;
    errno = 0;
    file.close();
    if (!file) {
      throw std::runtime_error("task log '" + out_->final_dir() +
                               "/task.log': write failed: " + std::strerror(errno ? errno : EIO));
    }
  });
  // a plot that cannot be drawn fails the run, and the rest is written; a plot of a CSV
  // that an external controller writes into {out} is skipped where the lab did not start
  // the controller (vlab serve: one started by hand has no {out}) and the file is not there
  for (const PlotConfig& plot : s_.scenario.outputs.plots) {
    if (!controller_ && plot.csv != "log.csv" && !std::filesystem::exists(out_->File(plot.csv))) {
      result_.plots_skipped.push_back(plot.file + ": no " + plot.csv +
                                      " (written by an external controller that vlab run starts)");
      continue;
    }
    try {
      WritePlot(out_->File(""), plot);
    } catch (const std::runtime_error& e) {
      // an interrupted run (or one a failed write stopped) keeps its verdict: a plot of a
      // CSV that was not written whole is skipped
      if (result_.interrupted_by || output_failed_) {
        result_.plots_skipped.push_back(plot.file + ": the run " +
                                        (output_failed_ ? "stopped on a failed write" : "was interrupted") + ": " +
                                        e.what());
        continue;
      }
      if (result_.failure.empty()) result_.failure = e.what();
      result_.exit_code = 1;
    }
  }
  // the summary names the files where they will be, not in the staging folder
  result_.failure = ReplaceAll(result_.failure, out_->staging_dir(), out_->final_dir());
  result_.total_wall_s = std::chrono::duration<double>(WallClock::now() - t_start_).count();
  nlohmann::json summary_json = SummaryJson(s_.scenario, m_, result_);
  if (images_) summary_json["images"] = images_->Summary();
  const std::string summary_path = out_->File("summary.json");
  std::ofstream summary(summary_path);
  summary << summary_json.dump(2) << "\n";
  errno = 0;
  summary.close();
  if (!summary) {
    const std::string why = std::strerror(errno ? errno : EIO);
    NoteWriteFailure("summary '" + out_->final_dir() + "/summary.json': write failed: " + why);
  }
  // the folder goes into place whatever failed: a run's files are never thrown away
  result_.out_dir = out_->Commit();
  result_.out_note = out_->note();
  if (output_failed_) result_.failure += "; what was written is in " + result_.out_dir + "/";
}

}  // namespace vlab::lab
