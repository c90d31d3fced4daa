// Face images of the lettered cubes (vision_face.h): the marker is where
// FaceGeometryOf says and reads back as its id, the letter is drawn above
// it, the bytes are deterministic, and bad input is refused by name.
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "bridge/bridge_markers.h"
#include "core/core_errors.h"
#include "vision/vision_detector.h"
#include "vision/vision_face.h"

namespace vlab::vision::face_test {
namespace {

FaceSpec Spec(char letter, int dictionary, int id) {
  FaceSpec f;
  f.letter = letter;
  f.dictionary = dictionary;
  f.id = id;
  f.background = cv::Scalar(150, 230, 255);
  f.ink = cv::Scalar(100, 36, 24);
  return f;
}

std::string ErrorOf(const FaceSpec& spec, const FaceLayout& layout) {
  try {
    DrawFace(spec, layout);
  } catch (const vlab::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Face, MarkerWhereTheGeometrySaysAndReadable) {
  const FaceLayout layout;
  for (const auto& [code, id] : {std::pair{0, 17}, std::pair{4, 3}, std::pair{20, 586}}) {
    const cv::Mat face = DrawFace(Spec('K', code, id), layout);
    ASSERT_EQ(face.type(), CV_8UC3);
    ASSERT_EQ(face.rows, layout.image_px);
    ASSERT_EQ(face.cols, layout.image_px);
    const FaceGeometry g = FaceGeometryOf(layout, bridge::FindMarkerDictionary(code)->bits);
    // whole pixels per cell
    const double cell_px = g.marker_side * layout.image_px / (bridge::FindMarkerDictionary(code)->bits + 2);
    EXPECT_EQ(cell_px, std::floor(cell_px));
    cv::Mat grey;
    cv::cvtColor(face, grey, cv::COLOR_BGR2GRAY);
    std::vector<MarkerDetection> found;
    MarkerDetector().Detect(grey, code, &found);
    ASSERT_EQ(found.size(), 1u) << code;
    EXPECT_EQ(found[0].id, id);
    // corners (pixel-centre convention) at the marker's outer edges, top-left first
    const double p = layout.image_px, s = g.marker_side * p;
    const double cx = (0.5 + g.offset_right) * p - 0.5, cy = (0.5 - g.offset_up) * p - 0.5;
    const double expected[4][2] = {
        {cx - s / 2, cy - s / 2}, {cx + s / 2, cy - s / 2}, {cx + s / 2, cy + s / 2}, {cx - s / 2, cy + s / 2}};
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(found[0].corners[static_cast<std::size_t>(k)].x(), expected[k][0], 0.3) << code << " corner " << k;
      EXPECT_NEAR(found[0].corners[static_cast<std::size_t>(k)].y(), expected[k][1], 0.3) << code << " corner " << k;
    }
  }
}

TEST(Face, LargeLetterAboveTheMarker) {
  const FaceLayout layout;
  const FaceSpec spec = Spec('W', 0, 5);
  const cv::Mat face = DrawFace(spec, layout);
  const FaceGeometry g = FaceGeometryOf(layout, 4);
  const double cell_px = g.marker_side * layout.image_px / 6;  // the white border is one cell wide
  const int white_top = static_cast<int>((0.5 - g.offset_up - g.marker_side / 2) * layout.image_px - cell_px);
  int ink = 0, top = layout.image_px, bottom = 0;
  for (int y = 0; y < face.rows; ++y) {
    for (int x = 0; x < face.cols; ++x) {
      const cv::Vec3b px = face.at<cv::Vec3b>(y, x);
      if (std::abs(px[0] - spec.ink[0]) + std::abs(px[1] - spec.ink[1]) + std::abs(px[2] - spec.ink[2]) < 30) {
        ++ink;
        top = std::min(top, y);
        bottom = std::max(bottom, y);
        EXPECT_LT(y, white_top);
      }
    }
  }
  EXPECT_GT(ink, layout.image_px * layout.image_px / 50);  // a bold glyph: > 2 % of the face
  EXPECT_GT(bottom - top, layout.image_px / 4);            // and large: over a quarter of the face's height
}

TEST(Face, DeterministicBytes) {
  const FaceLayout layout;
  const auto a = EncodePng(DrawFace(Spec('Q', 0, 9), layout));
  const auto b = EncodePng(DrawFace(Spec('Q', 0, 9), layout));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, EncodePng(DrawFace(Spec('Q', 0, 10), layout)));
  EXPECT_NE(a, EncodePng(DrawFace(Spec('O', 0, 9), layout)));
}

TEST(Face, BadInputNamed) {
  const FaceLayout layout;
  EXPECT_NE(ErrorOf(Spec('a', 0, 1), layout).find("letter 'a' is not A-Z or 0-9"), std::string::npos);
  EXPECT_NE(ErrorOf(Spec('A', 0, 50), layout).find("marker id 50 outside dictionary 4X4_50"), std::string::npos);
  EXPECT_NE(ErrorOf(Spec('A', 30, 1), layout).find("unknown marker dictionary code 30"), std::string::npos);
  FaceLayout crowded;
  crowded.marker_fraction = 0.9;
  EXPECT_NE(ErrorOf(Spec('A', 0, 1), crowded).find("leaves no room for the letter"), std::string::npos);
  FaceLayout tiny;
  tiny.image_px = 10;
  EXPECT_NE(ErrorOf(Spec('A', 0, 1), tiny).find("face layout"), std::string::npos);
}

}  // namespace
}  // namespace vlab::vision::face_test
