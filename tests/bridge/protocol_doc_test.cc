// Checks docs/protocol.md against the table of wire layouts
// (bridge/bridge_layouts.h): every "### <Kind> state (kind N, type 1): ...
// values" and "### <Kind> command (kind N, type 2): ... values" section (and
// the arm's "### Arm payload (kind 1, type 6): 10 values"), its
// table's payload indices, field names (in order) and units, and its value
// count; which kinds have which sections; and the kind codes of the "Devices
// and ports" table. The page's conventions: a field cell is "name: meaning"
// or "a, b, c: meaning" (several values sharing the row's unit), a per-joint
// group is written "q_1 … q_n" and a per-sensor group "force_1 … force_m",
// and "–" is the unit of a pure number.
//
// The checker is run on the page as it is (no problem allowed) and on copies
// of it with one mistake each, which it must report: a check that cannot
// fail would prove nothing.
#include <cctype>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_layouts.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"

namespace vlab::bridge::protocol_doc_test {
namespace {

const std::string kPage = "docs/protocol.md";
const std::string kEllipsis = "\xE2\x80\xA6";  // …
const std::string kMinus = "\xE2\x88\x92";     // −
const std::string kDash = "\xE2\x80\x93";      // –

std::string ReadPage() {
  std::ifstream in(std::string(VLAB_SOURCE_DIR) + "/" + kPage);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(' '), e = s.find_last_not_of(' ');
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

// the cells of a markdown table row "| a | b | c |"
std::vector<std::string> Cells(const std::string& row) {
  std::vector<std::string> cells;
  std::string inner = Trim(row);
  if (inner.size() < 2 || inner.front() != '|' || inner.back() != '|') return cells;
  inner = inner.substr(1, inner.size() - 2);
  std::istringstream in(inner);
  for (std::string cell; std::getline(in, cell, '|');) cells.push_back(Trim(cell));
  return cells;
}

std::string Letter(FieldGroup group) { return group == FieldGroup::kPerJoint ? "n" : "m"; }

// c * letter + d as the page writes it: "0", "3", "n", "n+1", "2n", "m−1"
std::string Linear(int c, int d, const std::string& letter) {
  if (c == 0) return std::to_string(d);
  std::string s = (c == 1 ? "" : std::to_string(c)) + letter;
  if (d > 0) s += "+" + std::to_string(d);
  if (d < 0) s += kMinus + std::to_string(-d);
  return s;
}

// the heading's count: "8", "1 + 3n", "m"
std::string CountText(FieldList fields) {
  int singles = 0, groups = 0;
  std::string letter;
  for (const LayoutField& f : fields) {
    if (f.group == FieldGroup::kOne) {
      ++singles;
    } else {
      ++groups;
      letter = Letter(f.group);
    }
  }
  if (groups == 0) return std::to_string(singles);
  return (singles > 0 ? std::to_string(singles) + " + " : "") + (groups > 1 ? std::to_string(groups) : "") + letter;
}

std::string GroupLabel(const LayoutField& f) {
  const std::string l = Letter(f.group);
  return std::string(f.name) + "_1 " + kEllipsis + " " + f.name + "_" + l;
}

std::string Describe(const LayoutField& f) {
  return f.group == FieldGroup::kOne ? "'" + std::string(f.name) + "'" : "'" + GroupLabel(f) + "'";
}

/// One field as the page has it.
struct PageField {
  std::string name;
  FieldGroup group = FieldGroup::kOne;
  std::string unit;   // "" for "–"
  std::string index;  // the row's index cell
  int row = 0;        // position of the field in its row
  int line = 0;
};

class PageChecker {
 public:
  explicit PageChecker(const std::string& text) : lines_(Lines(text)) {}

  std::vector<std::string> Check() {
    CheckSections();
    CheckKindCodes();
    return problems_;
  }

 private:
  void Problem(int line, const std::string& what) {
    problems_.push_back(kPage + ":" + std::to_string(line) + ": " + what);
  }

  void CheckSections() {
    static const std::regex heading(R"(^### (\S+) (state|command|payload) \(kind (\d+), type (\d+)\): (.+) values$)");
    std::vector<int> seen(3 * (kMaxDeviceKind + 1), 0);  // line of each kind's state / command / payload section
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      const std::string& line = lines_[i];
      if (line.rfind("### ", 0) != 0 || line.find("(kind ") == std::string::npos) continue;
      const int at = static_cast<int>(i) + 1;
      std::smatch m;
      if (!std::regex_match(line, m, heading)) {
        Problem(at, "heading not of the form '### <Kind> state|command|payload (kind N, type T): <count> values'");
        continue;
      }
      const std::string label = m[1], which = m[2];
      const bool command = which == "command", payload = which == "payload";
      const int type = payload ? static_cast<int>(MessageType::kPayload) : command ? 2 : 1;
      const KindLayout* k = FindKindLayout(Lower(label));
      const std::string section = label + " " + which;
      if (k == nullptr) {
        Problem(at, section + ": no device kind is called '" + Lower(label) + "'");
        continue;
      }
      if (std::stoi(m[3]) != static_cast<int>(k->kind)) {
        Problem(at, section + ": kind " + std::string(m[3]) + ", the code says " +
                        std::to_string(static_cast<int>(k->kind)));
      }
      if (std::stoi(m[4]) != type) {
        Problem(at, section + ": type " + std::string(m[4]) + ", a " + which + " is type " + std::to_string(type));
      }
      int& first = seen[3 * static_cast<int>(k->kind) + (payload ? 2 : command ? 1 : 0)];
      if (first != 0) Problem(at, section + ": a second section (the first is at line " + std::to_string(first) + ")");
      first = at;
      if (payload && k->kind != DeviceKind::kArm) {
        Problem(at, section + ": only an arm takes a payload");
        continue;
      }
      const FieldList fields = payload ? kArmPayloadLayout : command ? k->command : k->state;
      if (!k->float64) {
        Problem(at, section + ": " + k->name + " has no float64 layout (" + k->note + ")");
        continue;
      }
      if (fields.empty()) {
        Problem(at, section + ": the code's " + k->name + " takes no " + which + "s");
        continue;
      }
      if (m[5] != CountText(fields)) {
        Problem(at, section + ": '" + std::string(m[5]) + " values', the code has " + CountText(fields) + " values");
      }
      CheckTable(section, i + 1, fields);
    }
    for (const KindLayout& k : kKindLayouts) {
      if (!k.float64) continue;
      if (seen[3 * static_cast<int>(k.kind)] == 0) Problem(0, std::string(k.name) + ": no state section");
      const bool has_command = seen[3 * static_cast<int>(k.kind) + 1] != 0;
      if (!k.command.empty() && !has_command) Problem(0, std::string(k.name) + ": no command section");
      const bool has_payload = seen[3 * static_cast<int>(k.kind) + 2] != 0;
      if (k.kind == DeviceKind::kArm && !has_payload) Problem(0, "arm: no payload section");
    }
  }

  // the first table after the heading at lines_[from - 1], up to the next heading
  void CheckTable(const std::string& section, std::size_t from, FieldList fields) {
    std::size_t i = from;
    while (i < lines_.size() && lines_[i].rfind("#", 0) != 0 && lines_[i].rfind("|", 0) != 0) ++i;
    if (i >= lines_.size() || lines_[i].rfind("|", 0) != 0) {
      Problem(static_cast<int>(from), section + ": no table");
      return;
    }
    if (Cells(lines_[i]) != std::vector<std::string>{"payload index", "field", "unit"}) {
      Problem(static_cast<int>(i) + 1, section + ": the table's columns are not 'payload index | field | unit'");
      return;
    }
    std::vector<PageField> page;
    for (i += 2; i < lines_.size() && lines_[i].rfind("|", 0) == 0; ++i) ReadRow(section, i, &page);
    Compare(section, static_cast<int>(from), fields, page);
  }

  void ReadRow(const std::string& section, std::size_t i, std::vector<PageField>* page) {
    static const std::regex group(R"(^([A-Za-z][A-Za-z0-9_]*)_1 \xE2\x80\xA6 \1_([nm])$)");
    static const std::regex single(R"(^[A-Za-z][A-Za-z0-9_]*$)");
    const int at = static_cast<int>(i) + 1;
    const std::vector<std::string> cells = Cells(lines_[i]);
    if (cells.size() != 3) {
      Problem(at, section + ": a row without 3 cells");
      return;
    }
    const std::string names = cells[1].substr(0, cells[1].find(':'));
    std::istringstream in(names);
    int position = 0;
    for (std::string label; std::getline(in, label, ',');) {
      label = Trim(label);
      PageField f;
      std::smatch m;
      if (std::regex_match(label, m, group)) {
        f.name = m[1];
        f.group = m[2] == "n" ? FieldGroup::kPerJoint : FieldGroup::kPerSensorValue;
      } else if (std::regex_match(label, single)) {
        f.name = label;
      } else {
        Problem(at, section + ": cannot read the field label '" + label + "'");
        continue;
      }
      f.unit = cells[2] == kDash ? "" : cells[2];
      f.index = cells[0];
      f.row = position++;
      f.line = at;
      page->push_back(f);
    }
  }

  void Compare(const std::string& section, int heading, FieldList fields, const std::vector<PageField>& page) {
    if (page.size() != fields.size) {
      Problem(heading, section + ": the table has " + std::to_string(page.size()) + " fields, the code " +
                           std::to_string(fields.size));
    }
    int groups = 0, singles = 0;  // values before the field: groups * n + singles
    std::string row_index;        // the index cell the current row should have
    for (std::size_t f = 0; f < fields.size && f < page.size(); ++f) {
      const LayoutField& want = fields[f];
      const PageField& have = page[f];
      const std::string field = section + ": field " + std::to_string(f + 1);
      if (have.name != want.name || have.group != want.group) {
        const std::string label = have.group == FieldGroup::kOne
                                      ? have.name
                                      : have.name + "_1 " + kEllipsis + " " + have.name + "_" + Letter(have.group);
        Problem(have.line, field + " is '" + label + "', the code says " + Describe(want));
      }
      if (have.unit != want.unit) {
        Problem(have.line,
                field + " (" + want.name + ") has unit '" + have.unit + "', the code says '" + want.unit + "'");
      }
      const std::string letter = want.group == FieldGroup::kOne ? "n" : Letter(want.group);
      const std::string at = Linear(groups, singles, letter);
      if (want.group != FieldGroup::kOne) {
        if (have.row != 0 || (f + 1 < page.size() && page[f + 1].line == have.line)) {
          Problem(have.line, field + " (" + want.name + "): a group has a row of its own");
        }
        row_index = at + " " + kEllipsis + " " + Linear(groups + 1, singles - 1, letter);
        ++groups;
      } else {
        row_index = have.row == 0 ? at : row_index + ", " + at;
        ++singles;
      }
      const bool row_ends = f + 1 >= page.size() || page[f + 1].line != have.line;
      if (row_ends && have.index != row_index) {
        Problem(have.line,
                section + ": payload index '" + have.index + "', the code's fields are at '" + row_index + "'");
      }
    }
  }

  // "## Devices and ports": | kind | code | ... |, every kind once, in order
  void CheckKindCodes() {
    std::size_t i = 0;
    while (i < lines_.size() && lines_[i] != "## Devices and ports") ++i;
    while (i < lines_.size() && lines_[i].rfind("|", 0) != 0) ++i;
    if (i >= lines_.size() || Cells(lines_[i]).size() < 2 || Cells(lines_[i])[0] != "kind" ||
        Cells(lines_[i])[1] != "code") {
      Problem(0, "Devices and ports: no table with columns 'kind | code | ...'");
      return;
    }
    int expected = 1;
    for (i += 2; i < lines_.size() && lines_[i].rfind("|", 0) == 0; ++i, ++expected) {
      const std::vector<std::string> cells = Cells(lines_[i]);
      const int at = static_cast<int>(i) + 1;
      const std::string want = KindName(expected);
      if (cells.size() < 2 || cells[0] != want || cells[1] != std::to_string(expected)) {
        Problem(at, "Devices and ports: row " + std::to_string(expected) + " is '" +
                        (cells.size() >= 2 ? cells[0] + " | " + cells[1] : lines_[i]) + "', the code says '" + want +
                        " | " + std::to_string(expected) + "'");
      }
    }
    if (expected != kMaxDeviceKind + 1) {
      Problem(static_cast<int>(i), "Devices and ports: " + std::to_string(expected - 1) + " kinds, the code has " +
                                       std::to_string(kMaxDeviceKind));
    }
  }

  static std::string Lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  }

  std::vector<std::string> lines_;
  std::vector<std::string> problems_;
};

std::string Joined(const std::vector<std::string>& problems) {
  std::string out;
  for (const std::string& p : problems) out += p + "\n";
  return out;
}

TEST(ProtocolDocTest, ThePageAgreesWithTheTable) {
  const std::string page = ReadPage();
  ASSERT_FALSE(page.empty()) << "cannot read " << VLAB_SOURCE_DIR << "/" << kPage;
  const std::vector<std::string> problems = PageChecker(page).Check();
  EXPECT_TRUE(problems.empty()) << Joined(problems);
}

/// One mistake put into the page, and what the checker must say about it.
struct Mistake {
  const char* what;
  std::string from, to;
  std::vector<std::string> reported;  // substrings of one problem
};

TEST(ProtocolDocTest, EachMistakeInThePageIsReported) {
  const std::string page = ReadPage();
  const std::string e = kEllipsis;
  const std::vector<Mistake> mistakes = {
      {"a renamed field",
       "| 4 | grasped: ",
       "| 4 | grasp: ",
       {"Gripper state: field 5 is 'grasp', the code says 'grasped'"}},
      {"two fields swapped",
       "| 4, 5 | vx, vy: measured velocity",
       "| 4, 5 | vy, vx: measured velocity",
       {"Base state: field 5 is 'vy', the code says 'vx'"}},
      {"a wrong unit",
       "| 6 | wz: measured yaw rate | rad/s |",
       "| 6 | wz: measured yaw rate | deg/s |",
       {"Base state: field 7 (wz) has unit 'deg/s', the code says 'rad/s'"}},
      {"a pure number given a unit",
       "else 0 | " + kDash + " |\n\n### Pose",
       "else 0 | px |\n\n### Pose",
       {"Gaze state: field 4 (visible) has unit 'px', the code says ''"}},
      {"a renamed per-joint group",
       "tau_1 " + e + " tau_n",
       "torque_1 " + e + " torque_n",
       {"Arm state: field 4 is 'torque_1 " + e + " torque_n', the code says 'tau_1 " + e + " tau_n'"}},
      {"a group written as one value",
       "| 1 " + e + " n | value_1 " + e + " value_n:",
       "| 1 " + e + " n | value:",
       {"Arm command: field 2 is 'value', the code says 'value_1 " + e + " value_n'"}},
      {"a wrong count",
       "### Wrench state (kind 2, type 1): 8 values",
       "### Wrench state (kind 2, type 1): 9 values",
       {"Wrench state: '9 values', the code has 8 values"}},
      {"a wrong kind code",
       "### Pose state (kind 13, type 1)",
       "### Pose state (kind 12, type 1)",
       {"Pose state: kind 12, the code says 13"}},
      {"a missing row",
       "| 6 | spin: spin rate about the axle (signed) | rad/s |\n",
       "",
       {"Yoyo state: the table has 6 fields, the code 7"}},
      {"a wrong payload index",
       "| 5 | string_force:",
       "| 6 | string_force:",
       {"Yoyo state: payload index '6', the code's fields are at '5'"}},
      {"a missing section",
       "### Point command (kind 10, type 2): 3 values",
       "### Point order: 3 values",
       {"point: no command section"}},
      {"a command for an output-only kind",
       "### Gaze state (kind 12, type 1)",
       "### Gaze command (kind 12, type 2)",
       {"Gaze command: the code's gaze takes no commands"}},
      {"two payload fields swapped",
       "| 7, 8, 9 | ixy, ixz, iyz:",
       "| 7, 8, 9 | ixy, iyz, ixz:",
       {"Arm payload: field 9 is 'iyz', the code says 'ixz'"}},
      {"a payload unit changed",
       "| 0 | mass: mass of the load, \xE2\x89\xA5 0 (0: none) | kg |",
       "| 0 | mass: mass of the load, \xE2\x89\xA5 0 (0: none) | g |",
       {"Arm payload: field 1 (mass) has unit 'g', the code says 'kg'"}},
      {"a payload for another kind",
       "### Arm payload (kind 1, type 6)",
       "### Base payload (kind 6, type 6)",
       {"Base payload: only an arm takes a payload"}},
      {"a wrong code in the kinds table",
       "| gaze | 12 |",
       "| gaze | 14 |",
       {"Devices and ports: row 12 is 'gaze | 14', the code says 'gaze | 12'"}},
  };
  for (const Mistake& m : mistakes) {
    const std::size_t at = page.find(m.from);
    ASSERT_NE(at, std::string::npos) << m.what << ": the page no longer has '" << m.from << "'";
    ASSERT_EQ(page.find(m.from, at + 1), std::string::npos) << m.what << ": '" << m.from << "' twice";
    std::string wrong = page;
    wrong.replace(at, m.from.size(), m.to);
    const std::vector<std::string> problems = PageChecker(wrong).Check();
    bool found = false;
    for (const std::string& p : problems) {
      bool all = true;
      for (const std::string& part : m.reported) all = all && p.find(part) != std::string::npos;
      found = found || all;
    }
    EXPECT_TRUE(found) << m.what << ": not reported as '" << m.reported[0] << "'; the checker said:\n"
                       << Joined(problems);
  }
}

// the page's hex examples (fenced blocks of hex digits only), in page order
std::vector<std::string> HexBlocks(const std::string& page) {
  std::vector<std::string> blocks;
  std::string block;
  bool in = false, hex = true;
  for (const std::string& line : Lines(page)) {
    if (line.rfind("```", 0) == 0) {
      if (in && hex && !block.empty()) blocks.push_back(block);
      in = !in;
      block.clear();
      hex = true;
      continue;
    }
    if (!in) continue;
    for (char c : line) {
      if (std::isxdigit(static_cast<unsigned char>(c))) {
        block += c;
      } else if (c != ' ') {
        hex = false;
      }
    }
  }
  return blocks;
}

std::string Hex(const std::vector<unsigned char>& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (unsigned char b : bytes) {
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

TEST(ProtocolDocTest, TheHexExamplesAreWhatTheEncodersWrite) {
  const std::vector<std::string> blocks = HexBlocks(ReadPage());
  ASSERT_EQ(blocks.size(), 2u) << "the page's worked examples: an arm command and a subscribe request";
  std::vector<unsigned char> bytes;
  ArmCommandMsg m;  // "A worked example": velocity, answering state 42 at client time 1.5 s
  m.mode = 2;
  m.value = {0.5, -0.25, 0.125, 0, 1, -1, 0.0625};
  EncodeArmCommand(42, 1.5, m, &bytes);
  EXPECT_EQ(blocks[0], Hex(bytes));
  EncodeSubscribeRequest(DeviceKind::kArm, 4503599627370497.0, 1, &bytes);  // cookie 2^52 + 1
  EXPECT_EQ(blocks[1], Hex(bytes));
}

}  // namespace
}  // namespace vlab::bridge::protocol_doc_test
