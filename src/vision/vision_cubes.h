// The lettered cubes: a set of wooden-block cubes, one letter each, with an
// ArUco marker and the cube's letter on every face, and their MJCF; or a set
// of alphabet blocks, six letters each, a different one on every face.
//
// Cube i of a set (letters[i]) has six faces in MuJoCo's cube-texture order
// (CubeFace); the marker of face f has id first_id + 6 i + f. Files written
// into one folder (CubeSetFiles):
//   cube_<L>_<face>.png   the face images (vision_face.h)
//   cubes_assets.xml      <mujocoinclude>: a cube texture and a material per cube
//   cube_<L>.xml          <mujocoinclude>: the contents of a cube's body (free
//                         joint, inertial, box geom), to include in a <body>
//                         whose pos/quat place the cube
//   README.md             dictionary, ids, sizes, frames, how to include
// The textures name their files without a folder: the including model sets
// <compiler texturedir> to this folder.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vision/vision_cube_faces.h"
#include "vision/vision_face.h"

namespace vlab::vision {

/// "right", "left", "up", "down", "front", "back" (the texture attribute's suffix).
const char* CubeFaceName(int face);

struct CubeSetConfig {
  std::string letters = "ABCDEF";  ///< one cube per letter (A-Z, 0-9), no repeats; unused with `faces`
  /// Alphabet blocks: one entry per cube, its six face letters (A-Z, 0-9) in
  /// CubeFace order; no two entries alike. Empty: one cube per letter of
  /// `letters`, the letter on every face.
  std::vector<std::string> faces;
  double size_m = 0.05;  ///< cube edge, m
  int dictionary = 0;    ///< MarkerDictionary::code (0: 4X4_50)
  int first_id = 0;      ///< marker id of the first cube's first face
  /// Beech wood, dried: 650-750 kg/m3 [EST: typical handbook range; no
  /// datasheet for the lab's blocks]; mass = density * size^3.
  double density_kg_m3 = 700;
  FaceLayout layout;
};
/// Throws InputError naming the option (letters, size, dictionary, ids).
void CheckCubeSet(const CubeSetConfig& config);

/// Number of cubes of the set.
int CubeCount(const CubeSetConfig& config);
/// The letter on face f of cube i.
char CubeFaceLetter(const CubeSetConfig& config, int cube, int face);
/// Body (and geom, material, texture) name of cube i: "cube_<L>", or for an
/// alphabet block "cube_<its six letters>" (cube_AGMSY4).
std::string CubeName(const CubeSetConfig& config, int cube);
/// The set as `vlab cubes` options name it: "--letters ABCDEF" or "--faces AGMSY4,...".
std::string CubeSetOption(const CubeSetConfig& config);
/// Marker id of face f of cube i.
int CubeMarkerId(const CubeSetConfig& config, int cube, int face);
/// Marker side on the cube, m.
double CubeMarkerSide(const CubeSetConfig& config);
/// The marker frame of face f in the cube's body frame (origin at the cube's
/// centre, axes of the box): x to the right of the printed marker, y up, z
/// the face's outward normal; origin at the marker's centre on the face.
Eigen::Isometry3d CubeMarkerFrame(const CubeSetConfig& config, int face);

/// One generated file: name within the cube folder, and its bytes.
struct GeneratedFile {
  std::string name;
  std::string bytes;
};
/// Every file of the set, deterministic bytes. Throws as CheckCubeSet.
std::vector<GeneratedFile> CubeSetFiles(const CubeSetConfig& config);

/// Writes files into `dir` (created if missing): each to a temporary name
/// in the same folder, then renamed, so no half-written file is left.
/// Throws InputError naming the file when it cannot.
void WriteGeneratedFiles(const std::string& dir, const std::vector<GeneratedFile>& files);

/// A number as MJCF text: shortest round-trip form up to 6 significant digits.
std::string MjcfNumber(double value);

}  // namespace vlab::vision
