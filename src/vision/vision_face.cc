#include "vision/vision_face.h"

#include <cmath>
#include <string>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include "bridge/bridge_markers.h"
#include "core/core_errors.h"
#include "render/image_codec.h"

namespace vlab::vision {

namespace {

constexpr int kFont = cv::FONT_HERSHEY_DUPLEX;

// pixel layout of a face: the marker square and the letter band
struct FacePixels {
  int cell = 0;         // px per marker cell
  int marker = 0;       // marker side, px
  cv::Rect marker_box;  // the marker
  cv::Rect white_box;   // the white square under it
  cv::Rect letter_box;  // the band the letter is centred in
};

FacePixels Pixels(const FaceLayout& layout, int bits) {
  const int p = layout.image_px;
  if (p < 64 || p > 4096 || !(layout.marker_fraction > 0 && layout.marker_fraction < 1) ||
      !(layout.margin_fraction >= 0 && layout.margin_fraction < 0.25)) {
    throw vlab::InputError("face layout: image " + std::to_string(p) + " px (64..4096), marker fraction " +
                           std::to_string(layout.marker_fraction) + " (0..1), margin fraction " +
                           std::to_string(layout.margin_fraction) + " (0..0.25)");
  }
  FacePixels f;
  const int cells = bits + 2;
  f.cell = static_cast<int>(std::floor(layout.marker_fraction * p / cells));
  f.marker = f.cell * cells;
  const int border = f.cell;  // one cell of white around the marker, as printed tags have
  const int white = f.marker + 2 * border;
  const int margin = static_cast<int>(std::lround(layout.margin_fraction * p));
  const int white_top = p - margin - white;
  f.white_box = cv::Rect((p - white) / 2, white_top, white, white);
  f.marker_box = cv::Rect(f.white_box.x + border, white_top + border, f.marker, f.marker);
  // the letter: between the top margin and the white square, as wide as the face less margins
  const int band_top = margin, band_bottom = white_top - margin;
  f.letter_box = cv::Rect(margin, band_top, p - 2 * margin, band_bottom - band_top);
  if (f.cell < 2 || white_top < margin || f.letter_box.height < p / 10) {
    throw vlab::InputError("face layout: marker fraction " + std::to_string(layout.marker_fraction) +
                           " leaves no room for the letter on a " + std::to_string(p) + " px face");
  }
  return f;
}

// an anti-aliased glyph mask, its ink scaled to fill `box`'s height (or width)
// and centred in it
cv::Mat LetterMask(char letter, const cv::Rect& box, cv::Size size) {
  const std::string text(1, letter);
  // measure the glyph's ink at a reference scale
  const double reference = 4.0;
  const int reference_thickness = 8;
  cv::Mat probe(400, 400, CV_8UC1, cv::Scalar(0));
  cv::putText(probe, text, cv::Point(50, 300), kFont, reference, cv::Scalar(255), reference_thickness, cv::LINE_8);
  const cv::Rect ink = cv::boundingRect(probe);
  const double fill = 0.94;  // of the band, leaving air around the glyph
  const double scale = std::min(fill * box.height / ink.height, fill * box.width / ink.width);
  const int thickness = std::max(1, static_cast<int>(std::lround(reference_thickness * scale)));
  // draw at the final scale, then move the ink's bounding box to the band's centre
  // (on a canvas twice the face's size: no glyph is clipped)
  cv::Mat glyph(size * 2, CV_8UC1, cv::Scalar(0));
  const cv::Point origin(size.width / 2, size.height * 3 / 2);
  cv::putText(glyph, text, origin, kFont, reference * scale, cv::Scalar(255), thickness, cv::LINE_AA);
  const cv::Rect drawn = cv::boundingRect(glyph);
  const cv::Point shift(box.x + (box.width - drawn.width) / 2 - drawn.x,
                        box.y + (box.height - drawn.height) / 2 - drawn.y);
  cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
  const cv::Mat moved = (cv::Mat_<double>(2, 3) << 1, 0, shift.x, 0, 1, shift.y);
  cv::warpAffine(glyph, mask, moved, size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  return mask;
}

}  // namespace

FaceGeometry FaceGeometryOf(const FaceLayout& layout, int bits) {
  const FacePixels f = Pixels(layout, bits);
  const double p = layout.image_px;
  FaceGeometry g;
  g.marker_side = f.marker / p;
  g.offset_right = (f.marker_box.x + f.marker / 2.0) / p - 0.5;
  g.offset_up = 0.5 - (f.marker_box.y + f.marker / 2.0) / p;
  return g;
}

cv::Mat DrawFace(const FaceSpec& face, const FaceLayout& layout) {
  const bridge::MarkerDictionary* dictionary = bridge::FindMarkerDictionary(face.dictionary);
  if (dictionary == nullptr)
    throw vlab::InputError("face: unknown marker dictionary code " + std::to_string(face.dictionary));
  if (face.id < 0 || face.id >= dictionary->markers) {
    throw vlab::InputError("face: marker id " + std::to_string(face.id) + " outside dictionary " + dictionary->name +
                           " (0.." + std::to_string(dictionary->markers - 1) + ")");
  }
  const bool letter_ok = (face.letter >= 'A' && face.letter <= 'Z') || (face.letter >= '0' && face.letter <= '9');
  if (!letter_ok) throw vlab::InputError(std::string("face: letter '") + face.letter + "' is not A-Z or 0-9");
  const FacePixels f = Pixels(layout, dictionary->bits);
  const int p = layout.image_px;

  cv::Mat image(p, p, CV_8UC3, face.background);
  // the letter: ink blended by the anti-aliased mask
  const cv::Mat mask = LetterMask(face.letter, f.letter_box, image.size());
  for (int y = 0; y < p; ++y) {
    const std::uint8_t* a = mask.ptr<std::uint8_t>(y);
    cv::Vec3b* px = image.ptr<cv::Vec3b>(y);
    for (int x = 0; x < p; ++x) {
      if (a[x] == 0) continue;
      for (int c = 0; c < 3; ++c) {
        const int mixed = (face.ink[c] * a[x] + px[x][c] * (255 - a[x]) + 127) / 255;
        px[x][c] = static_cast<std::uint8_t>(mixed);
      }
    }
  }
  // the marker on its white square
  image(f.white_box).setTo(cv::Scalar(255, 255, 255));
  cv::Mat marker;
  cv::aruco::drawMarker(cv::aruco::getPredefinedDictionary(face.dictionary), face.id, f.marker, marker, 1);
  cv::Mat marker_bgr;
  cv::cvtColor(marker, marker_bgr, cv::COLOR_GRAY2BGR);
  marker_bgr.copyTo(image(f.marker_box));
  return image;
}

std::vector<std::uint8_t> EncodePng(const cv::Mat& image) {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw std::runtime_error("PNG encoding failed: an 8-bit grey or BGR image expected");
  }
  // OpenCV draws BGR; PNG holds RGB
  cv::Mat rgb = image;
  if (image.channels() == 3) cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);
  std::vector<std::uint8_t> bytes;
  render::EncodePng({rgb.cols, rgb.rows, rgb.channels(), 8, rgb.data, rgb.step}, 9, &bytes);  // zlib level 9
  return bytes;
}

}  // namespace vlab::vision
