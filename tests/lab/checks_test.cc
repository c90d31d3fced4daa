// Checks: each reduction over a hand-made series equals its closed form; the
// window and the bounds decide pass/fail; empty windows, NaN samples and
// unknown signals fail loudly.
#include "lab/judge/lab_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/core_errors.h"
#include "test_util.h"

namespace vlab::lab::checks_test {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Columns of the hand-made log: time and one signal "x".
const std::vector<std::string> kColumns = {"time", "x"};
// x at t = 0, 1, ..., 7 s. Sum 9, sum of squares 176.5: every closed form is exact
// or one rounding away.
const std::vector<double> kSeries = {3, -1, 4, -1.5, 5, -9, 2.5, 6};

CheckConfig Check(const std::string& name, const std::string& reduce, double from_s = 0.0, double to_s = kInf) {
  CheckConfig c;
  c.name = name;
  c.signal = "x";
  EXPECT_TRUE(ReduceFromName(reduce, &c.reduce)) << reduce;
  c.from_s = from_s;
  c.to_s = to_s;
  c.where = "case.yaml:12";
  return c;
}

CheckConfig Windowed(const std::string& name, const std::string& reduce, double window_s, double from_s = 0.0,
                     double to_s = kInf) {
  CheckConfig c = Check(name, reduce, from_s, to_s);
  c.window_s = window_s;
  return c;
}

// Feeds `series` at t = 0, 1, 2, ... s and returns the results.
std::vector<CheckResult> Evaluate(const std::vector<CheckConfig>& checks, const std::vector<double>& series) {
  CheckSet set(checks, kColumns);
  for (std::size_t i = 0; i < series.size(); ++i) {
    const double row[2] = {static_cast<double>(i), series[i]};
    set.Add(row[0], row);
  }
  return set.Results();
}

TEST(CheckSetTest, ReductionsEqualClosedForms) {
  const auto r = Evaluate({Check("a", "max"), Check("b", "min"), Check("c", "mean"), Check("d", "rms"),
                           Check("e", "final"), Check("f", "max_abs")},
                          kSeries);
  ASSERT_EQ(r.size(), 6u);
  EXPECT_EQ(r[0].value, 6.0);
  EXPECT_EQ(r[1].value, -9.0);
  EXPECT_EQ(r[2].value, 9.0 / 8.0);
  EXPECT_DOUBLE_EQ(r[3].value, std::sqrt(176.5 / 8.0));
  EXPECT_EQ(r[4].value, 6.0);
  EXPECT_EQ(r[5].value, 9.0);  // |-9|, larger than the maximum 6
  for (const auto& c : r) {
    EXPECT_EQ(c.samples, 8) << c.config.name;
    EXPECT_TRUE(c.pass) << c.config.name;  // no bounds: any finite value passes
    EXPECT_EQ(c.config.name.size(), 1u);   // the config travels with its result
  }
  EXPECT_EQ(r[3].config.reduce, Reduce::kRms);
}

TEST(CheckSetTest, WindowIsInclusiveAndRespected) {
  // [2, 5] holds t = 2, 3, 4, 5: x = 4, -1.5, 5, -9
  const auto r = Evaluate({Check("max", "max", 2, 5), Check("min", "min", 2, 5), Check("mean", "mean", 2, 5),
                           Check("final", "final", 2, 5), Check("tail", "mean", 5.5)},
                          kSeries);
  EXPECT_EQ(r[0].value, 5.0);
  EXPECT_EQ(r[1].value, -9.0);
  EXPECT_EQ(r[2].value, -1.5 / 4.0);
  EXPECT_EQ(r[3].value, -9.0);  // last sample inside the window, not of the run
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r[i].samples, 4);
  // from 5.5 to the end: t = 6, 7
  EXPECT_EQ(r[4].samples, 2);
  EXPECT_EQ(r[4].value, (2.5 + 6.0) / 2.0);
}

TEST(CheckSetTest, BoundsDecidePassInclusively) {
  std::vector<CheckConfig> checks;
  auto add = [&](const std::string& reduce, double min, double max) {
    CheckConfig c = Check(reduce + std::to_string(checks.size()), reduce);
    c.min = min;
    c.max = max;
    checks.push_back(c);
  };
  add("max", -kInf, 6.0);    // value 6 at the bound: pass
  add("max", -kInf, 5.999);  // fail
  add("min", -9.0, kInf);    // at the bound: pass
  add("min", -8.999, kInf);  // fail
  add("mean", 1.0, 1.25);    // 1.125 inside: pass
  add("mean", 1.13, 1.25);   // below min: fail
  add("mean", 1.0, 1.12);    // above max: fail
  add("max_abs", 0.0, 8.5);  // 9: fail
  const auto r = Evaluate(checks, kSeries);
  const std::vector<bool> expected = {true, false, true, false, true, false, false, false};
  ASSERT_EQ(r.size(), expected.size());
  for (std::size_t i = 0; i < r.size(); ++i) EXPECT_EQ(r[i].pass, expected[i]) << r[i].config.name;
}

TEST(CheckSetTest, EmptyWindowFailsWithNaN) {
  CheckConfig after = Check("after", "max", 100, 200);
  after.max = 1e9;
  CheckConfig between = Check("between", "min", 2.25, 2.75);  // between two samples
  between.min = -1e9;
  const auto r = Evaluate({after, between, Check("final", "final", 8)}, kSeries);
  for (const auto& c : r) {
    EXPECT_EQ(c.samples, 0) << c.config.name;
    EXPECT_TRUE(std::isnan(c.value)) << c.config.name;
    EXPECT_FALSE(c.pass) << c.config.name;
  }
  // no samples at all
  const auto none = Evaluate({Check("none", "mean")}, {});
  EXPECT_TRUE(std::isnan(none[0].value));
  EXPECT_FALSE(none[0].pass);
}

TEST(CheckSetTest, NaNSampleFailsMaxMinAndMaxAbs) {
  for (std::size_t at : {std::size_t{0}, std::size_t{3}, kSeries.size() - 2}) {
    std::vector<double> series = kSeries;
    series[at] = kNaN;
    std::vector<CheckConfig> checks = {Check("max", "max"), Check("min", "min"), Check("max_abs", "max_abs"),
                                       Check("mean", "mean"), Check("rms", "rms")};
    for (auto& c : checks) c.max = 1e9;  // generous bound: only the NaN can fail them
    const auto r = Evaluate(checks, series);
    for (const auto& c : r) {
      EXPECT_TRUE(std::isnan(c.value)) << c.config.name << ", NaN at sample " << at;
      EXPECT_FALSE(c.pass) << c.config.name << ", NaN at sample " << at;
    }
  }
  // a NaN outside the window does not matter
  std::vector<double> series = kSeries;
  series[0] = kNaN;
  const auto r = Evaluate({Check("late", "max", 1)}, series);
  EXPECT_EQ(r[0].value, 6.0);
  EXPECT_TRUE(r[0].pass);
}

TEST(CheckSetTest, RangeIsLargestMinusSmallestInTheWindow) {
  // whole run: 6 - (-9); [2, 4]: x = 4, -1.5, 5 -> 6.5; one sample: 0
  CheckConfig held = Check("held", "range", 5.5);
  held.max = 3.5;  // t = 6, 7: 6 - 2.5 = 3.5 at the bound: pass
  CheckConfig wanders = Check("wanders", "range", 5.5);
  wanders.max = 3.499;
  const auto r = Evaluate(
      {Check("all", "range"), Check("mid", "range", 2, 4), Check("one", "range", 3, 3), held, wanders}, kSeries);
  EXPECT_EQ(r[0].value, 15.0);
  EXPECT_EQ(r[1].value, 6.5);
  EXPECT_EQ(r[2].value, 0.0);
  EXPECT_EQ(r[2].samples, 1);
  EXPECT_TRUE(r[3].pass);
  EXPECT_FALSE(r[4].pass);
  // a NaN inside the window fails it
  std::vector<double> series = kSeries;
  series[3] = kNaN;
  CheckConfig generous = Check("nan", "range");
  generous.max = 1e9;
  const auto n = Evaluate({generous}, series);
  EXPECT_TRUE(std::isnan(n[0].value));
  EXPECT_FALSE(n[0].pass);
}

TEST(CheckSetTest, ExtremeValuesReduceToThemselves) {
  // max and min of a series are elements of it, whatever their magnitude
  const std::vector<double> low = {-1.5e308, -1.7e308};
  const auto r = Evaluate({Check("max", "max"), Check("final", "final")}, low);
  EXPECT_EQ(r[0].value, -1.5e308);
  EXPECT_EQ(r[1].value, -1.7e308);
  const std::vector<double> high = {1.5e308, 1.7e308};
  EXPECT_EQ(Evaluate({Check("min", "min")}, high)[0].value, 1.5e308);
  // an infinite signal never passes a bound, whichever side the bound is on
  CheckConfig min_check = Check("min", "min");
  min_check.min = 0.0;
  const auto inf = Evaluate({min_check}, {kInf, kInf});
  EXPECT_EQ(inf[0].value, kInf);
  EXPECT_FALSE(inf[0].pass);
  CheckConfig max_check = Check("max", "max");
  max_check.max = 0.0;
  const auto minus_inf = Evaluate({max_check}, {-kInf});
  EXPECT_EQ(minus_inf[0].value, -kInf);
  EXPECT_FALSE(minus_inf[0].pass);
}

TEST(CheckSetTest, WindowedReductionsTakeWholeSubWindowsOnly) {
  // x = 3, -1 | 4, -1.5 | 5, -9 | 2.5, 6 at t = 0..7, windows of 2 s from 0: the last,
  // [6, 8), ends after the last sample and is left out
  const auto r = Evaluate({Windowed("tops", "min_of_window_max", 2), Windowed("bottoms", "max_of_window_min", 2),
                           // [1, 3.5) holds -1, 4, -1.5; [3.5, 6) holds 5, -9; [6, 8.5) is not whole
                           Windowed("shifted", "min_of_window_max", 2.5, 1, 6),
                           // to = 5.5 ends the second window [3, 5) whole and cuts [5, 7)
                           Windowed("cut", "max_of_window_min", 2, 1, 5.5),
                           // [0, 7) ends at to and at the last sample: whole; t = 7 opens [7, 14)
                           Windowed("one", "min_of_window_max", 7, 0, 7)},
                          kSeries);
  EXPECT_EQ(r[0].value, 3.0);   // maxima 3, 4, 5
  EXPECT_EQ(r[1].value, -1.0);  // minima -1, -1.5, -9
  EXPECT_EQ(r[2].value, 4.0);   // maxima 4, 5
  EXPECT_EQ(r[3].value, -1.0);  // minima of {-1, 4}, {-1.5, 5}: -1, -1.5
  EXPECT_EQ(r[4].value, 5.0);   // max of 3, -1, 4, -1.5, 5, -9, 2.5
  EXPECT_EQ(r[0].samples, 8);   // every sample of the window is counted, whole sub-window or not
  for (const auto& c : r) EXPECT_TRUE(c.pass) << c.config.name;
  // a swing that stays low in one window fails a bound the others meet
  CheckConfig tops = Windowed("tops", "min_of_window_max", 2);
  tops.min = 3.5;
  EXPECT_FALSE(Evaluate({tops}, kSeries)[0].pass);
  tops.min = 3.0;
  EXPECT_TRUE(Evaluate({tops}, kSeries)[0].pass);
}

TEST(CheckSetTest, WindowedReductionsFailWithoutAWholeWindowOrWithNaN) {
  // 8 s of samples, 10 s windows: no whole window
  const auto none = Evaluate({Windowed("long", "min_of_window_max", 10)}, kSeries);
  EXPECT_TRUE(std::isnan(none[0].value));
  EXPECT_FALSE(none[0].pass);
  // 0.5 s windows over samples 1 s apart: every other one is empty, which fails
  const auto gaps = Evaluate({Windowed("short", "min_of_window_max", 0.5)}, kSeries);
  EXPECT_TRUE(std::isnan(gaps[0].value));
  EXPECT_FALSE(gaps[0].pass);
  std::vector<double> series = kSeries;
  series[2] = kNaN;  // in the second window
  const auto r =
      Evaluate({Windowed("tops", "min_of_window_max", 2), Windowed("bottoms", "max_of_window_min", 2)}, series);
  for (const auto& c : r) {
    EXPECT_TRUE(std::isnan(c.value)) << c.config.name;
    EXPECT_FALSE(c.pass) << c.config.name;
  }
}

// Loads a scenario whose one check is `check` and returns the error message ("" if none).
std::string CheckError(const std::string& check) {
  vlab::testing::TempDir dir;
  vlab::testing::WriteFile(dir / "s.yaml", "scene: x.xml\nduration: 1\nchecks:\n  - " + check + "\n");
  try {
    LoadScenario(dir / "s.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CheckSetTest, WindowedReductionsNeedAPositiveWindow) {
  EXPECT_EQ(CheckError("{name: c, signal: x, reduce: min_of_window_max, window: 2.5, min: 1}"), "");
  const std::string missing = CheckError("{name: c, signal: x, reduce: min_of_window_max, min: 1}");
  EXPECT_NE(missing.find("s.yaml:4"), std::string::npos) << missing;
  EXPECT_NE(missing.find("window"), std::string::npos) << missing;
  EXPECT_NE(missing.find("needs a window"), std::string::npos) << missing;
  for (const char* bad : {"0", "-1e-9", "-1"}) {
    const std::string m =
        CheckError(std::string("{name: c, signal: x, reduce: max_of_window_min, window: ") + bad + ", max: 1}");
    EXPECT_NE(m.find("s.yaml:4: checks[0].window: must be a finite number of seconds > 0"), std::string::npos)
        << bad << ": " << m;
  }
  for (const char* bad : {".nan", ".inf"}) {  // refused by the number reader already
    const std::string m =
        CheckError(std::string("{name: c, signal: x, reduce: max_of_window_min, window: ") + bad + ", max: 1}");
    EXPECT_NE(m.find("s.yaml:4: checks[0].window: expected a finite number"), std::string::npos) << bad << ": " << m;
  }
  const std::string stray = CheckError("{name: c, signal: x, reduce: max, window: 2, max: 1}");
  EXPECT_NE(stray.find("window: only for reduce min_of_window_max or max_of_window_min"), std::string::npos) << stray;
  const std::string unknown = CheckError("{name: c, signal: x, reduce: window_max, max: 1}");
  EXPECT_NE(unknown.find("min_of_window_max, max_of_window_min"), std::string::npos) << unknown;
}

TEST(CheckSetTest, UnknownSignalNamesCheckAndSignal) {
  CheckConfig c = Check("tracking", "max");
  c.signal = "controller.postion_error";
  try {
    CheckSet set({Check("fine", "max"), c}, kColumns);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("case.yaml:12"), std::string::npos) << m;
    EXPECT_NE(m.find("check 'tracking'"), std::string::npos) << m;
    EXPECT_NE(m.find("unknown signal 'controller.postion_error'"), std::string::npos) << m;
  }
}

TEST(CheckSetTest, ReadsItsOwnColumn) {
  // the signal's column is found by name, not assumed to be the second
  CheckSet set({Check("x", "final")}, {"time", "y", "x", "z"});
  const double row[4] = {0.0, 100.0, 7.0, -100.0};
  set.Add(0.0, row);
  EXPECT_EQ(set.Results()[0].value, 7.0);
}

TEST(CheckSetTest, AWindowAfterTheRunsEndIsSkippedOneWithinItFails) {
  // a run shortened to 7 s: a check from 10 s is skipped (passes, says so); one from 5 s to
  // 6.5 s whose samples are all there is evaluated; one from 6.5 s to 6.9 s holds no sample
  // inside the run and fails
  CheckConfig late = Check("late", "max", 10.0);
  late.max = 0;  // would fail if evaluated
  CheckConfig seen = Check("seen", "max", 5.0, 6.5);
  seen.max = -5;  // x = -9 at 5 s: fails
  CheckConfig empty = Check("empty", "max", 6.5, 6.9);
  empty.max = 100;
  CheckSet set({late, seen, empty}, kColumns);
  for (std::size_t i = 0; i < kSeries.size(); ++i) {
    const double row[2] = {static_cast<double>(i), kSeries[i]};
    set.Add(row[0], row);
  }
  const std::vector<CheckResult> r = set.Results(7.0);
  EXPECT_TRUE(r[0].skipped);
  EXPECT_TRUE(r[0].pass);
  EXPECT_EQ(r[0].samples, 0);
  EXPECT_FALSE(r[1].skipped);
  EXPECT_FALSE(r[1].pass);
  EXPECT_FALSE(r[2].skipped);
  EXPECT_FALSE(r[2].pass) << "a window inside the run without a sample fails";
  // a run that ended after every window (no end given): nothing is skipped, and the late check fails
  EXPECT_FALSE(set.Results()[0].skipped);
}

}  // namespace
}  // namespace vlab::lab::checks_test
