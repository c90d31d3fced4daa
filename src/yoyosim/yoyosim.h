// The yo-yo simulator's core: a MuJoCo scene with a hand that moves on three
// servo-driven slide joints and the yo-yo of mjcf/yoyo/ hanging from it
// (default scene mjcf/yoyo/yoyo_moving_hand.xml). No sockets here: the wire is
// yoyosim_server.
//
// Ports
//   input   hand set-point [x, y, z] (m, world frame), within the workspace
//           (SetTarget): where the servo's reference goes by the end of the
//           next Step, moving to it linearly over that period (a robot
//           controller's interpolator: a staircase of set-points would shake
//           the stiff servo at the control rate); Hold keeps the hand where
//           it is
//   output  point state [status, x, y, z, vx, vy, vz] of the hand and yo-yo
//           state [status, x, y, z, vz, string_force, spin] (bridge_layouts.h
//           layouts; SamplePoint, SampleYoyo)
//   rate    driven by its owner: one Step per control period (period_s, a
//           whole number of the scene's timesteps)
// Scene contract (checked by Create): a body `hand` whose frame stays parallel
// to the world's, moved by three limited slide joints `hand_x`, `hand_y`,
// `hand_z` along its x, y, z axes (their ranges are the workspace around the
// start), each the transmission of exactly one actuator whose ctrl is the
// joint's position set-point; the yo-yo's site `yoyo_centre`, joints
// `yoyo_drop` and `yoyo_spin`, tendon `yoyo_string_plus` and sensors
// `yoyo_string_plus_force`, `yoyo_string_minus_force`.
// Step, SetTarget, Hold and the samplers never throw and never allocate.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "core/core_mujoco.h"

namespace vlab::yoyosim {

/// A vector in the world frame (m, m/s).
using Vec3 = std::array<double, 3>;

struct SimConfig {
  std::string scene = "mjcf/yoyo/yoyo_moving_hand.xml";  ///< MJCF path
  double period_s = 0.01;                                ///< control period, s: a whole number of the scene's timesteps
};

/// The yo-yo as the compiled scene has it (SI units), for describe replies and tests.
struct YoyoParams {
  double mass = 0;           ///< m, kg
  double spin_inertia = 0;   ///< J about the spin axis, kg m^2
  double axle_radius = 0;    ///< r, m (the string tendon's spin coefficient)
  double string_length = 0;  ///< L, m
  double gravity = 0;        ///< |g|, m/s^2
};

class YoyoSim {
 public:
  /// Loads the scene and checks its contract. Throws vlab::InputError naming
  /// the scene and the missing or unusable element, or the period.
  static std::unique_ptr<YoyoSim> Create(const SimConfig& config);

  /// True when every value is finite and inside the workspace box.
  bool WithinWorkspace(const double* target_W) const;
  /// Sets the hand's set-point (m, world) for the end of the next Step, which
  /// moves the servo reference to it linearly from the set-point in force;
  /// false (nothing changes) when it is not within the workspace. Ends a hold.
  bool SetTarget(const double* target_W);
  /// Holds the hand where it is now: the set-point becomes its position.
  void Hold();
  /// Simulates one control period. False when MuJoCo reported a divergence
  /// (bad qpos, qvel or qacc): the state is then unusable and Step does nothing.
  bool Step();

  /// Hand state [status, x, y, z, vx, vy, vz] (m, m/s, world): status has
  /// bridge::kStatusHolding before the first set-point and after Hold.
  void SamplePoint(double* out7) const;
  /// Yo-yo state [status (0), x, y, z of its centre (m, world), vz (m/s),
  /// string tension (N, during the period's last step, >= 0), spin rate
  /// (rad/s, about the hand's +y)].
  void SampleYoyo(double* out7) const;

  const Vec3& start() const { return start_W_; }                  ///< the hand's start, m, world
  const Vec3& workspace_min() const { return workspace_min_W_; }  ///< m, world
  const Vec3& workspace_max() const { return workspace_max_W_; }  ///< m, world
  const Vec3& target() const { return target_W_; }                ///< the set-point in force, m, world
  const YoyoParams& yoyo() const { return yoyo_; }
  double period_s() const { return period_s_; }
  long periods() const { return periods_; }                                  ///< Steps done
  double time() const { return static_cast<double>(periods_) * period_s_; }  ///< s
  bool diverged() const { return diverged_; }
  /// The MuJoCo warning that ended the run ("badqacc", ...), "" if none.
  const char* divergence() const;
  const std::string& scene() const { return scene_; }
  const mjModel* model() const { return model_.get(); }
  const mjData* data() const { return data_.get(); }

 private:
  YoyoSim() = default;
  void CheckScene();
  void Refresh();

  std::string scene_;
  vlab::ModelPtr model_;
  vlab::DataPtr data_;
  double period_s_ = 0;
  int steps_per_period_ = 0;
  long periods_ = 0;
  int hand_body_ = -1, centre_site_ = -1, spin_dof_ = -1;
  int plus_force_ = -1, minus_force_ = -1;  // sensordata addresses
  std::array<int, 3> hand_qpos_{}, hand_dof_{}, hand_actuator_{};
  Vec3 start_W_{}, workspace_min_W_{}, workspace_max_W_{}, target_W_{};
  Vec3 from_W_{};  // the servo reference at the start of the period
  YoyoParams yoyo_;
  bool holding_ = true;
  bool diverged_ = false;
  int divergence_warning_ = -1;
};

}  // namespace vlab::yoyosim
