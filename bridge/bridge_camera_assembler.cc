#include "bridge/bridge_camera_assembler.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace vlab::bridge {

FrameAssembler::FrameAssembler(const AssemblerConfig& config) : config_(config) {
  config_.slots = std::clamp(config_.slots, 1, 64);
  slots_.resize(static_cast<std::size_t>(config_.slots));
}

FrameAssembler::Result FrameAssembler::Refuse(ChunkError e, ChunkError* error) {
  ++counters_.refused;
  ++counters_.refused_by[static_cast<std::size_t>(e)];
  if (error) *error = e;
  return Result::kRefused;
}

std::size_t FrameAssembler::Piece(const ChunkHeader& h) {
  if (h.chunk_index < h.chunk_count - 1) return h.chunk_bytes;
  if (h.chunk_count > 1) return h.offset / static_cast<std::size_t>(h.chunk_count - 1);
  return h.frame_bytes;
}

bool FrameAssembler::SameFrame(const ChunkHeader& a, const ChunkHeader& b) {
  // bitwise equal times and poses: every chunk of a frame carries the same values
  return a.chunk_count == b.chunk_count && a.width == b.width && a.height == b.height && a.encoding == b.encoding &&
         a.frame_bytes == b.frame_bytes && a.time_s == b.time_s && a.pose.valid == b.pose.valid &&
         a.pose.p_WC == b.pose.p_WC && a.pose.q_WC.coeffs() == b.pose.q_WC.coeffs();
}

void FrameAssembler::Drop(Slot& slot, long* reason) {
  slot.busy = false;
  ++counters_.frames_dropped;
  if (reason) ++*reason;
  if (slot.first.frame_id > floor_id_) {
    floor_id_ = slot.first.frame_id;
    floor_time_s_ = slot.first.time_s;
  }
}

void FrameAssembler::Expire(double now_s) {
  for (Slot& s : slots_) {
    if (s.busy && now_s - s.started_s > config_.timeout_s) Drop(s, &counters_.dropped_timeout);
  }
}

void FrameAssembler::Reset() {
  for (Slot& s : slots_) s.busy = false;
  ready_ = false;
  floor_id_ = -1;
  floor_time_s_ = 0;
}

int FrameAssembler::in_progress() const {
  return static_cast<int>(std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.busy; }));
}

FrameAssembler::Slot* FrameAssembler::FindOrStart(const ChunkHeader& h, double now_s) {
  Slot* free = nullptr;
  Slot* oldest = nullptr;
  for (Slot& s : slots_) {
    if (s.busy && s.first.frame_id == h.frame_id) return &s;
    if (!s.busy && !free) free = &s;
    if (s.busy && (!oldest || s.first.frame_id < oldest->first.frame_id)) oldest = &s;
  }
  if (!free) {
    // all busy: a frame older than all of them has no room; else the oldest goes
    if (h.frame_id < oldest->first.frame_id) return nullptr;
    Drop(*oldest, &counters_.dropped_evicted);
    free = oldest;
  }
  free->busy = true;
  free->first = h;
  free->piece = Piece(h);
  free->started_s = now_s;
  free->received = 0;
  free->data.resize(h.frame_bytes);  // (no allocation once the buffer has the capacity)
  free->have.assign(static_cast<std::size_t>(h.chunk_count), 0);
  return free;
}

void FrameAssembler::Complete(Slot& done) {
  if (ready_) ++counters_.overwritten;
  const ChunkHeader& h = done.first;
  ready_frame_.id = h.frame_id;
  ready_frame_.time_s = h.time_s;
  ready_frame_.width = h.width;
  ready_frame_.height = h.height;
  ready_frame_.encoding = h.encoding;
  ready_frame_.pose = h.pose;
  std::swap(ready_frame_.data, done.data);
  ready_ = true;
  done.busy = false;
  ++counters_.frames_completed;
  floor_id_ = h.frame_id;
  floor_time_s_ = h.time_s;
  // older frames still in progress can no longer be shown in order
  for (Slot& s : slots_) {
    if (s.busy && s.first.frame_id < h.frame_id) Drop(s, &counters_.dropped_superseded);
  }
}

FrameAssembler::Result FrameAssembler::Add(const unsigned char* data, std::size_t size, double now_s,
                                           ChunkError* error) {
  ++counters_.chunks;
  if (error) *error = ChunkError::kNone;
  const unsigned char* bytes = nullptr;
  const ChunkError e = DecodeCameraChunk(data, size, &header_, &bytes);
  if (e != ChunkError::kNone) return Refuse(e, error);
  const ChunkHeader& h = header_;
  if (h.frame_bytes > config_.max_frame_bytes) return Refuse(ChunkError::kTooLarge, error);
  Expire(now_s);

  if (h.frame_id <= floor_id_) {
    const bool restarted =
        floor_id_ - h.frame_id > config_.restart_gap || h.time_s < floor_time_s_ - config_.restart_time_s;
    if (!restarted) {
      ++counters_.late;
      return Result::kLate;
    }
    ++counters_.restarts;
    for (Slot& s : slots_) {
      if (s.busy) {
        s.busy = false;
        ++counters_.frames_dropped;
      }
    }
    floor_id_ = -1;
    floor_time_s_ = 0;
  }

  Slot* slot = FindOrStart(h, now_s);
  if (!slot) {
    ++counters_.late;
    return Result::kLate;
  }
  if (!SameFrame(slot->first, h) || Piece(h) != slot->piece) return Refuse(ChunkError::kInconsistent, error);
  std::uint8_t& have = slot->have[static_cast<std::size_t>(h.chunk_index)];
  if (have) {
    ++counters_.duplicates;
    return Result::kDuplicate;
  }
  std::memcpy(slot->data.data() + h.offset, bytes, h.chunk_bytes);
  have = 1;
  ++counters_.accepted;
  if (++slot->received < slot->first.chunk_count) return Result::kAccepted;
  Complete(*slot);
  return Result::kCompleted;
}

bool FrameAssembler::Take(CameraFrame* frame) {
  if (!ready_) return false;
  frame->id = ready_frame_.id;
  frame->time_s = ready_frame_.time_s;
  frame->width = ready_frame_.width;
  frame->height = ready_frame_.height;
  frame->encoding = ready_frame_.encoding;
  frame->pose = ready_frame_.pose;
  std::swap(frame->data, ready_frame_.data);
  ready_ = false;
  return true;
}

}  // namespace vlab::bridge
