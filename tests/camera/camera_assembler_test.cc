// Tests bridge/bridge_camera_assembler.cc: frames complete whatever the chunk
// order, duplicates and late chunks are ignored, an incomplete frame is
// dropped (newer frame, timeout, eviction) and later frames still arrive, and
// no frame is ever returned torn.
#include "bridge/bridge_camera_assembler.h"

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_protocol.h"
#include "camera_test_util.h"

namespace vlab::bridge::camera_assembler_test {
namespace {

using testing::Chunks;
using testing::FirstPatternMismatch;
using testing::PatternFrame;
using Result = FrameAssembler::Result;
using Datagram = std::vector<unsigned char>;

constexpr int kW = 16, kH = 10;  // 480 bytes: 5 chunks of 100 bytes
constexpr std::size_t kChunk = 100;

Result Add(FrameAssembler& a, const Datagram& d, double now_s = 0, ChunkError* e = nullptr) {
  return a.Add(d.data(), d.size(), now_s, e);
}

std::vector<Datagram> FrameChunks(std::int64_t id) { return Chunks(PatternFrame(id, kW, kH), kChunk); }

// takes the ready frame and checks it is frame `id`, whole and untorn
void ExpectFrame(FrameAssembler& a, std::int64_t id) {
  CameraFrame f;
  ASSERT_TRUE(a.Take(&f));
  EXPECT_EQ(f.id, id);
  EXPECT_EQ(f.width, kW);
  EXPECT_EQ(f.height, kH);
  EXPECT_EQ(f.time_s, static_cast<double>(id) / 30.0);
  ASSERT_EQ(f.data.size(), 3u * kW * kH);
  EXPECT_EQ(FirstPatternMismatch(id, f.data), -1);
}

TEST(FrameAssemblerTest, InOrderChunksMakeAWholeFrame) {
  FrameAssembler a;
  const auto chunks = FrameChunks(3);
  ASSERT_EQ(chunks.size(), 5u);
  for (std::size_t i = 0; i + 1 < chunks.size(); ++i) {
    EXPECT_EQ(Add(a, chunks[i]), Result::kAccepted);
    EXPECT_FALSE(a.ready());
  }
  EXPECT_EQ(Add(a, chunks.back()), Result::kCompleted);
  ExpectFrame(a, 3);
  EXPECT_FALSE(a.ready());
  EXPECT_EQ(a.counters().frames_completed, 1);
  EXPECT_EQ(a.counters().accepted, 5);
}

TEST(FrameAssemblerTest, AnyChunkOrderAndDuplicates) {
  FrameAssembler a;
  auto chunks = FrameChunks(1);
  std::mt19937 rng(7);
  std::shuffle(chunks.begin(), chunks.end(), rng);
  EXPECT_EQ(Add(a, chunks[0]), Result::kAccepted);
  EXPECT_EQ(Add(a, chunks[0]), Result::kDuplicate);
  for (std::size_t i = 1; i + 1 < chunks.size(); ++i) Add(a, chunks[i]);
  EXPECT_EQ(Add(a, chunks[1]), Result::kDuplicate);
  EXPECT_EQ(Add(a, chunks.back()), Result::kCompleted);
  ExpectFrame(a, 1);
  EXPECT_EQ(a.counters().duplicates, 2);
  // a repeat of a delivered frame's chunk is late, not a new frame
  EXPECT_EQ(Add(a, chunks[2]), Result::kLate);
  EXPECT_FALSE(a.ready());
}

TEST(FrameAssemblerTest, LostChunkDropsTheFrameAndLaterFramesArrive) {
  FrameAssembler a;
  const auto f1 = FrameChunks(1);
  for (std::size_t i = 0; i < f1.size(); ++i) {
    if (i != 2) Add(a, f1[i]);  // chunk 2 lost
  }
  EXPECT_FALSE(a.ready());
  EXPECT_EQ(a.in_progress(), 1);
  for (const Datagram& d : FrameChunks(2)) Add(a, d);
  ExpectFrame(a, 2);
  EXPECT_EQ(a.in_progress(), 0);
  EXPECT_EQ(a.counters().dropped_superseded, 1);
  EXPECT_EQ(a.counters().frames_dropped, 1);
  // the lost chunk turns up after all: too late, frame 1 is never shown
  EXPECT_EQ(Add(a, f1[2]), Result::kLate);
  EXPECT_FALSE(a.ready());
  for (const Datagram& d : FrameChunks(3)) Add(a, d);
  ExpectFrame(a, 3);
}

TEST(FrameAssemblerTest, InterleavedFramesBothComplete) {
  FrameAssembler a;
  const auto f1 = FrameChunks(1), f2 = FrameChunks(2);
  for (std::size_t i = 0; i + 1 < f1.size(); ++i) {
    Add(a, f1[i]);
    Add(a, f2[i]);
  }
  EXPECT_EQ(a.in_progress(), 2);
  EXPECT_EQ(Add(a, f1.back()), Result::kCompleted);
  ExpectFrame(a, 1);
  EXPECT_EQ(Add(a, f2.back()), Result::kCompleted);
  ExpectFrame(a, 2);
  EXPECT_EQ(a.counters().frames_dropped, 0);
}

TEST(FrameAssemblerTest, ANewerFrameCompletingFirstDropsTheOlder) {
  FrameAssembler a;
  const auto f1 = FrameChunks(1), f2 = FrameChunks(2);
  for (std::size_t i = 0; i + 1 < f1.size(); ++i) Add(a, f1[i]);
  for (const Datagram& d : f2) Add(a, d);
  ExpectFrame(a, 2);
  EXPECT_EQ(Add(a, f1.back()), Result::kLate);  // reordered behind frame 2: dropped, not shown out of order
  EXPECT_FALSE(a.ready());
}

TEST(FrameAssemblerTest, IncompleteFrameTimesOut) {
  AssemblerConfig config;
  config.timeout_s = 0.5;
  FrameAssembler a(config);
  const auto f1 = FrameChunks(1);
  Add(a, f1[0], 10.0);
  a.Expire(10.4);
  EXPECT_EQ(a.in_progress(), 1);
  a.Expire(10.6);
  EXPECT_EQ(a.in_progress(), 0);
  EXPECT_EQ(a.counters().dropped_timeout, 1);
  EXPECT_EQ(Add(a, f1[1], 10.7), Result::kLate);
  // Add expires too
  const auto f2 = FrameChunks(2);
  Add(a, f2[0], 11.0);
  for (std::size_t i = 1; i < f2.size(); ++i) EXPECT_EQ(Add(a, f2[i], 11.6), Result::kLate) << i;
  EXPECT_EQ(a.counters().dropped_timeout, 2);
}

TEST(FrameAssemblerTest, AllSlotsBusyEvictsTheOldest) {
  AssemblerConfig config;
  config.slots = 2;
  FrameAssembler a(config);
  const auto f1 = FrameChunks(1), f2 = FrameChunks(2), f3 = FrameChunks(3), f0 = FrameChunks(0);
  Add(a, f2[0]);
  Add(a, f3[0]);
  EXPECT_EQ(Add(a, f1[0]), Result::kLate);             // older than all in progress and no room
  for (const Datagram& d : FrameChunks(4)) Add(a, d);  // evicts 2, completes 4, drops 3
  ExpectFrame(a, 4);
  EXPECT_EQ(a.counters().dropped_evicted, 1);
  EXPECT_EQ(a.counters().dropped_superseded, 1);
  EXPECT_EQ(a.in_progress(), 0);
}

TEST(FrameAssemblerTest, InconsistentChunkIsRefusedAndTheFrameNeverCompletes) {
  FrameAssembler a;
  const auto f1 = FrameChunks(1);
  CameraFrame other = PatternFrame(1, kW, kH);
  other.time_s = 99;  // same id, another time
  const auto f1_other = Chunks(other, kChunk);
  Add(a, f1[0]);
  ChunkError e;
  EXPECT_EQ(Add(a, f1_other[1], 0, &e), Result::kRefused);
  EXPECT_EQ(e, ChunkError::kInconsistent);
  CameraFrame bigger = PatternFrame(1, kW, kH);  // same id, another chunk size
  const auto f1_big = Chunks(bigger, 120);
  EXPECT_EQ(Add(a, f1_big[1], 0, &e), Result::kRefused);
  EXPECT_EQ(e, ChunkError::kInconsistent);
  for (std::size_t i = 2; i < f1.size(); ++i) Add(a, f1[i]);
  EXPECT_FALSE(a.ready());  // chunk 1 never came in a consistent form
  EXPECT_EQ(a.counters().refused_by[static_cast<int>(ChunkError::kInconsistent)], 2);
}

TEST(FrameAssemblerTest, RefusesMalformedAndTooLargeChunksByReason) {
  AssemblerConfig config;
  config.max_frame_bytes = 400;
  FrameAssembler a(config);
  Datagram d = FrameChunks(1)[0];
  ChunkError e;
  EXPECT_EQ(Add(a, d, 0, &e), Result::kRefused);
  EXPECT_EQ(e, ChunkError::kTooLarge);
  PutDouble(1, d.data() + 8);  // version 1
  EXPECT_EQ(Add(a, d, 0, &e), Result::kRefused);
  EXPECT_EQ(e, ChunkError::kBadVersion);
  const Datagram json = {'{', '}'};
  EXPECT_EQ(Add(a, json, 0, &e), Result::kRefused);
  EXPECT_EQ(e, ChunkError::kTooShort);
  EXPECT_EQ(a.counters().refused, 3);
  EXPECT_EQ(a.counters().refused_by[static_cast<int>(ChunkError::kTooLarge)], 1);
  EXPECT_EQ(a.counters().refused_by[static_cast<int>(ChunkError::kBadVersion)], 1);
  EXPECT_EQ(a.counters().chunks, 3);
}

TEST(FrameAssemblerTest, RestartedSenderIsFollowed) {
  FrameAssembler a;
  for (const Datagram& d : FrameChunks(1000)) Add(a, d);
  ExpectFrame(a, 1000);
  // far below: a restarted sender (its frames are not late)
  for (const Datagram& d : FrameChunks(0)) Add(a, d);
  ExpectFrame(a, 0);
  EXPECT_EQ(a.counters().restarts, 1);
  // a few frames below, but its time more than restart_time_s earlier: a restart too
  for (const Datagram& d : FrameChunks(50)) Add(a, d);
  ExpectFrame(a, 50);
  CameraFrame early = PatternFrame(48, kW, kH);
  early.time_s = 0;  // 50 / 30 s = 1.67 s before frame 50
  for (const Datagram& d : Chunks(early, kChunk)) Add(a, d);
  CameraFrame f;
  ASSERT_TRUE(a.Take(&f));
  EXPECT_EQ(f.id, 48);
  EXPECT_EQ(a.counters().restarts, 2);
  // but an ordinary late frame (close in id and time) stays late
  for (const Datagram& d : FrameChunks(47)) EXPECT_EQ(Add(a, d), Result::kLate);
}

// many frames, chunks shuffled within a window, some lost, some repeated: every
// frame returned is whole and right, ids only increase, and every frame whose
// chunks all arrived before a newer frame completed is returned
TEST(FrameAssemblerTest, NeverTornUnderShuffleLossAndRepeats) {
  FrameAssembler a;
  std::mt19937 rng(12345);
  std::bernoulli_distribution lose(0.03), repeat(0.05);
  std::vector<Datagram> stream;
  std::set<std::int64_t> complete_sent, started;
  for (std::int64_t id = 0; id < 300; ++id) {
    bool whole = true;
    for (Datagram& d : FrameChunks(id)) {
      if (lose(rng)) {
        whole = false;
        continue;
      }
      started.insert(id);
      if (repeat(rng)) stream.push_back(d);
      stream.push_back(std::move(d));
    }
    if (whole) complete_sent.insert(id);
  }
  // shuffle within windows of 4 datagrams (a frame is 5 chunks): mild reordering
  for (std::size_t i = 0; i + 4 <= stream.size(); i += 4) std::shuffle(stream.begin() + i, stream.begin() + i + 4, rng);
  std::int64_t last = -1;
  std::set<std::int64_t> got;
  CameraFrame f;
  for (const Datagram& d : stream) {
    if (Add(a, d) != Result::kCompleted) continue;
    ASSERT_TRUE(a.Take(&f));
    ASSERT_GT(f.id, last);
    last = f.id;
    ASSERT_EQ(FirstPatternMismatch(f.id, f.data), -1) << "torn frame " << f.id;
    got.insert(f.id);
  }
  for (std::int64_t id : got) EXPECT_TRUE(complete_sent.count(id)) << id;
  // with this mild reordering no whole frame is overtaken: all of them arrive
  EXPECT_EQ(got, complete_sent);
  EXPECT_GT(complete_sent.size(), 200u);
  EXPECT_LT(complete_sent.size(), 300u);
  const AssemblerCounters& c = a.counters();
  EXPECT_EQ(c.frames_completed + c.frames_dropped + a.in_progress(), static_cast<long>(started.size()))
      << "every frame started either completed, was dropped, or is in progress";
  EXPECT_GT(c.duplicates + c.late, 0);
}

}  // namespace
}  // namespace vlab::bridge::camera_assembler_test
