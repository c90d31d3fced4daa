// lab_sweep_text.h: every value a sweep file can hold reaches `vlab run --set`
// as one line of printable YAML that reads back as the same value, and a job
// line never carries a control character.
#include "lab/sweep/lab_sweep_text.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/core_errors.h"

namespace vlab::lab::sweep_text_test {
namespace {

// the strings a hostile sweep file would try: every control byte alone and
// inside text, quotes, command substitution, backquotes, a planted command
std::vector<std::string> HostileStrings() {
  std::vector<std::string> all;
  for (int c = 1; c < 0x20; ++c) all.push_back("a" + std::string(1, static_cast<char>(c)) + "b");
  all.push_back(
      "a\x7f"
      "b");
  all.push_back("\n");
  all.push_back("x\ntouch CANARY\n");
  all.push_back("it's \"quoted\"");
  all.push_back("$(touch CANARY)");
  all.push_back("`touch CANARY`");
  all.push_back("\\x41 \\n \\");  // backslashes that look like escapes
  all.push_back("a: b, [c] {d} #e &f *g !h |i >j %k @l");
  all.push_back("");
  return all;
}

bool Printable7Bit(const std::string& text) {
  for (char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  }
  return true;
}

TEST(SweepTextTest, EveryHostileStringReadsBackAsItselfFromOneLine) {
  for (const std::string& s : HostileStrings()) {
    const std::string text = ValueText(YAML::Node(s), "f:1: k");
    EXPECT_TRUE(Printable7Bit(text)) << text;
    EXPECT_EQ(YAML::Load(text).as<std::string>(), s) << text;
  }
}

TEST(SweepTextTest, CollectionsWithControlCharactersReadBackAsTheSameNodes) {
  const YAML::Node node = YAML::Load("[1, -2.5e3, \"a\\nb\", {k: \"\\t\\x7f\", 'q r': [x, ~]}, '-', '10']");
  const std::string text = ValueText(node, "f:1: k");
  EXPECT_TRUE(Printable7Bit(text)) << text;
  EXPECT_EQ(text, "[1, -2.5e3, \"a\\x0ab\", {k: \"\\x09\\x7f\", \"q r\": [x, ~]}, \"-\", \"10\"]");
  const YAML::Node back = YAML::Load(text);
  EXPECT_EQ(back[2].as<std::string>(), "a\nb");
  EXPECT_EQ(back[3]["k"].as<std::string>(), "\t\x7f");
  EXPECT_TRUE(back[3]["q r"][1].IsNull());
  EXPECT_EQ(back[4].as<std::string>(), "-");
}

TEST(SweepTextTest, PlainValuesAreWrittenAsBefore) {
  EXPECT_EQ(ValueText(YAML::Load("10"), "w"), "10");
  EXPECT_EQ(ValueText(YAML::Load("0.50"), "w"), "0.50");
  EXPECT_EQ(ValueText(YAML::Load("[0, 0.5, 1]"), "w"), "[0, 0.5, 1]");
  EXPECT_EQ(ValueText(YAML::Load("{bandwidth_hz: 8, damping_ratio: 0.9}"), "w"),
            "{bandwidth_hz: 8, damping_ratio: 0.9}");
  // a string YAML would read as something else is quoted (it used to be written bare)
  EXPECT_EQ(YAML::Load(ValueText(YAML::Load("'a: b'"), "w")).as<std::string>(), "a: b");
}

TEST(SweepTextTest, AValueTooLongForOneArgumentIsRefusedNamingWhere) {
  // an alias bomb: 10 levels of 10 aliases stand for 10^10 scalars; stopped at the limit
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i <= 10; ++i) {
    const std::string p = "*a" + std::to_string(i - 1);
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [" + p + ", " + p + ", " + p + ", " + p + ", " +
            p + ", " + p + ", " + p + ", " + p + ", " + p + ", " + p + "]\n";
  }
  const YAML::Node node = YAML::Load(bomb)["a10"];
  try {
    ValueText(node, "s.yaml:11: grid.k[0]");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "s.yaml:11: grid.k[0]: the value is longer than 100000 bytes as text (one command line argument holds "
              "at most 131072)");
  }
}

TEST(SweepTextTest, ShellQuoteLeavesPlainWordsAndQuotesTheRest) {
  EXPECT_EQ(ShellQuote("controller.gains.position=10"), "controller.gains.position=10");
  EXPECT_EQ(ShellQuote("a=[1, 2]"), "'a=[1, 2]'");
  EXPECT_EQ(ShellQuote("it's"), "'it'\\''s'");
  EXPECT_EQ(ShellQuote("$(x) `y` \"z\""), "'$(x) `y` \"z\"'");
  EXPECT_EQ(ShellQuote(""), "''");
}

TEST(SweepTextTest, AJobLineRefusesAWordWithAControlCharacter) {
  EXPECT_EQ(JobLine({"/opt/vlab", "run", "k=\"a\\x0ab\""}), "/opt/vlab run 'k=\"a\\x0ab\"'");
  try {
    JobLine({"/opt/vlab", "--out", "/data/a\nb"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'/data/a\\x0ab': holds a control character"), std::string::npos) << e.what();
  }
  for (int c : {0x01, 0x09, 0x0d, 0x1b, 0x1f, 0x7f}) {
    EXPECT_THROW(JobLine({"vlab", std::string("x") + static_cast<char>(c)}), InputError) << c;
  }
}

}  // namespace
}  // namespace vlab::lab::sweep_text_test
