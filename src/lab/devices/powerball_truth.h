// Ground truth of a PowerBall (mjcf/powerball/) in a MuJoCo scene: spin, precession relative
// to the shell, slip of the axle tips on the groove walls and the walls' couple on the rotor.
// Read by the counter device's truth columns (lab-only: no real ball reports them) and by
// the ball's physics tests. Reads mjData, never steps it.
//
// Frames and signs (mjcf/powerball/powerball.xml): e3 = the shell's +z (groove normal);
// a = the rotor's +y (the axle, pointing at tip pb_tip_plus); b = e3 x a.
//   omega  spin of the rotor about a, relative to the shell (rad/s);
//   nu     rate of the axle round the groove relative to the shell = pb_precess's rate (rad/s);
//   slip   |omega r - nu R| / max(|omega| r, 1e-9): 0 while the tips roll, 1 at nu = 0.
//          Rolling on the wall the +a tip presses (the upper one when omega nu > 0) is
//          omega = (R/r) nu, on the other (R/r)(-nu): slip uses |nu| against |omega|;
//   couple the moment of all tip-wall contact forces about the rotor's centre (world frame,
//          N m); with the tips rolling it is I_s omega nu along b (the gyroscopic couple).
// R (groove rolling radius) and r (tip radius) and I_s are read from the compiled model.
#pragma once

#include <array>
#include <string>

#include <mujoco/mujoco.h>

namespace vlab::lab {

/// The elements of one PowerBall in a compiled model. Throws InputError naming `where`
/// (a scene or device) and the first element it cannot find.
struct PowerballBinding {
  int shell_body = -1, ring_body = -1, rotor_body = -1;
  int precess_dof = -1, tilt_dof = -1, spin_dof = -1;
  int tip_plus = -1, tip_minus = -1;  ///< geom ids of the axle tips
  double groove_radius_m = 0.0;       ///< R: tip centre to ball centre
  double tip_radius_m = 0.0;          ///< r: tip sphere radius
  double spin_inertia = 0.0;          ///< I_s, kg m^2 (rotor inertia about the axle)

  static PowerballBinding Bind(const mjModel& model, const std::string& where);
};

/// One reading of the truth (see the file comment for definitions).
struct PowerballTruth {
  double omega = 0.0;              ///< rad/s, spin about a relative to the shell
  double nu = 0.0;                 ///< rad/s, precession relative to the shell
  double slip = 0.0;               ///< 1, tip slip ratio
  std::array<double, 3> couple{};  ///< N m, wall couple on the rotor (world)
  std::array<double, 3> axle{};    ///< a in the world
  std::array<double, 3> normal{};  ///< e3 in the world
  int contacts = 0;                ///< tip-wall contacts in the data

  double Rpm() const { return omega * 60.0 / (2.0 * 3.14159265358979323846); }
  double CoupleNorm() const;
};

/// Reads the truth from `data` after mj_forward or mj_step (contacts and forces of the same
/// state). Needs mjData's efc_force: with MuJoCo 2.2.2's Newton solver the forces of the stiff
/// tip contacts are inconsistent with qacc (mjcf/powerball/README.md "Solver"): use PGS.
PowerballTruth MeasurePowerball(const mjModel& model, const mjData& data, const PowerballBinding& ball);

}  // namespace vlab::lab
