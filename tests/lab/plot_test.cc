// Tests the scenario plots (src/lab/outputs/lab_plot.cc): tick positions are 1, 2, 5 x
// 10^k multiples covering the range; a plot of a known CSV is a PNG of the
// documented size whose curve passes through the pixels the axes put its
// points at; a missing column or file is an error naming the plot and the
// column, and writes nothing; a log column a plot names is checked before a run;
// `vlab run` writes the plot and prints its path.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "core/core_errors.h"
#include "lab/outputs/lab_plot.h"
#include "render/image_codec.h"
#include "test_util.h"

namespace vlab::lab::plot_test {
namespace {

// a PNG file as OpenCV's imread gave it: 8-bit BGR
cv::Mat ReadBgr(const std::string& path) {
  render::Image rgb = render::ReadImageFile(path, render::DecodeMode::kColor);
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(rgb.height, rgb.width, CV_8UC3, rgb.bytes.data()), bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

TEST(PlotTest, NiceTicks) {
  EXPECT_EQ(NiceTicks(0, 10, 10), (std::vector<double>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(NiceTicks(0, 50, 10), (std::vector<double>{0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50}));
  const std::vector<double> t = NiceTicks(-0.13, 0.37, 5);  // step 0.1
  ASSERT_EQ(t.size(), 5u);
  EXPECT_NEAR(t.front(), -0.1, 1e-12);
  EXPECT_NEAR(t.back(), 0.3, 1e-12);
}

TEST(PlotTest, DrawsTheCurveWhereTheAxesPutIt) {
  testing::TempDir dir;
  // a straight line y = x from (0, 0) to (10, 10), and a constant
  std::string csv = "time,a,b\n";
  for (int i = 0; i <= 100; ++i) csv += std::to_string(i * 0.1) + "," + std::to_string(i * 0.1) + ",5\n";
  testing::WriteFile(dir / "data.csv", csv);
  PlotConfig p;
  p.file = "p.png";
  p.csv = "data.csv";
  p.y = {"a", "b"};
  p.title = "a test";
  WritePlot(dir.path(), p);
  const cv::Mat img = ReadBgr(dir / "p.png");
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 1000);
  EXPECT_EQ(img.rows, 520);
  // y spans [0, 10] padded by 5 %: [-0.5, 10.5]; the plot area is x 80..980, y 50..460
  auto px = [](double x) { return 80 + static_cast<int>(std::lround(x / 10 * 900)); };
  auto py = [](double y) { return 50 + 410 - static_cast<int>(std::lround((y + 0.5) / 11 * 410)); };
  const cv::Vec3b first = img.at<cv::Vec3b>(py(7.0), px(7.0));   // on the line a
  const cv::Vec3b second = img.at<cv::Vec3b>(py(5.0), px(2.0));  // on the constant b
  EXPECT_EQ(first, cv::Vec3b(200, 80, 20));
  EXPECT_EQ(second, cv::Vec3b(30, 30, 220));
  EXPECT_EQ(img.at<cv::Vec3b>(py(2.5), px(8.5)), cv::Vec3b(255, 255, 255));  // off both curves and the grid: background
}

TEST(PlotTest, MissingColumnsAndFilesAreNamed) {
  testing::TempDir dir;
  testing::WriteFile(dir / "data.csv", "time,a\n0,1\n1,2\n");
  PlotConfig p;
  p.file = "p.png";
  p.csv = "data.csv";
  p.y = {"nope"};
  try {
    WritePlot(dir.path(), p);
    FAIL() << "a missing column must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "plot 'p.png': no column 'nope' in 'data.csv'");
  }
  p.csv = "absent.csv";
  EXPECT_THROW(WritePlot(dir.path(), p), std::runtime_error);
  EXPECT_EQ(testing::Entries(dir.path()), (std::set<std::string>{"data.csv"}));
  p.csv = "log.csv";
  p.where = "s.yaml:12";
  try {
    CheckPlotColumns(p, {"time", "a"});
    FAIL() << "an unknown log column must be refused before the run";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:12: outputs.plots: no log column 'nope'"), std::string::npos);
  }
}

// scenes/pa10_joint_pd.yaml with one plot (a line of outputs.plots), as DIR/s.yaml;
// runs it into DIR/out
testing::ProcessResult RunJointPdWithPlot(const testing::TempDir& dir, const std::string& plot) {
  std::string yaml = testing::ReadFile(VLAB_SOURCE_DIR "/scenes/pa10_joint_pd.yaml");
  const std::size_t scene = yaml.find("scene: ");
  if (scene == std::string::npos) throw std::runtime_error("pa10_joint_pd.yaml has no 'scene: '");
  yaml.replace(scene, 7, "scene: " VLAB_SOURCE_DIR "/scenes/");
  yaml += "\noutputs:\n  plots:\n    - " + plot + "\n";
  testing::WriteFile(dir / "s.yaml", yaml);
  return testing::RunVlab("run " + (dir / "s.yaml") + " -q --out " + (dir / "out"));
}

// end to end: a plot of a log column the scenario does not have is bad input
// (exit 2, one line naming the file and line), found before anything is written
TEST(PlotTest, UnknownLogColumnIsBadInputBeforeTheRun) {
  testing::TempDir dir;
  const testing::ProcessResult r = RunJointPdWithPlot(dir, "{file: p.png, y: [no.such.column]}");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("outputs.plots: no log column 'no.such.column'"), std::string::npos) << r.err;
  EXPECT_EQ(testing::Entries(dir.path()), (std::set<std::string>{"s.yaml"}));
}

// end to end: a run writes its plots into the output folder and names each one
TEST(PlotTest, RunWritesThePlotAndNamesIt) {
  testing::TempDir dir;
  const testing::ProcessResult r = RunJointPdWithPlot(dir, "{file: q.png, y: [pa10.q.S1, pa10.q.E1]}");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("plot: " + (dir / "out/q.png") + "\n"), std::string::npos) << r.out;
  const render::Image png = render::ReadImageFile(dir / "out/q.png", render::DecodeMode::kUnchanged);
  EXPECT_FALSE(png.bytes.empty());
}

}  // namespace
}  // namespace vlab::lab::plot_test
