// The faces of a lettered cube, as the cube generator draws them: the order
// of the faces (MuJoCo's cube-texture order), each face's outward normal and
// its image axes on the cube, and the letter each face carries. One
// definition for the generator (vision_cubes.cc), the vision program and the
// lab's scoring device (src/lab/devices/device_word.cc), header-only and
// without OpenCV so that the lab can use it.
//
// A face image is drawn upright in its own axes (vision_face.h): the letter
// reads left to right along the image's right axis, its top towards the
// image's up axis; the marker's x and y are the same axes. So a letter's
// reading direction ("up" of the letter) on face f is CubeFaceUp(f) in the
// cube's body frame.
//
// A cube of a set with one letter per cube (the default, `vlab cubes
// --letters`) carries that letter on all six faces. An alphabet block (`vlab
// cubes --faces`) carries six letters, one per face in this face order; its
// MJCF assets name them in a custom text element `<body>.faces` (data: the
// six letters), which the scoring device reads from the model.
#pragma once

#include <string>

#include <Eigen/Core>

namespace vlab::vision {

/// Faces in MuJoCo's cube-texture order (fileright, fileleft, fileup,
/// filedown, filefront, fileback): the face's outward normal in the cube frame.
enum CubeFace : int { kFacePlusX = 0, kFaceMinusX, kFacePlusY, kFaceMinusY, kFacePlusZ, kFaceMinusZ };
inline constexpr int kCubeFaces = 6;

namespace cube_faces_detail {
// the face's image axes on the cube, seen from outside: right and up (box
// frame; measured with MuJoCo 2.2.2's cube textures on a box geom, and checked
// against rendered markers by tests/vision/accuracy_test.cc)
inline constexpr int kRight[kCubeFaces][3] = {{0, 0, -1}, {0, 0, 1}, {1, 0, 0}, {1, 0, 0}, {1, 0, 0}, {-1, 0, 0}};
inline constexpr int kUp[kCubeFaces][3] = {{0, 1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}, {0, 1, 0}, {0, 1, 0}};
}  // namespace cube_faces_detail

/// Face f's image right axis (the letter's reading direction, left to right), cube frame.
inline Eigen::Vector3d CubeFaceRight(int face) {
  const int* r = cube_faces_detail::kRight[face];
  return Eigen::Vector3d(r[0], r[1], r[2]);
}
/// Face f's image up axis (the letter's up), cube frame.
inline Eigen::Vector3d CubeFaceUp(int face) {
  const int* u = cube_faces_detail::kUp[face];
  return Eigen::Vector3d(u[0], u[1], u[2]);
}
/// Face f's outward normal (right x up), cube frame.
inline Eigen::Vector3d CubeFaceNormal(int face) { return CubeFaceRight(face).cross(CubeFaceUp(face)); }

/// Name of the MJCF custom text that lists an alphabet block's face letters
/// (faces 0-5, in CubeFace order): "<body>.faces".
inline std::string CubeFacesTextName(const std::string& body) { return body + ".faces"; }

}  // namespace vlab::vision
