// Receiver side of camera chunks: reassembles whole frames and drops the
// incomplete ones, so that a client never sees a torn frame.
//
// Ports
//   input   chunk datagrams (Add), each with the receiver's clock `now_s`
//   output  whole frames (Take), in increasing frame id
// Rules (docs/protocol_camera.md, "Reassembly")
//   - chunks are keyed by frame id; up to `slots` frames are in progress;
//   - a frame is complete when every chunk index 0..count-1 has arrived; its
//     chunks must agree (size, encoding, byte count, chunk size, time, pose),
//     a chunk that disagrees is refused (kInconsistent) and the frame can
//     then never complete;
//   - when a frame completes, every incomplete frame with a lower id is
//     dropped; an incomplete frame is also dropped `timeout_s` after its first
//     chunk, and the oldest one when all slots are busy and a newer frame starts;
//   - a chunk of a frame not newer than the newest delivered or dropped frame
//     is late and ignored, except when the sender evidently restarted (its id
//     is more than `restart_gap` below, or its time more than `restart_time_s`
//     before, that newest frame): then everything in progress is dropped and
//     reassembly starts afresh;
//   - a repeated chunk is ignored; a malformed one is refused and counted by
//     reason.
// Never throws and never blocks; allocates only while a frame is larger than
// any seen before (buffers are reused and swapped with the caller's in Take).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bridge/bridge_camera.h"

namespace vlab::bridge {

struct AssemblerConfig {
  int slots = 4;                            ///< frames in progress at once (1..64)
  double timeout_s = 1.0;                   ///< an incomplete frame is dropped this long after its first chunk
  std::size_t max_frame_bytes = 64u << 20;  ///< larger frames are refused (kTooLarge)
  std::int64_t restart_gap = 64;            ///< frames: an id this far below the newest means a restart
  double restart_time_s = 1.0;              ///< s: a time this far before the newest means a restart
};

struct AssemblerCounters {
  long chunks = 0;                                  ///< datagrams offered to Add
  long accepted = 0;                                ///< chunks stored
  long duplicates = 0;                              ///< chunks received before (ignored)
  long late = 0;                                    ///< chunks of frames already delivered or dropped (ignored)
  long refused = 0;                                 ///< malformed or inconsistent chunks, all reasons
  std::array<long, kChunkErrorCount> refused_by{};  ///< refused, indexed by ChunkError
  long frames_completed = 0;
  long frames_dropped = 0;      ///< incomplete frames dropped, all reasons (the three below and restarts)
  long dropped_superseded = 0;  ///< a newer frame completed first
  long dropped_timeout = 0;     ///< timeout_s passed
  long dropped_evicted = 0;     ///< all slots busy when a newer frame started
  long overwritten = 0;         ///< completed frames replaced by a newer one before Take
  long restarts = 0;            ///< sender restarts detected
};

class FrameAssembler {
 public:
  enum class Result {
    kRefused,    ///< malformed, inconsistent or too large: see *error
    kAccepted,   ///< stored; its frame is not complete yet
    kDuplicate,  ///< this chunk was already there
    kLate,       ///< its frame was already delivered or dropped
    kCompleted,  ///< stored, and its frame is now complete: Take it
  };

  explicit FrameAssembler(const AssemblerConfig& config = {});

  /// Offers one datagram received at `now_s` (receiver's clock, s; used for
  /// timeouts only). Expires old frames first. `error` (may be null) gets the
  /// refusal reason, or kNone.
  Result Add(const unsigned char* data, std::size_t size, double now_s, ChunkError* error = nullptr);
  /// Drops incomplete frames whose first chunk came more than timeout_s before now_s.
  void Expire(double now_s);
  /// A completed frame waits to be taken.
  bool ready() const { return ready_; }
  /// Moves the completed frame into *frame (buffers are swapped, not copied);
  /// false if none is ready.
  bool Take(CameraFrame* frame);
  /// Forgets every frame in progress and the frame id history (counters stay).
  void Reset();

  int in_progress() const;
  const AssemblerCounters& counters() const { return counters_; }
  const AssemblerConfig& config() const { return config_; }

 private:
  struct Slot {
    bool busy = false;
    ChunkHeader first;      // the first chunk's fields: the others must agree
    std::size_t piece = 0;  // P: bytes of every chunk but the last
    double started_s = 0;
    int received = 0;
    std::vector<std::uint8_t> data;
    std::vector<std::uint8_t> have;  // one flag per chunk index
  };
  Result Refuse(ChunkError e, ChunkError* error);
  Slot* FindOrStart(const ChunkHeader& h, double now_s);
  void Drop(Slot& slot, long* reason);
  void Complete(Slot& slot);
  static std::size_t Piece(const ChunkHeader& h);
  static bool SameFrame(const ChunkHeader& a, const ChunkHeader& b);

  AssemblerConfig config_;
  AssemblerCounters counters_;
  std::vector<Slot> slots_;
  bool ready_ = false;
  CameraFrame ready_frame_;
  std::int64_t floor_id_ = -1;  // newest frame delivered or dropped
  double floor_time_s_ = 0;     // its time
  ChunkHeader header_;          // scratch
};

}  // namespace vlab::bridge
