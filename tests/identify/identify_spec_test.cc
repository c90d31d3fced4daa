// vlab identify's spec: read and checked, every error naming the file, the entry and the
// field; names bound to the scenario's model and the log's columns with the same care.
#include <charconv>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "identify/identify_output.h"
#include "identify/identify_problem.h"
#include "identify/identify_spec.h"
#include "identify_test_plant.h"
#include "scene/scene_csv.h"
#include "test_util.h"

namespace vlab::identify::spec_test {
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

// the spec `text`, written to `file`, is refused when its problem is made (bound to the model and
// the logs), with an InputError whose message holds `message`
void ExpectProblemRefused(const std::string& file, const std::string& text, const std::string& message) {
  WriteFile(file, text);
  try {
    Problem::Create(LoadSpec(file));
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << text << ": " << e.what();
  }
}

TEST(IdentifySpec, ReadsEveryKey) {
  TempDir tmp;
  WriteFile(tmp / "id.yaml", Spec("window: 0.2",
                                  "window: 0.5\nstart_smoothing: 4\ncontacts: keep\nmax_iterations: 7\n"
                                  "first_estimate: nominal\nwrench_settle: 0.05"));
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
  EXPECT_EQ(s.wrench_settle_s, 0.05);
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
  EXPECT_LT(LoadSpec(tmp / "id.yaml").wrench_settle_s, 1.0);
  // the centre-of-mass and payload targets
  WriteFile(tmp / "id.yaml", Spec("target: joint S1 damping, nominal: 1, lower: 0, upper: 5, frozen: true",
                                  "target: payload tool_body mass, lower: 0, upper: 2}\n"
                                  "  - {name: c, target: payload tool_body com_z, lower: -1, upper: 1}\n"
                                  "  - {name: d, target: body pa10_link3 com_y, lower: -1, upper: 1"));
  const identify::Spec t = LoadSpec(tmp / "id.yaml");
  ASSERT_EQ(t.parameters.size(), 4u);
  EXPECT_EQ(t.parameters[1].kind, TargetKind::kPayloadMass);
  EXPECT_EQ(t.parameters[2].kind, TargetKind::kPayloadCom);
  EXPECT_EQ(t.parameters[2].axis, 2);
  EXPECT_EQ(t.parameters[3].kind, TargetKind::kBodyCom);
  EXPECT_EQ(t.parameters[3].element, "pa10_link3");
  EXPECT_EQ(t.parameters[3].axis, 1);
  EXPECT_EQ(TargetText(t.parameters[3].kind, t.parameters[3].element, t.parameters[3].axis), "body pa10_link3 com_y");
  EXPECT_LT(t.wrench_settle_s, 0.0);  // the filter's own
  // the PowerBall's keys: spans, a derived column, a start speed with its run-in, an inertia
  // target, the Jacobian's step
  std::string text = Spec(
      "window: 0.2", "window: 0.2\nspans: [[0.5, 2], [3, 4.5]]\nstart_speed: pb.rpm\nrun_in: 0.1\njacobian_step: 0.01");
  auto edit = [&](const std::string& from, const std::string& to) { text.replace(text.find(from), from.size(), to); };
  edit("  - {name: pa10.q.*, weight: 1.0e5}",
       "  - {name: pa10.q.*, weight: 1.0e5, spans: [[1, 2]]}\n  - {name: m, norm: [jr3.My, jr3.Mz], rate: true, "
       "weight: 2}");
  edit("joint S1 damping, nominal: 1, lower: 0", "body pa10_link2 inertia_z, nominal: 1, lower: 0.5");
  WriteFile(tmp / "id.yaml", text);
  const identify::Spec u = LoadSpec(tmp / "id.yaml");
  ASSERT_EQ(u.spans.size(), 2u);
  EXPECT_EQ(u.spans[1], std::make_pair(3.0, 4.5));
  EXPECT_EQ(u.start_speed, "pb.rpm");
  EXPECT_EQ(u.run_in_s, 0.1);
  EXPECT_EQ(u.jacobian_step, 0.01);
  ASSERT_EQ(u.columns.size(), 2u);
  ASSERT_EQ(u.columns[0].spans.size(), 1u);
  EXPECT_TRUE(u.columns[0].norm.empty());
  EXPECT_EQ(u.columns[1].pattern, "m");
  EXPECT_EQ(u.columns[1].norm, std::vector<std::string>({"jr3.My", "jr3.Mz"}));
  EXPECT_TRUE(u.columns[1].rate);
  EXPECT_EQ(u.parameters[1].kind, TargetKind::kBodyInertia);
  EXPECT_EQ(u.parameters[1].axis, 2);
  EXPECT_EQ(TargetText(u.parameters[1].kind, u.parameters[1].element, u.parameters[1].axis),
            "body pa10_link2 inertia_z");
  EXPECT_TRUE(s.spans.empty());
  EXPECT_TRUE(s.start_speed.empty());
  EXPECT_EQ(s.run_in_s, 0.0);
  EXPECT_EQ(s.jacobian_step, 1e-4);
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
      {"body pa10_link2 mass", "body pa10_link2 com_w", ":8: parameters[0].target: 'body pa10_link2 com_w' is none of"},
      {"joint S1 damping", "payload pa10_link2 com_x",
       ":9: parameters[1].target: 'payload pa10_link2 com_x' needs a 'payload pa10_link2 mass' parameter"},
      {"body pa10_link2 mass, lower: 4", "payload pa10_link2 mass, lower: -1",
       ":8: parameters[0].lower: must be >= 0 for payload pa10_link2 mass"},
      {"window: 0.2", "window: 0.2\nwrench_settle: -1", ":4: wrench_settle: must be from 0 to 1000 s"},
      {"window: 0.2", "window: 0.2\nspans: [[2, 1]]", ":4: spans[0]: must be [from, to] in seconds, finite, to > from"},
      {"window: 0.2", "window: 0.2\nspans: [[1, 2, 3]]", ":4: spans[0]: must be [from, to]"},
      {"window: 0.2", "window: 0.2\nspans: [1, 2]", ":4: spans[0]: must be [from, to] in seconds"},
      {"window: 0.2", "window: 0.2\nspans: []", ":4: spans: name at least one [from, to] span"},
      {"window: 0.2", "window: 0.2\nrun_in: 0.1", "run_in: needs start_speed"},
      {"window: 0.2", "window: 0.2\nstart_speed: pb.rpm\nrun_in: -1", "run_in: must be from 0 to 100 s"},
      {"window: 0.2", "window: 0.2\njacobian_step: 1", "jacobian_step: must be from 1e-8 to 0.1"},
      {"weight: 1.0e5}", "weight: 1.0e5, rate: true}", ":6: columns[0].rate: is for a derived column (norm:)"},
      {"name: pa10.q.*, weight: 1.0e5}", "name: m*, norm: [jr3.Mx]}",
       ":6: columns[0].name: a derived column's own name has no '*'"},
      {"name: pa10.q.*, weight: 1.0e5}", "name: m, norm: [jr3.M*]}", ":6: columns[0].norm: 'jr3.M*' is not a column"},
      {"name: pa10.q.*, weight: 1.0e5}", "name: m, norm: []}", ":6: columns[0].norm: name at least one column"},
      {"weight: 1.0e5}", "weight: 1.0e5, spans: [[3, 3]]}", ":6: columns[0].spans[0]: must be [from, to]"},
      {"body pa10_link2 mass, lower: 4", "body pa10_link2 inertia_x, lower: 0",
       ":8: parameters[0].lower: must be > 0 for body pa10_link2 inertia_x"},
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
      {"joint S1 damping", "column jr3.Fx bias", ":9: parameters[1].target: column 'jr3.Fx' is not among the fitted"},
      {"joint S1 damping", "column pa10.tau.S1 bias",
       ":9: parameters[1].target: 'pa10.tau.S1' is not a column the replay predicts (an arm's q or qd, a wrench "
       "device's axis: pa10.q.S1,"},
      {"body pa10_link2 mass", "body nobody com_x", ":8: parameters[0].target: no body 'nobody' in the scene"},
      {"body pa10_link2 mass, lower: 4", "payload world mass, lower: 0",
       ":8: parameters[0].target: no body 'world' in the scene (the world's is not one)"},
      {"name: pa10.q.*, weight: 1.0e5}", "name: jr3.*}",
       ":3: window: windows of 100 rows leave no wrench row: 112 rows"},
      {"joint S1 damping", "column pa10.qd.S1 bias",
       ":9: parameters[1].target: column 'pa10.qd.S1' is not among the fitted columns"},
      {"name: pa10.q.*", "name: jr3.sat*",
       ":6: columns[0].name: 'jr3.sat*' names none of the columns the replay predicts"},
      {"window: 0.2", "window: 0.9", "window: 0.9"},  // longer than the 0.5 s log
      {"window: 0.2", "window: 0.2\nspans: [[0.1, 0.2]]", ":3: window: 0.200000 s is longer than every log's spans"},
      {"name: pa10.q.*, weight: 1.0e5}", "name: m, norm: [pa10.q.S1, jr3.Mw]}",
       ":6: columns[0].norm: 'jr3.Mw' is none of the columns a norm can take"},
      {"name: pa10.q.*, weight: 1.0e5}", "name: pa10.q.S1, norm: [pa10.q.S2]}",
       ":6: columns[0].name: 'pa10.q.S1' is taken: name the derived column apart"},
      {"window: 0.2", "window: 0.2\nstart_speed: pa10.q.S1",
       "start_speed: 'pa10.q.S1' is no counter device's speed column (the scenario's: none)"},
      // a mass scales the inertia: the one or the other
      {"joint S1 damping, nominal: 1, lower: 0, upper: 5", "body pa10_link2 inertia_x, lower: 0.001, upper: 5",
       ":9: parameters[1].target: body 'pa10_link2' has a mass parameter too"},
      // bounds that let the moments break the triangle inequality
      {"body pa10_link2 mass, lower: 4, upper: 16", "body pa10_link2 inertia_x, lower: 1.0e-6, upper: 100",
       ":8: parameters[0]: the bounds let body 'pa10_link2''s principal moments break I_y + I_z >= I_x"},
  };
  for (const Case& c : cases) ExpectProblemRefused(tmp / "id.yaml", Spec(c.from, c.to), c.message);
  // a delay on a wrench column: its filter's lag is the model's
  std::string text = Spec("name: pa10.q.*, weight: 1.0e5}", "name: pa10.q.*, weight: 1.0e5}\n  - {name: jr3.F*}");
  text.replace(text.find("joint S1 damping"), 16, "column jr3.Fy delay");
  ExpectProblemRefused(
      tmp / "id.yaml", text,
      ":10: parameters[1].target: a delay is for an arm's q or qd column, not the wrench column 'jr3.Fy'");
  // a log without the torques the replay needs
  vlab::testing::WriteFile(tmp / "short.csv", "time,pa10.q.S1\n0,0\n0.002,0\n");
  ExpectProblemRefused(tmp / "id.yaml", Spec("logs: [run]", "logs: [short.csv]"), "short.csv': no column 'pa10.qd.S1'");
}

// start_speed needs counter readings about each window's start within its span: too few is
// refused naming the key, the window and the column (a short PowerBall log, its drive off)
TEST(IdentifySpec, RefusesAStartSpeedWithTooFewReadings) {
  TempDir tmp;
  const std::string stage1 = VLAB_SOURCE_DIR "/cases/powerball/stage1.yaml";
  testing::RunScenario(stage1, tmp / "run",
                       {"controller={type: none}", "clock=fast", "duration=0.5", "checks=[]", "outputs={log: true}",
                        "devices.pa10.log_command=true"});
  const std::string text = "scenario: " + stage1 +
                           "\nlogs: [run]\ninput: reference\ncontacts: keep\nwindow: 0.2\n"
                           "start_speed: pb.rpm\ncolumns:\n  - {name: pb.rpm}\n"
                           "parameters:\n  - {name: c, target: joint pb_spin damping, lower: 0, upper: 1.0e-6}\n";
  // the whole log: 5 readings (a 0.1 s gate) about each start
  WriteFile(tmp / "id.yaml", text);
  EXPECT_EQ(Problem::Create(LoadSpec(tmp / "id.yaml"))->window_count(), 2);
  // a span of 0.25 s holds 2 whole gates
  ExpectProblemRefused(
      tmp / "id.yaml", text + "spans: [[0, 0.25]]\n",
      ":6: start_speed: the window at 0.000000 s of a log has 2 reading(s) of 'pb.rpm' within its span");
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
    ExpectProblemRefused(tmp / "id.yaml", text, message);
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

// A payload: a point mass combined with its body's inertial exactly (the mass sum, the combined
// centre of mass, the inertia about the body's origin the sum of the two), and nothing changed
// at all by a payload of mass 0.
TEST(IdentifyModel, PayloadCombinesWithItsBodyExactly) {
  double mass = 2.0, ipos[3] = {0.1, 0.0, 0.05}, inertia[3] = {0.01, 0.02, 0.03};
  const Eigen::Quaterniond q0 = Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized();
  double iquat[4] = {q0.w(), q0.x(), q0.y(), q0.z()};
  const double m2 = 0.5, c2[3] = {-0.05, 0.1, 0.2};
  // second moment about the body's origin, body frame: R I R^T + m (|c|^2 E - c c^T)
  auto about_origin = [](double m, const double c[3], const double d[3], const double q[4]) {
    const Eigen::Matrix3d r = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
    const Eigen::Vector3d v(c[0], c[1], c[2]);
    return Eigen::Matrix3d(r * Eigen::Vector3d(d[0], d[1], d[2]).asDiagonal() * r.transpose() +
                           m * (v.squaredNorm() * Eigen::Matrix3d::Identity() - v * v.transpose()));
  };
  const double zero[3] = {0, 0, 0};
  const Eigen::Matrix3d expected = about_origin(mass, ipos, inertia, iquat) + about_origin(m2, c2, zero, iquat);
  const double c_expected[3] = {(2.0 * 0.1 + 0.5 * -0.05) / 2.5, (0.5 * 0.1) / 2.5, (2.0 * 0.05 + 0.5 * 0.2) / 2.5};
  AddPointMass(m2, c2, &mass, ipos, inertia, iquat);
  EXPECT_EQ(mass, 2.5);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(ipos[k], c_expected[k], 1e-15);
  EXPECT_NEAR(Eigen::Vector4d(iquat[0], iquat[1], iquat[2], iquat[3]).norm(), 1.0, 1e-14);
  EXPECT_TRUE(inertia[0] > 0 && inertia[0] <= inertia[1] && inertia[1] <= inertia[2]);
  EXPECT_LT((about_origin(mass, ipos, inertia, iquat) - expected).cwiseAbs().maxCoeff(), 1e-14);
  // the triangle inequality of a physical body holds
  EXPECT_LE(inertia[2], inertia[0] + inertia[1]);
  // mass 0: nothing moves, to the bit
  double mass0 = mass, ipos0[3], inertia0[3], iquat0[4];
  std::copy(ipos, ipos + 3, ipos0);
  std::copy(inertia, inertia + 3, inertia0);
  std::copy(iquat, iquat + 4, iquat0);
  AddPointMass(0.0, c2, &mass, ipos, inertia, iquat);
  EXPECT_EQ(std::memcmp(&mass, &mass0, sizeof mass), 0);
  EXPECT_EQ(std::memcmp(ipos, ipos0, sizeof ipos), 0);
  EXPECT_EQ(std::memcmp(inertia, inertia0, sizeof inertia), 0);
  EXPECT_EQ(std::memcmp(iquat, iquat0, sizeof iquat), 0);
}

// Bound to the scene: a payload of mass 0 and the body's own centre of mass leave the model as
// it is to the bit; a payload and a moved centre of mass change exactly that body.
TEST(IdentifyModel, PayloadAndCentreOfMassTargetsSetTheModel) {
  TempDir tmp;
  testing::RunLab(testing::kScene, tmp / "run", 0.3);
  WriteFile(tmp / "id.yaml", Spec("target: joint S1 damping, nominal: 1, lower: 0, upper: 5, frozen: true",
                                  "target: payload tool_body mass, lower: 0, upper: 2}\n"
                                  "  - {name: c, target: payload tool_body com_z, lower: -1, upper: 1}\n"
                                  "  - {name: d, target: body tool_body com_x, lower: -1, upper: 1"));
  const std::unique_ptr<Problem> problem = Problem::Create(LoadSpec(tmp / "id.yaml"));
  const mjModel* m = problem->model();
  const int tool = testing::Body(m, "tool_body");
  std::vector<double> values;
  for (const BoundParameter& p : problem->parameters()) values.push_back(p.nominal);
  EXPECT_EQ(values[1], 0.0);  // the payload's mass: none in the model
  ModelPtr copy(mj_copyModel(nullptr, m));
  problem->SetModel(values, copy.get());
  auto same = [&](const double* a, const double* b, int n) { return std::memcmp(a, b, n * sizeof(double)) == 0; };
  EXPECT_TRUE(same(copy->body_mass, m->body_mass, m->nbody));
  EXPECT_TRUE(same(copy->body_ipos, m->body_ipos, 3 * m->nbody));
  EXPECT_TRUE(same(copy->body_inertia, m->body_inertia, 3 * m->nbody));
  EXPECT_TRUE(same(copy->body_iquat, m->body_iquat, 4 * m->nbody));
  // 0.2 kg at z 0.1 m, the tool's own centre of mass moved 10 mm in x
  values[1] = 0.2;
  values[2] = 0.1;
  values[3] = 0.01;
  problem->SetModel(values, copy.get());
  const double own = m->body_mass[tool], z0 = m->body_ipos[3 * tool + 2];
  EXPECT_DOUBLE_EQ(copy->body_mass[tool], own + 0.2);
  EXPECT_NEAR(copy->body_ipos[3 * tool + 0], own * 0.01 / (own + 0.2), 1e-15);
  EXPECT_NEAR(copy->body_ipos[3 * tool + 2], (own * z0 + 0.2 * 0.1) / (own + 0.2), 1e-15);
  for (int b = 0; b < m->nbody; ++b) {
    if (b != tool) {
      EXPECT_EQ(copy->body_mass[b], m->body_mass[b]);
    }
  }
  // model.xml carries the changed body (mj_saveLastXML: 6 significant digits)
  WriteEditedScene(
      problem->scene(), [&](mjModel* edit) { SetModelParameters(*problem, values, edit); }, tmp / "model.xml");
  const ModelPtr written = LoadModel(tmp / "model.xml");
  EXPECT_NEAR(written->body_mass[tool], copy->body_mass[tool], 1e-6 * copy->body_mass[tool]);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(written->body_ipos[3 * tool + k], copy->body_ipos[3 * tool + k], 1e-6);
    EXPECT_NEAR(written->body_inertia[3 * tool + k], copy->body_inertia[3 * tool + k],
                1e-5 * copy->body_inertia[3 * tool + 2]);
  }
}

}  // namespace
}  // namespace vlab::identify::spec_test
