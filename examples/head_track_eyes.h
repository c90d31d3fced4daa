// The vision and eye geometry of examples/head_track: finding the ball in an
// eye image, the eye angles that fixate a pixel, and which camera frame a
// controller may use at a given state time so that a lockstep run repeats
// bit for bit. Plain functions of their arguments, no I/O.
#pragma once

#include <cstdint>

namespace head_track {

/// Pinhole intrinsics of an eye image, pixels (OpenCV: u right, v down).
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

/// The ball in one image: the centroid of its pixels.
struct Blob {
  bool found = false;
  double u = 0, v = 0;  ///< centroid, px (pixel centres at whole numbers)
  int pixels = 0;       ///< pixels classified as ball
};

/// Finds a saturated red ball in an RGB8 image (rows top-down): pixels with
/// R >= 60 and R >= 2 max(G, B) + 20, their centroid; found when at least
/// min_pixels pixels qualify.
Blob FindBall(const std::uint8_t* rgb, int width, int height, int min_pixels = 6);

/// The eye angles of the humanoid head that put pixel (u, v) on the optical
/// axis, given the angles at the time of the image. The eye is a gimbal:
/// the common tilt (about the head's y axis, positive looks down) carries
/// the pan (about the tilted -z axis, positive looks right), and the camera
/// looks along the eye's x axis. rad.
struct EyeAngles {
  double pan = 0;
  double tilt = 0;
};
EyeAngles FixateAngles(double u, double v, const Intrinsics& k, double pan, double tilt);

/// When a simulated camera's frames reach a controller (docs/protocol_camera.md,
/// vlab's webcam model): frame i is exposed at i / fps + exposure / 2, rendered
/// at the first control period end at or after that and sent latency later.
struct FrameSchedule {
  double fps = 30;                  ///< Hz
  double exposure_s = 0;            ///< s
  double latency_s = 0;             ///< s
  double control_period_s = 0.002;  ///< the lab's control period, s
};

/// The newest frame id that the lab has certainly sent before its state of
/// time t_s (-1: none yet): the largest i with
/// i / fps + exposure / 2 + latency + control period <= t_s (less 1 us).
/// A controller that uses the newest frame with an id up to this one, and
/// waits for it when it has not arrived, sees the same frames in every
/// lockstep run.
std::int64_t NewestSentFrame(double t_s, const FrameSchedule& schedule);

/// An alpha-beta filter of an angle and its rate from measurements at
/// irregular times: rad, rad/s, s. The first measurement, and one after a gap
/// longer than gap_s, restarts it with rate 0. It follows an angle that
/// changes at a constant rate with no lag once settled.
class AngleFilter {
 public:
  AngleFilter(double alpha, double beta, double gap_s) : alpha_(alpha), beta_(beta), gap_s_(gap_s) {}
  /// Takes the angle measured at time t_s (t_s increasing).
  void Update(double t_s, double angle);
  bool valid() const { return valid_; }
  /// The angle predicted at t_s; the last estimate without its rate once
  /// the last measurement is older than gap_s.
  double Angle(double t_s) const;
  /// The rate at t_s: 0 once the last measurement is older than gap_s.
  double Rate(double t_s) const;

 private:
  double alpha_, beta_, gap_s_;
  bool valid_ = false;
  double t_ = 0, angle_ = 0, rate_ = 0;
};

}  // namespace head_track
