// markers:next()'s lockstep rule (MarkersFrameDue, task_channel.h) against the
// lab camera's own schedule: sensors/sensor_camera.h renders frame i at the first
// period boundary at or after its exposure stamp (DueForRender) and stamps it
// with that boundary; src/lab/devices/device_camera.cc delivers it at the first
// boundary at which stamp + latency has passed (1 ns tolerance). For a call at
// every boundary t0 the rule must name the first frame stamped at or after t0
// and the boundary that delivers it, at which no later frame has been delivered
// (so a vision program that skips to the newest frame processes exactly it).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "sensors/sensor_camera.h"
#include "task/task_channel.h"

namespace vlab::task {
namespace {

struct CameraFrame {
  double time;      // the boundary that rendered it: the stamp its markers state carries
  double delivery;  // the boundary that delivered it
};

// the lab camera's schedule, by its own rules, over `duration_s`
std::vector<CameraFrame> LabSchedule(double fps, double exposure_s, double latency_s, double period_s,
                                     double duration_s) {
  sensors::CameraModelConfig c;
  c.fps = fps;
  c.exposure_s = exposure_s;
  c.latency_s = latency_s;
  const auto m = sensors::CameraModel::Create(c);
  std::vector<CameraFrame> frames;
  double t_prev = -1;
  const long periods = std::lround(duration_s / period_s);
  for (long k = 0; k <= periods; ++k) {
    const double t = static_cast<double>(k) * period_s;
    const sensors::FrameRange r = m->DueForRender(t_prev, t);
    for (std::int64_t i = r.first; i < r.end; ++i) frames.push_back({t, -1});
    for (CameraFrame& f : frames) {
      if (f.delivery < 0 && f.time + latency_s <= t + 1e-9) f.delivery = t;
    }
    t_prev = t;
  }
  return frames;
}

void CheckRule(double fps, double exposure_s, double latency_s, double period_s) {
  const double duration_s = 3.0;
  const std::vector<CameraFrame> frames = LabSchedule(fps, exposure_s, latency_s, period_s, duration_s + 1.0);
  const CameraTiming timing{fps, exposure_s, latency_s};
  const long periods = std::lround(duration_s / period_s);
  for (long k = 0; k <= periods; ++k) {
    const double t0 = static_cast<double>(k) * period_s;
    std::size_t wanted = 0;
    while (frames[wanted].time < t0 - 1e-9) ++wanted;  // the first frame stamped at or after t0
    double frame_time = -1;
    const double due = MarkersFrameDue(timing, period_s, t0, &frame_time);
    ASSERT_NEAR(frame_time, frames[wanted].time, 1e-9) << "t0 = " << t0;
    ASSERT_NEAR(due, frames[wanted].delivery, 1e-9) << "t0 = " << t0;
    if (wanted + 1 < frames.size()) {
      EXPECT_GT(frames[wanted + 1].delivery, due + 1e-9) << "t0 = " << t0 << ": a later frame is out by then";
    }
  }
}

TEST(MarkersFrameDueTest, LabWebcamAt500Hz) { CheckRule(30, 0, 0.03, 0.002); }  // scenes/pa10_cubes.yaml
TEST(MarkersFrameDueTest, ExposureAndAnAwkwardPeriod) { CheckRule(25, 0.013, 0.071, 1.0 / 333); }
TEST(MarkersFrameDueTest, NoLatencyAt100Hz) { CheckRule(30, 0, 0, 0.01); }

}  // namespace
}  // namespace vlab::task
