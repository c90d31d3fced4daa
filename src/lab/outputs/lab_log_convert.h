// `vlab convert`: a run's log written again in another format, next to it.
//
// The source is the run folder's log.csv, or its log.h5 where there is no
// log.csv (or the target is CSV). Both are user input: a FIFO, a file over the
// cap, a malformed row are refused with the file (and line) named. log.mcap
// also carries the folder's poses.bin (body names from scene.json) and each
// CAMERA/ folder's frames (frames.csv, rgb_NNNNNN.png), checked the same way
// before anything is written; from a run's own files it is the log.mcap the
// run wrote, byte for byte. The target (log.csv, log.mat, log.h5 or log.mcap)
// is written under a temporary name and renamed
// into place, so nothing half-written is ever left under its name. An
// existing target is refused, and replaced with `force` only when the run
// folder's list (lab_output.h) says vlab wrote it.
#pragma once

#include <string>

#include "lab/outputs/lab_log_formats.h"

namespace vlab::lab {

/// What ConvertLog did: the file read, the file written, and a note ("" or
/// one line, e.g. that the folder's list of vlab's files could not name it).
struct ConvertResult {
  std::string source;
  std::string target;
  std::string note;
};

/// Writes run_dir's log as `to`. Throws InputError naming the file for a
/// missing folder or source, a bad source, or a target it may not replace;
/// std::runtime_error naming the file when writing fails (the temporary file
/// is removed).
ConvertResult ConvertLog(const std::string& run_dir, LogFormat to, bool force);

}  // namespace vlab::lab
