// vlab convert RUN_DIR --to mat|hdf5|mcap|csv: a run's log written again in another
// format next to it (lab_log_convert.h). Exit: 0 written; 1 a write failed;
// 2 bad input (no such folder or log, a malformed log, a target it may not
// replace).
#include <cstdio>
#include <memory>
#include <string>

#include "cli/cli_commands.h"
#include "core/core_errors.h"
#include "lab/outputs/lab_log_convert.h"
#include "lab/outputs/lab_log_mat.h"

namespace vlab::cli {

namespace {

struct ConvertArgs {
  std::string run_dir;
  std::string to;
  bool force = false;
};

int Convert(const ConvertArgs& a) {
  const lab::LogFormat to = lab::ParseLogFormat(a.to, "--to");
  const lab::ConvertResult result = lab::ConvertLog(a.run_dir, to, a.force);
  std::printf("%s: written from %s%s\n", result.target.c_str(), result.source.c_str(),
              to == lab::LogFormat::kMat ? (" (MAT " + lab::MatFileVersion() + ")").c_str() : "");
  if (!result.note.empty()) std::fprintf(stderr, "note: %s\n", result.note.c_str());
  return 0;
}

}  // namespace

Subcommand AddConvertCommand(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Write a run's log in another format next to it: RUN_DIR/log.mat (MATLAB/Octave: one struct per column group "
      "with fields data, names, units), RUN_DIR/log.h5 (HDF5: dataset /log with attributes columns and units), "
      "RUN_DIR/log.mcap (MCAP, ROS 2 messages: the signals, and the run's poses.bin and camera PNG frames where it has "
      "them) or RUN_DIR/log.csv. Reads log.csv (--to csv: log.h5; --to mat, mcap: log.csv, else log.h5). Writes a "
      "temporary file "
      "and renames it into place; an existing target is refused, and replaced with --force only if vlab wrote it. "
      "Exit: 0 written; 1 a write failed; 2 bad input");
  cmd->add_option("RUN_DIR", args->run_dir, "A run's output folder (out/NAME)")->required();
  cmd->add_option("--to", args->to, "Target format: mat, hdf5, mcap or csv")->required();
  cmd->add_flag("--force", args->force, "Replace the target if it exists and vlab wrote it");
  return {cmd, [args] { return WithErrorReport([&] { return Convert(*args); }); }};
}

}  // namespace vlab::cli
