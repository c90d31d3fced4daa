// The cube scene: the PA10 scene (arm, table, floor, lights) with lettered
// cubes resting on the table at seeded random poses and a webcam above the
// table looking down at it.
//
// World frame = PA10 base frame (scenes/pa10.xml): table top z = 0.40 m,
// x 0.45..1.05 m, y -0.50..0.50 m. Each cube rests on one of its faces (drawn
// at random) with a random yaw, its centre inside the placement rectangle,
// outside the keep-out circle (where the arm's tool hangs in its ready pose),
// and no two cubes closer than their circumscribed circles plus a gap.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vision/vision_cubes.h"

namespace vlab::vision {

struct CubeSceneConfig {
  int count = 6;           ///< cubes placed: the first `count` letters of the set
  std::uint64_t seed = 1;  ///< xoshiro256++ seed of the poses
  // placement on the table (world frame), m
  double x_min = 0.52, x_max = 0.98;
  double y_min = -0.32, y_max = 0.32;
  Eigen::Vector2d keep_out_xy = Eigen::Vector2d(0.725, 0.0);  ///< the ready pose's tool tip (scenes/pa10.xml)
  double keep_out_radius = 0.10;
  double min_gap_m = 0.02;  ///< between circumscribed circles
  double table_top_z = 0.40;
  /// The cubes start this far above the table and settle in half a second
  /// (0.2 mm into the soft contact): faces exactly touching give MuJoCo
  /// 2.2.2's box-box test spurious deep contacts.
  double drop_m = 0.0001;
  // the webcam: a fixed MJCF camera named "webcam"
  Eigen::Vector3d webcam_position = Eigen::Vector3d(1.15, 0.0, 0.95);  ///< m
  Eigen::Vector3d webcam_target = Eigen::Vector3d(0.74, 0.0, 0.40);    ///< point on the optical axis, m
  /// Vertical field of view, deg: 38 deg at 640x480 is 49 deg horizontal, the
  /// QuickCam Pro 4000's HFOV of 45-50 deg [EST] (DATASHEET section 7), and
  /// near ARToolKit's default camera_para.dat (fy 726 px: 36.6 deg).
  double webcam_fovy_deg = 38;
};

/// Where one cube lies.
struct CubePlacement {
  int cube = 0;                                                     ///< index in the set
  int face_down = 0;                                                ///< CubeFace resting on the table
  double yaw_deg = 0;                                               ///< about the world z axis, deg
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               ///< centre, world frame, m
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< cube frame in the world
};

/// Seeded placement of `count` cubes. Throws InputError when the count
/// exceeds the set or the cubes do not fit the table's free area.
std::vector<CubePlacement> PlaceCubes(const CubeSetConfig& cubes, const CubeSceneConfig& scene);

/// The scene's MJCF text. `cubes_dir` and `pa10_dir` are the folders of the
/// cube files and of mjcf/pa10, as the scene file must name them (relative
/// to the scene file's folder).
std::string CubeSceneXml(const CubeSetConfig& cubes, const CubeSceneConfig& scene,
                         const std::vector<CubePlacement>& placements, const std::string& cubes_dir,
                         const std::string& pa10_dir);

}  // namespace vlab::vision
