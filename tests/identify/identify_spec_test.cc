// vlab identify's spec: read and checked, every error naming the file, the entry and the
// field; names bound to the scenario's model and the log's columns with the same care.
#include <charconv>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"
#include "identify_test_plant.h"
#include "scene/scene_csv.h"
#include "test_util.h"

namespace vlab::identify {
namespace {

using vlab::testing::TempDir;
using vlab::testing::WriteFile;

TEST(IdentifySpec, MatchColumn) {
  EXPECT_TRUE(MatchColumn("pa10.q.*", "pa10.q.S1"));
  EXPECT_FALSE(MatchColumn("pa10.q.*", "pa10.qd.S1"));
  EXPECT_TRUE(MatchColumn("*.S1", "pa10.qd.S1"));
  EXPECT_TRUE(MatchColumn("pa10.q*", "pa10.qd.S1"));
  EXPECT_TRUE(MatchColumn("pa10.*.S*", "pa10.qd.S1"));
  EXPECT_FALSE(MatchColumn("pa10.q.S1", "pa10.q.S12"));
  EXPECT_FALSE(MatchColumn("", "pa10.q.S1"));
}

// a valid spec with one line replaced (`from` -> `to`), for the error cases
std::string Spec(const std::string& from = "", const std::string& to = "") {
  std::string text = "scenario: " + testing::kScenario +
                     "\nlogs: [run]\nwindow: 0.2\ninput: torque\ncolumns:\n  - {name: pa10.q.*, weight: 1.0e5}\n"
                     "parameters:\n  - {name: a, target: body pa10_link2 mass, lower: 4, upper: 16}\n"
                     "  - {name: b, target: joint S1 damping, nominal: 1, lower: 0, upper: 5, frozen: true}\n";
  if (!from.empty()) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  return text;
}

TEST(IdentifySpec, ReadsEveryKey) {
  TempDir tmp;
  WriteFile(tmp / "id.yaml", Spec("window: 0.2",
                                  "window: 0.5\nstart_smoothing: 4\ncontacts: keep\nmax_iterations: 7\n"
                                  "first_estimate: nominal"));
  const identify::Spec s = LoadSpec(tmp / "id.yaml");
  EXPECT_EQ(s.scenario, testing::kScenario);
  ASSERT_EQ(s.logs.size(), 1u);
  EXPECT_EQ(s.logs[0], tmp / "run");  // not a folder there: taken as a file
  EXPECT_EQ(s.window_s, 0.5);
  EXPECT_EQ(s.start_smoothing, 4);
  EXPECT_FALSE(s.skip_contacts);
  EXPECT_EQ(s.max_iterations, 7);
  EXPECT_EQ(s.first_estimate, FirstEstimate::kNominal);
  WriteFile(tmp / "default.yaml", Spec());
  EXPECT_EQ(LoadSpec(tmp / "default.yaml").first_estimate, FirstEstimate::kLinear);  // the default
  ASSERT_EQ(s.columns.size(), 1u);
  EXPECT_EQ(s.columns[0].weight, 1e5);
  ASSERT_EQ(s.parameters.size(), 2u);
  EXPECT_EQ(s.parameters[0].kind, TargetKind::kBodyMass);
  EXPECT_EQ(s.parameters[0].element, "pa10_link2");
  EXPECT_FALSE(s.parameters[0].has_nominal);
  EXPECT_EQ(s.parameters[1].kind, TargetKind::kJointDamping);
  EXPECT_TRUE(s.parameters[1].has_nominal);
  EXPECT_EQ(s.parameters[1].nominal, 1.0);
  EXPECT_TRUE(s.parameters[1].frozen);
}

// the shipped spec reads (its log is made by the command its comment gives)
TEST(IdentifySpec, ShippedSpecReads) {
  const identify::Spec s = LoadSpec(VLAB_SOURCE_DIR "/scenes/identify/pa10_joint_pd.yaml");
  EXPECT_EQ(s.scenario, VLAB_SOURCE_DIR "/scenes/pa10_joint_pd.yaml");
  ASSERT_EQ(s.logs.size(), 1u);
  EXPECT_NE(s.logs[0].find("out/pa10_joint_pd"), std::string::npos);
  EXPECT_EQ(s.parameters.size(), 8u);
}

TEST(IdentifySpec, RefusesBadEntriesNamingTheField) {
  struct Case {
    std::string from, to, message;
  };
  const std::vector<Case> cases = {
      {"window: 0.2", "windw: 0.2", ":3: windw: unknown key"},
      {"window: 0.2", "window: -1", ":3: window: must be > 0"},
      {"input: torque", "input: servo", ":4: input: must be 'torque' (the recorded joint torques) or 'reference'"},
      {"body pa10_link2 mass", "servo pa10 bandwidth",
       ":8: parameters[0].target: 'servo pa10 bandwidth' needs input: reference"},
      {"body pa10_link2 mass, lower: 4", "servo pa10 damping_ratio, lower: 0",
       ":8: parameters[0].lower: must be > 0 for servo pa10 damping_ratio"},
      {"body pa10_link2 mass", "servo pa10 gains", ":8: parameters[0].target: 'servo pa10 gains' is none of"},
      {"input: torque", "input: torque\nservo_sensing: exact", ":5: servo_sensing: needs input: reference"},
      {"input: torque", "input: reference\nservo_sensing: counts",
       ":5: servo_sensing: must be 'scenario' or 'exact', got 'counts'"},
      {"window: 0.2", "first_estimate: linear_regression", ":3: first_estimate: must be 'linear' or 'nominal'"},
      {"logs: [run]", "logs: []", "logs: name at least one log"},
      {"weight: 1.0e5", "weight: -1", ":6: columns[0].weight: must be a finite number > 0"},
      {"body pa10_link2 mass", "body pa10_link2 volume",
       ":8: parameters[0].target: 'body pa10_link2 volume' is none of"},
      {"lower: 4, upper: 16", "lower: 4, upper: 4", ":8: parameters[0].upper: must be greater than lower"},
      {"lower: 4, upper: 16", "lower: 0, upper: 16", ":8: parameters[0].lower: must be > 0 for body pa10_link2 mass"},
      {"nominal: 1,", "nominal: 9,", ":9: parameters[1].nominal: must lie within [lower, upper]"},
      {"frozen: true", "frozen: maybe", ":9: parameters[1].frozen:"},
      {"name: b,", "name: a,", ":9: parameters[1].name: duplicate parameter name 'a'"},
      {"body pa10_link2 mass", "joint S1 damping",
       ":9: parameters[1].target: 'joint S1 damping' is already parameter 'a'"},
      {"name: a, target", "nme: a, target", ":8: parameters[0].name: missing"},
  };
  TempDir tmp;
  for (const Case& c : cases) {
    WriteFile(tmp / "id.yaml", Spec(c.from, c.to));
    try {
      LoadSpec(tmp / "id.yaml");
      ADD_FAILURE() << "accepted: " << c.to;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(tmp / "id.yaml"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
}

// names the scenario's model or the log does not have: refused when bound, naming the entry
TEST(IdentifySpec, RefusesNamesTheModelOrLogLacks) {
  TempDir tmp;
  testing::RunLab(testing::kScene, tmp / "run", 0.5);
  struct Case {
    std::string from, to, message;
  };
  const std::vector<Case> cases = {
      {"body pa10_link2 mass", "body nobody mass", ":8: parameters[0].target: no body 'nobody' in the scene"},
      {"joint S1 damping", "joint S9 damping", ":9: parameters[1].target: no joint 'S9' in the scene"},
      {"joint S1 damping", "column jr3.Fx bias", ":9: parameters[1].target: 'jr3.Fx' is not an arm's q or qd column"},
      {"joint S1 damping", "column pa10.qd.S1 bias",
       ":9: parameters[1].target: column 'pa10.qd.S1' is not among the fitted columns"},
      {"name: pa10.q.*", "name: jr3.F*", ":6: columns[0].name: 'jr3.F*' names none of the columns the replay predicts"},
      {"window: 0.2", "window: 0.9", "window: 0.9"},  // longer than the 0.5 s log
  };
  for (const Case& c : cases) {
    WriteFile(tmp / "id.yaml", Spec(c.from, c.to));
    try {
      Problem::Create(LoadSpec(tmp / "id.yaml"));
      ADD_FAILURE() << "accepted: " << c.to;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
  // a log without the torques the replay needs
  vlab::testing::WriteFile(tmp / "short.csv", "time,pa10.q.S1\n0,0\n0.002,0\n");
  WriteFile(tmp / "id.yaml", Spec("logs: [run]", "logs: [short.csv]"));
  try {
    Problem::Create(LoadSpec(tmp / "id.yaml"));
    ADD_FAILURE() << "accepted a log without torques";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("short.csv': no column 'pa10.qd.S1'"), std::string::npos) << e.what();
  }
}

// input: reference binds the arms' recorded commands and the servo targets' devices: a log
// without the command columns, a servo target naming no arm device, a mode that is none
TEST(IdentifySpec, RefusesWhatTheReferenceReplayLacks) {
  TempDir tmp;
  testing::RunLab(testing::kScene, tmp / "run", 0.2);  // no command columns
  auto edit = [](std::string text, const std::string& from, const std::string& to) {
    return text.replace(text.find(from), from.size(), to);
  };
  auto refused = [&](const std::string& text, const std::string& message) {
    WriteFile(tmp / "id.yaml", text);
    try {
      Problem::Create(LoadSpec(tmp / "id.yaml"));
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  const std::string reference = Spec("input: torque", "input: reference");
  refused(reference, "log '" + tmp / "run/log.csv" + "': no column 'pa10.cmd_mode'");
  // a servo target naming a device that is no arm
  refused(edit(reference, "body pa10_link2 mass", "servo jr3 bandwidth"),
          ":8: parameters[0].target: no arm device 'jr3' in the scenario (its arms: pa10)");
  // a command mode that is none of the four, named by its row and column
  testing::RunLab(testing::kScene, tmp / "cmd", 0.2, {"devices.pa10.log_command=true"});
  scene::CsvTable table = scene::ReadCsvTable(tmp / "cmd/log.csv");
  const int mode = table.Column("pa10.cmd_mode");
  ASSERT_GE(mode, 0);
  table.rows[3][mode] = 7;
  std::string csv;
  for (std::size_t c = 0; c < table.columns.size(); ++c) csv += (c ? "," : "") + table.columns[c];
  csv += "\n";
  char buffer[32];
  for (const std::vector<double>& row : table.rows) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      csv += (c ? "," : "") + std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, row[c]).ptr);
    }
    csv += "\n";
  }
  WriteFile(tmp / "bad_mode.csv", csv);
  refused(edit(reference, "logs: [run]", "logs: [bad_mode.csv]"),
          "log '" + tmp / "bad_mode.csv" + "': row 5: column 'pa10.cmd_mode' is 7, not a command mode");
  // the torque replay predicts no torque column
  refused(edit(Spec(), "name: pa10.q.*", "name: pa10.tau.*"),
          "'pa10.tau.*' names none of the columns the replay predicts");
}

}  // namespace
}  // namespace vlab::identify
