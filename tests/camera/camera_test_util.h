// Helpers for the camera tests: frames with a frame-dependent pattern, and
// frames cut into chunk datagrams.
#pragma once

#include <cstdint>
#include <vector>

#include "bridge/bridge_camera.h"

namespace vlab::testing {

/// Byte i of raw frame `id`: changes with the frame, the position and the channel.
inline std::uint8_t PatternByte(std::int64_t id, std::size_t i) {
  return static_cast<std::uint8_t>((i * 7u + (i >> 8) * 13u + static_cast<std::size_t>(id) * 31u) & 0xffu);
}

/// A raw RGB8 frame of `id` filled with PatternByte.
inline void FillPattern(std::int64_t id, std::vector<std::uint8_t>* rgb) {
  for (std::size_t i = 0; i < rgb->size(); ++i) (*rgb)[i] = PatternByte(id, i);
}

/// Index of the first byte that differs from frame `id`'s pattern, or -1.
inline long FirstPatternMismatch(std::int64_t id, const std::vector<std::uint8_t>& rgb) {
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    if (rgb[i] != PatternByte(id, i)) return static_cast<long>(i);
  }
  return -1;
}

/// A raw frame `id` of w x h with the pattern, stamped id / 30 s.
inline bridge::CameraFrame PatternFrame(std::int64_t id, int w, int h) {
  bridge::CameraFrame f;
  f.id = id;
  f.time_s = static_cast<double>(id) / 30.0;
  f.width = w;
  f.height = h;
  f.encoding = bridge::CameraEncoding::kRaw;
  f.data.resize(3u * static_cast<std::size_t>(w) * h);
  FillPattern(id, &f.data);
  return f;
}

/// The chunk datagrams of `frame` at `chunk_bytes` per chunk, in order.
inline std::vector<std::vector<unsigned char>> Chunks(const bridge::CameraFrame& frame, std::size_t chunk_bytes) {
  std::vector<std::vector<unsigned char>> out;
  bridge::ChunkHeader h;
  h.frame_id = frame.id;
  h.time_s = frame.time_s;
  h.width = frame.width;
  h.height = frame.height;
  h.encoding = frame.encoding;
  h.frame_bytes = frame.data.size();
  h.pose = frame.pose;
  h.chunk_count = bridge::ChunkCount(h.frame_bytes, chunk_bytes);
  for (int i = 0; i < h.chunk_count; ++i) {
    h.chunk_index = i;
    h.offset = static_cast<std::size_t>(i) * chunk_bytes;
    h.chunk_bytes = std::min(chunk_bytes, h.frame_bytes - h.offset);
    std::vector<unsigned char> d(bridge::ChunkDatagramBytes(h.chunk_bytes));
    bridge::EncodeCameraChunk(h, frame.data.data() + h.offset, d.data());
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace vlab::testing
