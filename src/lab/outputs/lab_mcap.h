// An MCAP file writer (the published MCAP specification, major version 0):
//   magic, Header (profile, library "vlab")
//   data section: Schema and Channel records as they are added, then Chunk
//                 records (zstd-compressed records, about chunk_bytes
//                 uncompressed each, with the CRC-32 of the uncompressed
//                 records), each followed by its Message Index records
//                 (McapOptions::message_indexes), then Data End (the CRC-32
//                 of the data section)
//   summary:      every Schema, every Channel, one Statistics (message,
//                 chunk and per-channel counts, first and last log time), a
//                 Chunk Index per chunk, each group of one opcode together
//   summary offsets (one per group), Footer (with the summary's CRC-32), magic
// A chunk whose records zstd does not make smaller (PNG frames) is stored
// uncompressed (compression ""). Messages are written in the order they are
// given; nothing in the file depends on the clock or the machine, so the same
// calls write the same bytes.
//
// Each chunk is flushed to the file when it is full: a process killed mid-run
// leaves the header, the schemas and channels and every chunk written so far,
// which a streaming reader reads up to the cut (no summary, no footer); Close
// writes the rest. One thread at a time; errors are returned as one line
// naming the file, and after one nothing more is written.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace vlab::lab {

struct McapOptions {
  /// The header's profile: "" (none) or a well-known one ("ros2").
  std::string profile;
  /// Uncompressed bytes of records after which a chunk is written.
  std::size_t chunk_bytes = std::size_t{1} << 20;
  /// zstd's compression level (1 fastest .. 19). 1: on 60 s of pa10_reach's
  /// signals levels 1, 3, 9 and 19 give 3.97, 4.00, 3.87 and 3.66 MB of chunks,
  /// level 19 at 6x the run's wall time.
  int zstd_level = 1;
  /// Message Index records after each chunk: 16 bytes per message, not
  /// compressed; @mcap/core's indexed reader (and the viewers built on it)
  /// finds no message in a chunk without them.
  bool message_indexes = true;
};

class McapWriter {
 public:
  /// Creates `path` (replacing a file there) and writes the magic and the
  /// header. Throws std::runtime_error naming `name` (how messages call the
  /// file: "log 'PATH'") when it cannot be created.
  static std::unique_ptr<McapWriter> Create(const std::string& path, const std::string& name,
                                            const McapOptions& options);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// A Schema record (ids from 1, in order); `data` its definition.
  std::uint16_t AddSchema(const std::string& name, const std::string& encoding, const std::string& data);
  /// A Channel record of `schema` (ids from 0, in order), no metadata.
  std::uint16_t AddChannel(std::uint16_t schema, const std::string& topic, const std::string& message_encoding);
  /// A Message record on `channel` at log_time = publish_time = `time_ns`,
  /// sequence the channel's count of messages before it. "" or why not.
  std::string Write(std::uint16_t channel, std::uint64_t time_ns, const void* data, std::size_t size);
  /// The last chunk, Data End, the summary, the footer and the magic; closes
  /// the file. "" or why not (the first error of any call).
  std::string Close();

  /// Bytes written to the file so far.
  std::uint64_t size() const { return position_; }

 private:
  struct ChunkIndex {
    std::uint64_t start_ns, end_ns, offset, length, index_length, compressed, uncompressed;
    std::string compression;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;  // channel, offset
  };
  McapWriter(std::FILE* file, std::string name, McapOptions options);
  void Emit(const std::string& bytes);  // to the file, counted and in the data CRC
  std::string FlushChunk();
  std::string Error(const std::string& what);

  std::FILE* file_;
  std::string name_;
  McapOptions options_;
  void* zstd_ = nullptr;  // ZSTD_CCtx, reused for every chunk
  std::uint64_t position_ = 0;
  std::uint32_t data_crc_ = 0;
  std::string error_;
  std::vector<std::string> schemas_, channels_;  // their records, for the summary
  std::vector<std::uint64_t> channel_counts_;
  std::uint64_t messages_ = 0, start_ns_ = 0, end_ns_ = 0;
  // the open chunk: its records, times and each channel's (log time, offset) pairs
  std::string chunk_;
  std::uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  bool chunk_has_messages_ = false;
  std::vector<std::vector<std::uint64_t>> chunk_index_;
  std::vector<ChunkIndex> chunks_;
  std::string compressed_, record_;  // reused buffers
};

}  // namespace vlab::lab
