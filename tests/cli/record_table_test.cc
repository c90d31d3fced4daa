// vlab record's table (src/cli/cli_record_table.h) in process: what it counts for a device.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_record_table.h"

namespace vlab::cli::record::record_table_test {
namespace {

// A device at 10 Hz recorded for 1 s of its stamps: 11 states, seq 0 .. 10, written; the state
// after the end (seq 11), which a recorder takes as it stops, is not written and is not the
// record's last state, but the next state must still come after it.
TEST(RecordTable, AStatePastTheEndIsNeitherWrittenNorTheLastState) {
  RecordTable table({1}, 1.0);
  for (std::int64_t seq = 0; seq <= 10; ++seq) {
    const double value = static_cast<double>(seq);
    EXPECT_TRUE(table.Add(0, seq, 0.1 * static_cast<double>(seq), &value)) << seq;
  }
  EXPECT_TRUE(table.Done());
  const double past = 11;
  EXPECT_FALSE(table.Add(0, 11, 1.1, &past));
  std::vector<double> stamps;
  table.Drain(true, [&stamps](const double* row) { stamps.push_back(row[0]); });
  const DeviceCounts& c = table.counts(0);
  EXPECT_EQ(c.states, 11);
  EXPECT_EQ(c.lost, 0);
  EXPECT_EQ(c.refused, 0);
  EXPECT_EQ(c.first_seq, 0);
  EXPECT_EQ(c.last_seq, 10);
  EXPECT_EQ(c.last_seq - c.first_seq + 1, c.states);
  EXPECT_DOUBLE_EQ(c.last_stamp, 1.0);
  EXPECT_EQ(table.rows(), 11);
  ASSERT_EQ(stamps.size(), 11u);
  EXPECT_DOUBLE_EQ(stamps.back(), 1.0);
  // seq 11 was taken: a replay of it is refused
  EXPECT_FALSE(table.Add(0, 11, 1.1, &past));
  EXPECT_EQ(table.counts(0).refused, 1);
}

}  // namespace
}  // namespace vlab::cli::record::record_table_test
