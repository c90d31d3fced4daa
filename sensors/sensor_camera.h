// Webcam model: frame timing, pinhole intrinsics, lens distortion and pixel
// noise. Independent of rendering: it says when frames are exposed and
// delivered, and turns an ideal (pinhole) RGB image into what the webcam gives.
//
// Ports
//   input   the control period boundaries (t_prev, t] the lab has simulated;
//           an ideal RGB8 image (rows top-down) rendered at a frame's stamp
//   output  which frames are due to be rendered and which to be delivered;
//           the webcam image (distorted, noisy), same size as configured
//   rates   fps (frame i is exposed from i / fps for exposure_s; its stamp is
//           the exposure's middle, i / fps + exposure_s / 2), independent of
//           the control rate
//   latency latency_s from the stamp to delivery (USB transfer, driver, decoding)
//
// Model
//   - Intrinsics from MuJoCo's vertical field of view (MUJOCO-NOTES "Frames and
//     intrinsics"): fx = fy = (H/2) / tan(fovy/2), cx = W/2 - 0.5,
//     cy = H/2 - 0.5 (pixel centres at whole numbers).
//   - Lens: Brown-Conrady radial + tangential distortion, OpenCV's plumb_bob
//     model: for the normalized pinhole point (x, y), r^2 = x^2 + y^2,
//       x_d = x (1 + k1 r^2 + k2 r^4) + 2 p1 x y + p2 (r^2 + 2 x^2)
//       y_d = y (1 + k1 r^2 + k2 r^4) + p1 (r^2 + 2 y^2) + 2 p2 x y
//     and u = fx x_d + cx, v = fy y_d + cy: a scene point lands where
//     cv::projectPoints puts it. The output image is resampled (bilinear) from
//     the ideal one through a map computed once: each output pixel looks up
//     the ideal pixel whose forward projection it is (Newton's method on the
//     model above). Output pixels whose ideal source lies outside the ideal
//     image are black, unless a larger ideal image is rendered (CoveringIdeal).
//   - Pixel noise: independent Gaussian noise of `noise` grey levels on every
//     channel of every pixel, rounded and clamped to 0..255. Since pixels are
//     whole grey levels, round(v + sigma Z) = v + round(sigma Z): the noise is
//     drawn directly as the discrete variable round(sigma Z) (truncated at
//     6 sigma + 1, where its tail is below 1e-9) by Walker's alias method
//     (A. J. Walker, ACM TOMS 3(3), 1977; table built by M. D. Vose's method,
//     IEEE TSE 17(9), 1991): one xoshiro256++ word and one table look-up per
//     value, about 5x faster than a ziggurat deviate plus rounding.
//   - Not modelled: motion blur (the image is the scene at the stamp), rolling
//     shutter, vignetting, auto exposure, JPEG artefacts (those come from the
//     wire's JPEG encoding when the device uses it).
//
// Defaults: a USB webcam of the original lab, the Logitech QuickCam Pro 4000
// (DATASHEET section 7; sources and estimates in sensors/README.md).
//
// Threading: a model is immutable after Create and may be shared; a
// CameraNoiseState belongs to one thread. Apply never allocates or throws.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "sensors/sensor_random.h"

namespace vlab::sensors {

/// QuickCam Pro 4000 horizontal field of view, deg ([EST] 45-50, DATASHEET section 7): the middle.
inline constexpr double kQuickCamHfovDeg = 47.5;

/// Pinhole intrinsics of an image, pixels; pixel centres at whole numbers.
struct PinholeIntrinsics {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};
/// Intrinsics of a MuJoCo camera with vertical field of view fovy_rad at width x height.
PinholeIntrinsics IntrinsicsFromFovy(double fovy_rad, int width, int height);
/// Vertical field of view (rad) of a camera with horizontal field of view hfov_rad at width x height.
double FovyFromHfov(double hfov_rad, int width, int height);

struct CameraModelConfig {
  int width = 640;  ///< output image, pixels (1..8192)
  int height = 480;
  double fps = 30.0;  ///< frame rate, Hz (0 < fps <= 1000)
  /// Vertical field of view, rad; default from the QuickCam's horizontal one at 640x480 (~36.5 deg).
  double fovy_rad = FovyFromHfov(kQuickCamHfovDeg * 3.14159265358979323846 / 180.0, 640, 480);
  double exposure_s = 0.0;  ///< exposure time, s (0 <= exposure < 1 / fps); the stamp is its middle
  double latency_s = 0.03;  ///< stamp to delivery, s (0..1) [EST]
  std::array<double, 4> distortion{0, 0, 0, 0};  ///< k1, k2, p1, p2 (plumb_bob); all 0: no distortion
  double noise = 0.0;                            ///< pixel noise standard deviation, grey levels (0..64)
  /// The ideal image Apply receives: size and intrinsics. width 0: the same as the output's.
  PinholeIntrinsics ideal;
};

/// Frames [first, end): end - first frames.
struct FrameRange {
  std::int64_t first = 0;
  std::int64_t end = 0;
  std::int64_t size() const { return end - first; }
  bool empty() const { return end <= first; }
};

/// The noise generator of one camera (seed it from the scenario's seed).
struct CameraNoiseState {
  explicit CameraNoiseState(std::uint64_t seed = 1) : rng(seed) {}
  Xoshiro256pp rng;
};

class CameraModel {
 public:
  /// Validates the configuration and computes the distortion map. Throws
  /// std::invalid_argument naming the field and its allowed range.
  static std::unique_ptr<CameraModel> Create(const CameraModelConfig& config);
  ~CameraModel();

  const CameraModelConfig& config() const { return config_; }
  /// Intrinsics of the output image (fovy, width, height).
  const PinholeIntrinsics& intrinsics() const { return intrinsics_; }
  /// Intrinsics of the ideal image Apply takes.
  const PinholeIntrinsics& ideal() const { return ideal_; }
  bool distorts() const { return distorts_; }

  // ---- schedule (times in s of the lab's clock) ----------------------------------
  /// Start of frame i's exposure: i / fps.
  double ExposureStart(std::int64_t i) const;
  /// Frame i's stamp, the middle of its exposure: i / fps + exposure_s / 2.
  double Stamp(std::int64_t i) const;
  /// When frame i is delivered: Stamp(i) + latency_s.
  double Delivery(std::int64_t i) const;
  /// Frames whose stamp lies in (t_prev, t] (1 ns tolerance): to be rendered
  /// from the state at t, the period boundary that closes them. Start with
  /// t_prev < 0 so that frame 0 is due at t = 0.
  FrameRange DueForRender(double t_prev, double t) const;
  /// Frames whose delivery time lies in (t_prev, t]: to be sent at t.
  FrameRange DueForDelivery(double t_prev, double t) const;
  /// The most frames rendered but not yet delivered at any boundary: the
  /// number of image buffers a delay line needs.
  int FramesInFlight() const;

  // ---- image ----------------------------------------------------------------------
  /// The webcam image from an ideal one: `ideal_rgb` is ideal().width x
  /// height RGB8, `out_rgb` width x height RGB8 (distinct buffers). Applies the
  /// lens (when it distorts), then the noise (when noise > 0) with `state`.
  void Apply(const std::uint8_t* ideal_rgb, std::uint8_t* out_rgb, CameraNoiseState* state) const;
  /// Where a pinhole (ideal-image) pixel lands in the output: the forward model.
  Eigen::Vector2d DistortPixel(const Eigen::Vector2d& ideal_px) const;
  /// The ideal pixel whose forward projection is output pixel `out_px`
  /// (Newton's method; exact to ~1e-9 px). False where the model does not
  /// invert there (far outside the field of view of strong distortion).
  bool UndistortPixel(const Eigen::Vector2d& out_px, Eigen::Vector2d* ideal_px) const;
  /// Intrinsics of an ideal image with the output's focal lengths that covers
  /// the source of every output pixel (with a 1-pixel margin): render that
  /// (vertical fov 2 atan((H/2) / fy)) and pass it as `ideal` for no black
  /// borders under barrel distortion.
  PinholeIntrinsics CoveringIdeal() const;

 private:
  explicit CameraModel(const CameraModelConfig& config);
  void BuildMap();
  void BuildNoiseTable();

  CameraModelConfig config_;
  PinholeIntrinsics intrinsics_;
  PinholeIntrinsics ideal_;
  bool distorts_ = false;
  bool ideal_is_output_ = true;
  std::vector<float> map_x_, map_y_;  // per output pixel: the ideal pixel it samples
  double map_min_x_ = 0, map_max_x_ = 0, map_min_y_ = 0, map_max_y_ = 0;
  // alias table of round(noise * Z): value i - noise_offset_ with probability
  // threshold_[i] / 2^32, else alias_[i] - noise_offset_
  int noise_offset_ = 0;
  std::vector<std::uint64_t> noise_threshold_;
  std::vector<std::int32_t> noise_alias_;
};

}  // namespace vlab::sensors
