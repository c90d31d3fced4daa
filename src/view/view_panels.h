// The view's optional panels: a camera device's pictures and a few signals
// plotted live (or from a run's log.csv in a replay), and the binary
// WebSocket messages that carry them to the page.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "bridge/bridge_camera.h"

namespace vlab::view {

/// Bytes of one camera message (channel /camera), little-endian:
///   float64 time (the frame's exposure stamp, s), float64 frame id,
///   uint32 width, uint32 height (px), then the picture: a JPEG frame's bytes
///   exactly as the camera sent them, or a raw RGB8 frame encoded as PNG
///   (lossless: the same pixels).
inline constexpr int kCameraHeaderBytes = 24;
std::string EncodeCameraMessage(const bridge::CameraFrame& frame);

/// Bytes of one plot message (channel /plot), little-endian: float64 time
/// (s), float64 seq (the state's control period), then one float64 value per
/// plotted signal, in the order of scene.json's "plots".
std::string EncodePlotMessage(double time, double seq, const std::vector<double>& values);

/// The comma-separated signal names of --plot ("pa10.q.S1,pa10.q.E1"):
/// 1 to kMaxPlotSignals names, each non-empty and at most 200 characters;
/// throws InputError naming --plot otherwise.
inline constexpr int kMaxPlotSignals = 8;
std::vector<std::string> ParsePlotSignals(const std::string& text);

/// The plotted signals of an arm device's states, named as log.csv names
/// them (ARM.q.JOINT, ARM.qd.JOINT, ARM.tau.JOINT).
class ArmSignals {
 public:
  /// Throws InputError naming the first signal the arm has not, and listing
  /// those it has.
  ArmSignals(const std::string& arm_name, const std::vector<std::string>& joint_names,
             const std::vector<std::string>& signals);
  /// The signals' values in a state (q, qd, tau: one entry per joint).
  std::vector<double> Values(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau) const;

 private:
  std::vector<int> quantity_, joint_;  // quantity 0 q, 1 qd, 2 tau
};

/// A replay's plots: the `signals` columns of the run's log.csv as rows of
/// float64 [time, value...] back to back (the /plots.bin resource). Throws
/// InputError naming the file and the first signal it lacks.
std::string ReplayPlotRows(const std::string& log_csv, const std::vector<std::string>& signals);

}  // namespace vlab::view
