// CheckYamlText (lab_yaml_check.h) and the input-file reader (core_input_file.h):
// duplicate keys with both lines, the expanded-node bound counted exactly, cycles,
// depth, UTF-8 with line and column, and files that are not regular.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <string>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "lab/scenario/lab_yaml.h"
#include "lab/scenario/lab_yaml_check.h"
#include "test_util.h"

namespace vlab::lab::yaml_check_test {
namespace {

using vlab::testing::TempDir;
using vlab::testing::WriteFile;

std::string ErrorOf(const std::string& text, bool lines = true) {
  try {
    CheckYamlText("f.yaml", text, lines);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// a flow list of `n` scalars: n + 1 nodes
std::string FlatList(std::size_t n) {
  std::string text = "[";
  for (std::size_t i = 0; i < n; ++i) text += i ? ",x" : "x";
  return text + "]";
}

TEST(YamlCheck, DuplicateKeysNameBothLines) {
  EXPECT_EQ(ErrorOf("a: 1\nb: 2\na: 3\n"), "f.yaml:3: a: duplicate key (first at line 1)");
  EXPECT_EQ(ErrorOf("x:\n  y: {c: 1, c: 2}\n"), "f.yaml:2: x.y.c: duplicate key (first at line 2)");
  EXPECT_EQ(ErrorOf("l:\n  - n: 1\n    n: 2\n"), "f.yaml:3: l[0].n: duplicate key (first at line 2)");
  EXPECT_EQ(ErrorOf("{a: 1, 'a': 2}", false), "f.yaml: a: duplicate key (first at column 2)");
  // the same key in two mappings is no repeat
  EXPECT_EQ(ErrorOf("l: [{n: 1}, {n: 2}]\nm: {n: 3}\n"), "");
}

TEST(YamlCheck, ExpandedNodesAreBoundedExactly) {
  EXPECT_EQ(ErrorOf(FlatList(kMaxYamlNodes - 1)), "");  // the list and its items: the bound
  EXPECT_NE(ErrorOf(FlatList(kMaxYamlNodes)).find("expands to more than 100000 nodes"), std::string::npos);
  // an alias counts what it names each time: 1001 nodes named 100 times
  const std::string a = "a: &a " + FlatList(1000) + "\n";
  std::string uses = "b: [*a";
  for (int i = 1; i < 100; ++i) uses += ", *a";
  EXPECT_EQ(ErrorOf(a + uses + "]\n"),
            "f.yaml:2: b[98]: the document expands to more than 100000 nodes (each "
            "alias counts the nodes it names; an alias bomb?)");
  EXPECT_EQ(ErrorOf(a + "b: [*a, *a]\n"), "");
}

TEST(YamlCheck, CyclesDepthAndDocuments) {
  EXPECT_EQ(ErrorOf("a: &a [1, *a]\n"), "f.yaml:1: a[1]: an alias inside the node it names (a cycle)");
  EXPECT_EQ(ErrorOf(std::string(kMaxYamlDepth, '[') + std::string(kMaxYamlDepth, ']')), "");
  EXPECT_NE(
      ErrorOf(std::string(kMaxYamlDepth + 1, '[') + std::string(kMaxYamlDepth + 1, ']')).find("nested more than 64"),
      std::string::npos);
  EXPECT_EQ(ErrorOf("a: 1\n---\na: 2\n"), "f.yaml:2: a second YAML document ('---'); a file holds one");
  EXPECT_EQ(ErrorOf("a: [1\n").find("f.yaml:2: malformed YAML"), 0u);
}

TEST(InputFile, Utf8IsCheckedWithLineAndColumn) {
  EXPECT_EQ(FirstNonUtf8("plain \xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80"), std::string::npos);
  EXPECT_EQ(FirstNonUtf8("ab\xc0\xaf"), 2u);          // overlong '/'
  EXPECT_EQ(FirstNonUtf8("ab\xed\xa0\x80"), 2u);      // a surrogate
  EXPECT_EQ(FirstNonUtf8("ab\xf4\x90\x80\x80"), 2u);  // past U+10FFFF
  EXPECT_EQ(FirstNonUtf8("ab\xe2\x82"), 2u);          // cut short
  try {
    CheckUtf8("f.yaml", "a: 1\nb: caf\xe9\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "f.yaml:2:7: byte 0xE9 is not UTF-8 (input text must be UTF-8)");
  }
}

TEST(InputFile, OnlyRegularFilesUpToTheCap) {
  TempDir tmp;
  auto error = [](const std::string& path, std::size_t cap) {
    try {
      ReadInputFile(path, "'" + path + "'", cap);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  WriteFile(tmp / "ten", "0123456789");
  EXPECT_EQ(ReadInputFile(tmp / "ten", "ten", 10), "0123456789");
  EXPECT_EQ(error(tmp / "ten", 9),
            "'" + (tmp / "ten") + "': 10 bytes, over the 9 bytes an input file of this kind may have");
  ASSERT_EQ(::mkfifo((tmp / "fifo").c_str(), 0644), 0);
  EXPECT_EQ(error(tmp / "fifo", 10), "'" + (tmp / "fifo") + "': a FIFO (named pipe), not a regular file");
  EXPECT_EQ(error("/dev/zero", 10), "'/dev/zero': a character device, not a regular file");
  EXPECT_EQ(error(tmp.path(), 10), "'" + tmp.path() + "': a folder, not a regular file");
  EXPECT_EQ(error(tmp / "none", 10), "'" + (tmp / "none") + "': cannot open file (No such file or directory)");
}

TEST(YamlSeed, TheWholeRangeAndNothingElse) {
  unsigned long long seed = 0;
  EXPECT_TRUE(ParseSeed("0", &seed));
  EXPECT_EQ(seed, 0u);
  EXPECT_TRUE(ParseSeed("9007199254740992", &seed));
  EXPECT_EQ(seed, kMaxSeed);
  for (const char* bad : {"9007199254740993", "99999999999999999999999", "-1", "+1", "1.0", "1e3", "0x10", "", " 1"}) {
    EXPECT_FALSE(ParseSeed(bad, &seed)) << bad;
  }
  std::string text = "007";
  EXPECT_EQ(CheckSeedText(text), "");
  EXPECT_EQ(text, "7");  // not octal
}

}  // namespace
}  // namespace vlab::lab::yaml_check_test
