// lab_compare.h: logs aligned by time, tolerances per column pattern, first and
// worst divergence; lab_golden.h: golden.yaml read strictly, logs thinned byte for byte.
#include "lab/judge/lab_compare.h"
#include "lab/judge/lab_golden.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/core_errors.h"
#include "test_util.h"

namespace vlab::lab::compare_test {
namespace {

using vlab::testing::TempDir;
using vlab::testing::WriteFile;

CsvTable Table(std::vector<std::string> columns, std::vector<std::vector<double>> rows, std::string file = "t.csv") {
  CsvTable t;
  t.file = std::move(file);
  t.columns = std::move(columns);
  t.rows = std::move(rows);
  return t;
}

const ColumnReport& Col(const CompareReport& r, const std::string& name) {
  for (const ColumnReport& c : r.columns) {
    if (c.column == name) return c;
  }
  throw std::runtime_error("no column " + name);
}

TEST(CompareTest, IdenticalLogsPassExactly) {
  const CsvTable g = Table({"time", "a", "b"}, {{0, 1, 2}, {0.5, 3, 4}});
  const CompareReport r = CompareLogs(g, g, {});
  EXPECT_TRUE(r.pass());
  EXPECT_EQ(r.golden_rows, 2);
  EXPECT_EQ(Col(r, "a").compared, 2);
}

TEST(CompareTest, AbsoluteAndRelativeToleranceBoundaries) {
  // allowed = abs + rel |golden| = 0.1 + 0.01 * 10 = 0.2 at golden 10
  const CsvTable g = Table({"time", "x"}, {{0, 10}});
  CompareOptions o;
  o.tolerances = {{"x", 0.1, 0.01, false}};
  EXPECT_TRUE(CompareLogs(Table({"time", "x"}, {{0, 10.2}}), g, o).pass());
  EXPECT_TRUE(CompareLogs(Table({"time", "x"}, {{0, 9.8}}), g, o).pass());
  const CompareReport out = CompareLogs(Table({"time", "x"}, {{0, 10.25}}), g, o);
  EXPECT_FALSE(out.pass());
  EXPECT_NEAR(Col(out, "x").worst.excess, 0.25 / 0.2, 1e-9);
  // no pattern matches: exact; the smallest difference fails
  EXPECT_FALSE(CompareLogs(Table({"time", "x"}, {{0, std::nextafter(10.0, 11.0)}}), g, {}).pass());
}

TEST(CompareTest, FirstMatchingPatternWinsAndIgnoreSkips) {
  const CsvTable g = Table({"time", "arm.q.S1", "arm.tau.S1", "jr3.Fx"}, {{0, 1, 1, 1}});
  const CsvTable run = Table({"time", "arm.q.S1", "arm.tau.S1", "jr3.Fx"}, {{0, 1.05, 1.05, 99}});
  CompareOptions o;
  o.tolerances = {{"arm.q.*", 0.1, 0, false}, {"arm.*", 0.01, 0, false}, {"jr3.*", 0, 0, true}};
  const CompareReport r = CompareLogs(run, g, o);
  EXPECT_TRUE(Col(r, "arm.q.S1").pass());
  EXPECT_FALSE(Col(r, "arm.tau.S1").pass());
  EXPECT_EQ(r.ignored, (std::vector<std::string>{"jr3.Fx"}));
  EXPECT_EQ(r.failing(), 1);
}

TEST(CompareTest, ReportsFirstAndWorstDivergence) {
  const CsvTable g = Table({"time", "x"}, {{0, 0}, {1, 0}, {2, 0}, {3, 0}, {4, 0}});
  const CsvTable run = Table({"time", "x"}, {{0, 0}, {1, 0.2}, {2, 0.9}, {3, -0.5}, {4, 0}});
  CompareOptions o;
  o.tolerances = {{"x", 0.1, 0, false}};
  const ColumnReport c = Col(CompareLogs(run, g, o), "x");
  EXPECT_EQ(c.out, 3);
  EXPECT_EQ(c.first.time_s, 1.0);
  EXPECT_EQ(c.first.run, 0.2);
  EXPECT_EQ(c.worst.time_s, 2.0);
  EXPECT_NEAR(c.worst.excess, 9.0, 1e-12);
  EXPECT_EQ(c.max_abs_diff, 0.9);
}

TEST(CompareTest, AlignsByTimeNotByRow) {
  // run at twice the golden's rate: golden rows meet run rows at the same times
  const CsvTable g = Table({"time", "x"}, {{0, 0}, {1, 2}, {2, 4}});
  const CsvTable run = Table({"time", "x"}, {{0, 0}, {0.5, 1}, {1, 2}, {1.5, 3}, {2, 4}});
  EXPECT_TRUE(CompareLogs(run, g, {}).pass());
  // run rows between the golden's times: linear interpolation, x = 2 t exactly
  const CsvTable offset = Table({"time", "x"}, {{0, 0}, {0.75, 1.5}, {1.25, 2.5}, {2, 4}});
  EXPECT_TRUE(CompareLogs(offset, g, {}).pass());
  // the window limits the golden rows compared
  CompareOptions o;
  o.from_s = 0.5;
  o.to_s = 1.5;
  const CompareReport r = CompareLogs(Table({"time", "x"}, {{0, 7}, {1, 2}, {2, 7}}), g, o);
  EXPECT_TRUE(r.pass());
  EXPECT_EQ(r.golden_rows, 1);
}

TEST(CompareTest, ShortRunMissingColumnAndNaNFail) {
  const CsvTable g = Table({"time", "x", "y"}, {{0, 0, 0}, {1, 0, 0}});
  const CompareReport short_run = CompareLogs(Table({"time", "x", "y"}, {{0, 0, 0}, {0.5, 0, 0}}), g, {});
  EXPECT_FALSE(short_run.pass());
  EXPECT_NE(short_run.coverage_failure.find("covers t = 0 .. 0.5 s"), std::string::npos) << short_run.coverage_failure;
  const CompareReport missing = CompareLogs(Table({"time", "x", "z"}, {{0, 0, 0}, {1, 0, 0}}), g, {});
  EXPECT_TRUE(Col(missing, "y").missing);
  EXPECT_EQ(missing.run_only, (std::vector<std::string>{"z"}));
  EXPECT_NE(FormatCompareReport(missing, false).find("FAIL y: not in the run's log"), std::string::npos);
  const CsvTable nan_golden = Table({"time", "x"}, {{0, NAN}});
  EXPECT_TRUE(CompareLogs(Table({"time", "x"}, {{0, NAN}}), nan_golden, {}).pass());
  CompareOptions loose;
  loose.tolerances = {{"*", 1e9, 0, false}};
  EXPECT_FALSE(CompareLogs(Table({"time", "x"}, {{0, 1}}), nan_golden, loose).pass());
}

TEST(CompareTest, ReportTextNamesColumnFirstAndWorst) {
  const CsvTable g = Table({"time", "pa10.q.S2"}, {{0, 0}, {1, 0}});
  const CsvTable run = Table({"time", "pa10.q.S2"}, {{0, 0.001}, {1, 0.002}}, "run.csv");
  CompareOptions o;
  o.tolerances = {{"pa10.q.*", 1e-9, 0, false}};
  const std::string text = FormatCompareReport(CompareLogs(run, g, o), false);
  EXPECT_NE(text.find("FAIL pa10.q.S2 (abs 1e-09): 2 of 2 rows out"), std::string::npos) << text;
  EXPECT_NE(text.find("first t = 0 s: run 0.001, golden 0"), std::string::npos) << text;
  EXPECT_NE(text.find("worst t = 1 s: run 0.002, golden 0"), std::string::npos) << text;
  EXPECT_NE(text.find("result: FAIL (1 of 1 columns diverge)"), std::string::npos) << text;
}

TEST(CompareTest, ReadCsvTableNamesFileLineAndField) {
  TempDir dir;
  WriteFile(dir / "a.csv", "time,x\n0,1\n1,oops\n");
  try {
    ReadCsvTable(dir / "a.csv");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a.csv:3: x: not a number: 'oops'"), std::string::npos) << e.what();
  }
  WriteFile(dir / "b.csv", "time,x\n0,1,2\n");
  EXPECT_THROW(ReadCsvTable(dir / "b.csv"), InputError);
  EXPECT_THROW(ReadCsvTable(dir / "none.csv"), InputError);
}

TEST(GoldenSpecTest, ReadsKeysAndRejectsBadOnes) {
  TempDir dir;
  WriteFile(dir / "s.yaml", "scene: x.xml\nduration: 1\n");
  WriteFile(dir / "golden.yaml",
            "scenario: s.yaml\nduration: 0.5\nevery: 4\nset: [seed=3]\n"
            "tolerances:\n  - {columns: 'q.*', abs: 1e-9, rel: 1e-6}\n  - {columns: 'jr3.*', ignore: true}\n");
  const GoldenSpec g = LoadGolden(dir.path());
  EXPECT_EQ(g.every, 4);
  EXPECT_EQ(g.duration_s, 0.5);
  EXPECT_EQ(g.sets, (std::vector<std::string>{"seed=3"}));
  ASSERT_EQ(g.compare.tolerances.size(), 2u);
  EXPECT_EQ(g.compare.tolerances[0].rel, 1e-6);
  EXPECT_TRUE(g.compare.tolerances[1].ignore);
  auto error = [&](const std::string& text) {
    WriteFile(dir / "golden.yaml", text);
    try {
      LoadGolden(dir.path());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("scenario: s.yaml\nevry: 2\n").find("golden.yaml:2: evry: unknown key"), std::string::npos);
  EXPECT_NE(error("scenario: nope.yaml\n").find("scenario: no such file"), std::string::npos);
  EXPECT_NE(error("scenario: s.yaml\ntolerances: [{columns: x, abs: -1}]\n").find("tolerances[0].abs: must be >= 0"),
            std::string::npos);
  EXPECT_NE(error("scenario: s.yaml\nevery: 0\n").find("every: must be >= 1"), std::string::npos);
  TempDir empty;
  try {
    LoadGolden(empty.path());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a golden folder (no golden.yaml"), std::string::npos) << e.what();
  }
}

TEST(GoldenSpecTest, ThinnedLogKeepsHeaderRowZeroAndEveryNthByteForByte) {
  TempDir dir;
  WriteFile(dir / "log.csv", "time,x\n0,0.1\n0.5,0.2\n1,0.30000000000000004\n1.5,0.4\n2,0.5\n");
  WriteDecimatedLog(dir / "log.csv", dir / "g.csv", 2);
  EXPECT_EQ(vlab::testing::ReadFile(dir / "g.csv"), "time,x\n0,0.1\n1,0.30000000000000004\n2,0.5\n");
  EXPECT_EQ(vlab::testing::Entries(dir.path()).size(), 2u) << "no temporary file left";
}

}  // namespace
}  // namespace vlab::lab::compare_test
