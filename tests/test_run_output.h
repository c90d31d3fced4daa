// Checks of the output folder of an interrupted run (vlab run, vlab serve): the
// files are complete for the periods that ran. Shared by the lab and serve tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_util.h"

namespace vlab::testing {

/// Expects `dir` to hold the whole output of a run interrupted by `signal`
/// ("SIGINT", "SIGTERM") with control period period_s: summary.json with result
/// `interrupted`, exit code 1 and the reason (the signal, the simulated time);
/// log.csv with its header, the row of t = 0 and one row per period run, every
/// row with every column and a newline at its end, the last at periods · T.
/// Returns the periods run (-1 when a file is missing or broken).
inline long ExpectInterruptedOutput(const std::string& dir, const std::string& signal, double period_s) {
  const std::string summary_text = ReadFile(dir + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(summary_text, nullptr, false);
  EXPECT_FALSE(summary.is_discarded()) << dir << "/summary.json: " << summary_text;
  if (summary.is_discarded()) return -1;
  EXPECT_EQ(summary.value("result", ""), "interrupted") << summary_text;
  EXPECT_EQ(summary.value("exit_code", -1), 1);
  const std::string failure = summary.value("failure", "");
  EXPECT_NE(failure.find("interrupted by " + signal + " at t = "), std::string::npos) << failure;
  EXPECT_TRUE(summary.contains("interrupted")) << summary_text;
  if (!summary.contains("interrupted")) return -1;
  const nlohmann::json& why = summary.at("interrupted");
  EXPECT_EQ(why.value("signal", ""), signal);
  const long periods = why.value("periods", -1L);
  EXPECT_GE(periods, 0);
  EXPECT_EQ(summary.at("timings").at("control_periods").get<long>(), periods);
  const double t_end = static_cast<double>(periods) * period_s;  // as the lab computes it: k T
  EXPECT_EQ(why.value("sim_time_s", -1.0), t_end);
  const std::size_t at = failure.find("at t = ");
  if (at != std::string::npos) {
    EXPECT_EQ(std::stod(failure.substr(at + 7)), t_end) << failure;
  }

  const std::string log = ReadFile(dir + "/log.csv");
  EXPECT_FALSE(log.empty()) << dir << "/log.csv";
  if (log.empty()) return -1;
  EXPECT_EQ(log.back(), '\n') << "the last row is whole";
  const std::vector<std::string> lines = Lines(log);
  EXPECT_EQ(lines.size(), static_cast<std::size_t>(periods) + 2) << "header, t = 0, one row per period";
  const std::vector<std::string> header = SplitCsv(lines.at(0));
  const std::size_t columns = header.size();
  EXPECT_EQ(header.at(0), "time") << lines.at(0);  // (a scenario that logs no device has only it)
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> fields = SplitCsv(lines[i]);
    std::size_t empty = 0;
    for (const std::string& f : fields) empty += f.empty() ? 1 : 0;
    const bool whole = fields.size() == columns && empty == 0 && !fields[0].empty() &&
                       std::stod(fields[0]) == static_cast<double>(i - 1) * period_s;
    EXPECT_TRUE(whole) << "row " << i << " (" << fields.size() << " of " << columns << " fields, " << empty
                       << " empty; time " << (fields.empty() ? "-" : fields[0]) << "): " << lines[i];
    if (!whole) break;  // one message, not thousands
  }
  return periods;
}

/// The --duration of a run of exactly `periods` periods of period_s (as the lab computes
/// its end: k T), written so that it reads back as the same double.
inline std::string DurationOfPeriods(long periods, double period_s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.17g", static_cast<double>(periods) * period_s);
  return text;
}

}  // namespace vlab::testing
