// Seeded layouts at reset (the scenario's `randomize:` key): free bodies
// (the lettered cubes) put at random on a flat surface, each on a random face
// with a random yaw, drawn from the run's seed, so that one scene serves every
// seed and `vlab run --seed N` gives a new table (docs/scenarios.md,
// "Randomised layouts").
//
// The draw is the one `vlab cubes --scene` bakes into a scene file
// (src/vision/vision_scene.cc): xoshiro256++ seeded with the seed, per body in
// the order given: a centre uniform in the region (rejection: up to 2000 tries),
// then the face down (0-5: +X -X +Y -Y +Z -Z of the body frame, uniform), then
// the yaw (uniform in [0, 360) deg). It is drawn once, when the lab is created;
// every reset (the run's start, a sim-device reset) puts the same layout back.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

namespace vlab::lab {

class MapReader;

/// An axis-aligned rectangle of the surface, world frame, m.
struct RandomizeRect {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
};

/// The `randomize:` key of a scenario (empty `bodies`: no randomisation).
struct RandomizeConfig {
  std::vector<std::string> bodies;  ///< bodies with a free joint, placed in this order
  RandomizeRect region;             ///< where the bodies' footprints lie (whole footprint inside)
  bool has_within = false;          ///< centres also inside this circle (e.g. the arm's reach)
  Eigen::Vector2d within_center = Eigen::Vector2d::Zero();  ///< m, world x, y
  double within_radius = 0;                                 ///< m
  std::vector<RandomizeRect> exclude;                       ///< no footprint (plus clearance) overlaps these
  double clearance_m = 0.04;                                ///< between footprints, and to an excluded rectangle
  double surface_z = 0;                                     ///< world z of the surface the bodies rest on, m
  double drop_m = 0.0001;                                   ///< start this far above it (they settle), m
  int resting_face = -1;                                    ///< -1: any (uniform); 0-5: always this face down
  double yaw_min_deg = 0, yaw_max_deg = 360;                ///< yaw uniform in [min, max), deg
  std::string where;                                        ///< "FILE:LINE" of the key, for messages
};

/// Reads the `randomize:` mapping; InputError naming file:line and key.
RandomizeConfig ReadRandomize(MapReader& r);

/// Where one body goes.
struct RandomPlacement {
  int body = -1;       ///< MuJoCo body id
  int face_down = 0;   ///< 0-5: +X -X +Y -Y +Z -Z of the body frame resting on the surface
  double yaw_deg = 0;  ///< about the world z axis, deg
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               ///< body origin, world, m
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< body frame in the world
};

/// The rotation that puts face `face` (0-5: +X -X +Y -Y +Z -Z) of a body down
/// (its outward normal to world -z), yaw 0: the convention of `vlab cubes`.
Eigen::Quaterniond RestingOn(int face);

class Randomizer {
 public:
  /// Binds the bodies and draws the layout from `seed`. Throws InputError
  /// naming `config.where` for a body that does not exist, has no free joint
  /// (or more joints), is named twice, or when the bodies do not fit.
  static std::unique_ptr<Randomizer> Create(const mjModel* m, const RandomizeConfig& config, std::uint64_t seed);
  /// Writes the layout into qpos (and zero velocity) of the bodies' free joints.
  void Apply(const mjModel* m, mjData* d) const;
  const std::vector<RandomPlacement>& placements() const { return placements_; }

 private:
  Randomizer() = default;
  std::vector<RandomPlacement> placements_;
  std::vector<int> qpos_adr_, dof_adr_;
};

}  // namespace vlab::lab
