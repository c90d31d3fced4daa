// Faces of the lettered cubes: one square image per face with an ArUco marker
// on a white border and a large letter, drawn with OpenCV (no fonts from the
// system: Hershey vector glyphs), so the same inputs give the same pixels and
// the same PNG bytes on every run.
//
// Layout of a face image (P x P pixels, rows top-down), in the face's own
// image axes (right, up):
//   - background: the cube's colour;
//   - the letter, centred in the band above the marker, in `ink`;
//   - the marker, centred left-right in the lower part, on a white square
//     one cell wider than the marker on every side (the quiet zone printed
//     tags have: with less, blur at a distance, in a lens or in mipmapped
//     textures, pulls the outer edges inwards).
// The marker is (bits + 2) cells wide with a whole number of pixels per cell,
// so its edges fall on pixel edges and FaceGeometry gives its exact size.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace vlab::vision {

/// Proportions of a face image.
struct FaceLayout {
  int image_px = 480;             ///< side of the face image, px
  double marker_fraction = 0.5;   ///< marker side / face side (rounded down to whole px per cell)
  double margin_fraction = 0.01;  ///< background left below the white square / face side
};

/// Where the marker lies on a face, as fractions of the face side.
struct FaceGeometry {
  double marker_side = 0;   ///< marker side / face side
  double offset_right = 0;  ///< marker centre minus face centre along the image's right axis / face side
  double offset_up = 0;     ///< the same along the image's up axis
};

/// One face to draw.
struct FaceSpec {
  char letter = 'A';                                  ///< A-Z or 0-9
  int dictionary = 0;                                 ///< MarkerDictionary::code
  int id = 0;                                         ///< marker id in that dictionary
  cv::Scalar background = cv::Scalar(255, 255, 255);  ///< BGR
  cv::Scalar ink = cv::Scalar(0, 0, 0);               ///< BGR, the letter's colour
};

/// Geometry of the marker on a face of `layout` for a dictionary with
/// `bits` data bits per side. Throws InputError when the layout leaves no
/// room for the marker or the letter.
FaceGeometry FaceGeometryOf(const FaceLayout& layout, int bits);

/// Draws a face: 8-bit BGR, layout.image_px square. Throws InputError for an
/// unknown dictionary, an id outside it or a letter outside A-Z, 0-9.
cv::Mat DrawFace(const FaceSpec& face, const FaceLayout& layout);

/// PNG bytes of an image (fixed compression settings: deterministic).
std::vector<std::uint8_t> EncodePng(const cv::Mat& image);

}  // namespace vlab::vision
