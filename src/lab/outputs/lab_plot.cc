// Line plots of CSV files (see lab_plot.h).
#include "lab/outputs/lab_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "render/image_io.h"

namespace vlab::lab {

namespace {

constexpr int kWidth = 1000, kHeight = 520;
constexpr int kLeft = 80, kRight = 20, kTop = 50, kBottom = 60;

struct Series {
  std::vector<double> x;
  std::vector<std::vector<double>> y;
};

std::vector<std::string> SplitLine(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) out.push_back(cell);
  return out;
}

// the x and y columns of the CSV, rows with a non-number in them left out
Series ReadColumns(const std::string& path, const PlotConfig& plot) {
  const std::string what = "plot '" + plot.file + "': ";
  // a regular file of at most kMaxCsvBytes (an external controller may have written it)
  std::istringstream in(ReadInputFile(path, what + "'" + path + "'", kMaxCsvBytes));
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(what + "cannot read '" + path + "': it is empty");
  const std::vector<std::string> header = SplitLine(line);
  auto index = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error(what + "no column '" + name + "' in '" + plot.csv + "'");
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t ix = index(plot.x);
  std::vector<std::size_t> iy;
  for (const std::string& y : plot.y) iy.push_back(index(y));
  Series s;
  s.y.resize(iy.size());
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = SplitLine(line);
    if (cells.size() != header.size()) continue;
    char* end = nullptr;
    const double x = std::strtod(cells[ix].c_str(), &end);
    if (end == cells[ix].c_str() || !std::isfinite(x)) continue;
    s.x.push_back(x);
    for (std::size_t k = 0; k < iy.size(); ++k) s.y[k].push_back(std::strtod(cells[iy[k]].c_str(), nullptr));
  }
  if (s.x.size() < 2) throw std::runtime_error(what + "fewer than two rows of numbers in '" + plot.csv + "'");
  return s;
}

std::string Label(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return text;
}

const cv::Scalar kColours[] = {{200, 80, 20}, {30, 30, 220}, {40, 150, 40}, {160, 40, 160}, {20, 150, 200}};

}  // namespace

std::vector<double> NiceTicks(double lo, double hi, int count) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / std::max(1, count);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double f : {1.0, 2.0, 5.0, 10.0}) {
    step = f * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step) ticks.push_back(t);
  return ticks;
}

void CheckPlotColumns(const PlotConfig& plot, const std::vector<std::string>& columns) {
  if (plot.csv != "log.csv") return;  // another program's file: checked when it is drawn
  std::vector<std::string> wanted = plot.y;
  wanted.push_back(plot.x);
  for (const std::string& c : wanted) {
    if (c != "time" && std::find(columns.begin(), columns.end(), c) == columns.end()) {
      throw InputError(plot.where + ": outputs.plots: no log column '" + c + "' (vlab run --list-signals lists them)");
    }
  }
}

void WritePlot(const std::string& dir, const PlotConfig& plot) {
  const Series s = ReadColumns(dir + "/" + plot.csv, plot);
  double x_lo = *std::min_element(s.x.begin(), s.x.end()), x_hi = *std::max_element(s.x.begin(), s.x.end());
  double y_lo = INFINITY, y_hi = -INFINITY;
  for (const auto& col : s.y) {
    for (double v : col) {
      if (!std::isfinite(v)) continue;
      y_lo = std::min(y_lo, v);
      y_hi = std::max(y_hi, v);
    }
  }
  if (!std::isfinite(y_lo)) throw std::runtime_error("plot '" + plot.file + "': no finite value to draw");
  if (y_hi - y_lo < 1e-12) y_lo -= 0.5, y_hi += 0.5;
  const double pad = 0.05 * (y_hi - y_lo);
  y_lo -= pad;
  y_hi += pad;
  if (x_hi <= x_lo) x_hi = x_lo + 1;

  cv::Mat img(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const int w = kWidth - kLeft - kRight, h = kHeight - kTop - kBottom;
  auto px = [&](double x) { return kLeft + static_cast<int>(std::lround((x - x_lo) / (x_hi - x_lo) * w)); };
  auto py = [&](double y) { return kTop + h - static_cast<int>(std::lround((y - y_lo) / (y_hi - y_lo) * h)); };
  const cv::Scalar grid(225, 225, 225), ink(40, 40, 40);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double t : NiceTicks(x_lo, x_hi, 10)) {
    cv::line(img, {px(t), kTop}, {px(t), kTop + h}, grid, 1);
    cv::putText(img, Label(t), {px(t) - 12, kTop + h + 20}, font, 0.45, ink, 1, cv::LINE_AA);
  }
  for (double t : NiceTicks(y_lo, y_hi, 8)) {
    cv::line(img, {kLeft, py(t)}, {kLeft + w, py(t)}, grid, 1);
    cv::putText(img, Label(t), {8, py(t) + 5}, font, 0.45, ink, 1, cv::LINE_AA);
  }
  cv::rectangle(img, {kLeft, kTop}, {kLeft + w, kTop + h}, ink, 1);
  for (std::size_t k = 0; k < s.y.size(); ++k) {
    const cv::Scalar colour = kColours[k % (sizeof(kColours) / sizeof(kColours[0]))];
    std::vector<cv::Point> line;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (std::isfinite(s.y[k][i])) line.emplace_back(px(s.x[i]), py(s.y[k][i]));
    }
    cv::polylines(img, line, false, colour, 2, cv::LINE_AA);
    const int ly = kTop + 18 + 20 * static_cast<int>(k);
    cv::line(img, {kLeft + 10, ly - 5}, {kLeft + 40, ly - 5}, colour, 2, cv::LINE_AA);
    cv::putText(img, plot.y[k], {kLeft + 48, ly}, font, 0.5, ink, 1, cv::LINE_AA);
  }
  cv::putText(img, plot.title, {kLeft, 30}, font, 0.65, ink, 1, cv::LINE_AA);
  cv::putText(img, plot.x, {kLeft + w / 2 - 20, kHeight - 15}, font, 0.5, ink, 1, cv::LINE_AA);
  if (!plot.ylabel.empty()) cv::putText(img, plot.ylabel, {kLeft + w - 200, 30}, font, 0.5, ink, 1, cv::LINE_AA);
  const std::string out = dir + "/" + plot.file;
  // PNG of the RGB pixels (OpenCV drew BGR), written whole
  cv::Mat rgb;
  cv::cvtColor(img, rgb, cv::COLOR_BGR2RGB);
  std::vector<std::uint8_t> png;
  try {
    render::EncodePng({rgb.cols, rgb.rows, 3, 8, rgb.data, rgb.step}, -1, &png);
    render::WriteFileAtomic(out, png);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("plot '" + plot.file + "': cannot write '" + out + "': " + e.what());
  }
}

}  // namespace vlab::lab
