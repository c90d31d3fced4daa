// lab_run_record.h: a run's record says what changed, field by field, and its
// hash differs when any field does.
#include "lab/outputs/lab_run_record.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

namespace vlab::lab::run_record_test {
namespace {

RunRecord Base() { return {"0.1.0", "scene: a.xml\nduration: 1\n", 3, 2.5}; }

TEST(RunRecordTest, TheSameRecordIsCurrentAndEachChangeIsNamed) {
  const RunRecord want = Base();
  const nlohmann::json summary = {{"record", RecordJson(want)}};
  EXPECT_EQ(RecordChange(summary, want), "");

  RunRecord other = want;
  other.vlab = "0.0.9";
  EXPECT_EQ(RecordChange({{"record", RecordJson(other)}}, want), "vlab changed since it ran (0.0.9 -> 0.1.0)");
  other = want;
  other.scenario_yaml += "seed: 4\n";
  EXPECT_EQ(RecordChange({{"record", RecordJson(other)}}, want), "the scenario changed since it ran");
  other = want;
  other.seed = 4;
  EXPECT_EQ(RecordChange({{"record", RecordJson(other)}}, want), "the seed changed since it ran (4 -> 3)");
  other = want;
  other.duration_s = 3;
  EXPECT_EQ(RecordChange({{"record", RecordJson(other)}}, want), "the duration changed since it ran (3 s -> 2.5 s)");
  // the fields agree but the hash was edited: not trusted
  nlohmann::json forged = {{"record", RecordJson(want)}};
  forged["record"]["hash"] = "fnv1a64:0000000000000000";
  EXPECT_EQ(RecordChange(forged, want), "its record's hash does not match");
  EXPECT_EQ(RecordChange(nlohmann::json::object(), want), "it has no record of what it ran (written by an older vlab)");
  EXPECT_EQ(RecordChange({{"record", "x"}}, want), "it has no record of what it ran (written by an older vlab)");
}

TEST(RunRecordTest, TheHashDiffersWhenAnyFieldDoes) {
  std::set<std::string> hashes;
  RunRecord r = Base();
  hashes.insert(RecordHash(r));
  r.vlab = "0.1.1";
  hashes.insert(RecordHash(r));
  r.seed = 4;
  hashes.insert(RecordHash(r));
  r.duration_s = 2.5000000000000004;  // the next double: still a change
  hashes.insert(RecordHash(r));
  r.scenario_yaml += " ";
  hashes.insert(RecordHash(r));
  // moving bytes from one field to the next is a change too (lengths are hashed)
  RunRecord a = Base(), b = Base();
  a.vlab = "0.1.03";
  b.vlab = "0.1.0";
  b.seed = 33;
  a.seed = 3;
  hashes.insert(RecordHash(a));
  hashes.insert(RecordHash(b));
  EXPECT_EQ(hashes.size(), 7u);
  EXPECT_EQ(RecordHash(Base()).size(), 8u + 16u);
}

}  // namespace
}  // namespace vlab::lab::run_record_test
