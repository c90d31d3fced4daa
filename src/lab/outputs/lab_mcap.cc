#include "lab/outputs/lab_mcap.h"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace vlab::lab {

namespace {

constexpr char kMagic[] = "\x89MCAP0\r\n";  // 8 bytes
constexpr std::size_t kMagicSize = 8;

// record opcodes
enum McapOp : std::uint8_t {
  kOpHeader = 0x01,
  kOpFooter = 0x02,
  kOpSchema = 0x03,
  kOpChannel = 0x04,
  kOpMessage = 0x05,
  kOpChunk = 0x06,
  kOpMessageIndex = 0x07,
  kOpChunkIndex = 0x08,
  kOpStatistics = 0x0B,
  kOpSummaryOffset = 0x0E,
  kOpDataEnd = 0x0F,
};

// little-endian fields appended to a record's bytes
template <typename T>
void PutLe(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out->append(bytes, sizeof(T));
}
void PutMcapString(std::string* out, const std::string& s) {
  PutLe<std::uint32_t>(out, static_cast<std::uint32_t>(s.size()));
  out->append(s);
}

// a record: opcode, uint64 content length, content
void PutRecord(std::string* out, McapOp op, const std::string& content) {
  PutLe<std::uint8_t>(out, op);
  PutLe<std::uint64_t>(out, content.size());
  out->append(content);
}

std::uint32_t Crc32Of(std::uint32_t crc, const void* data, std::size_t size) {
  // zlib's crc32 takes uInt lengths: large buffers in pieces
  const auto* bytes = static_cast<const Bytef*>(data);
  while (size > 0) {
    const uInt n = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = static_cast<std::uint32_t>(crc32(crc, bytes, n));
    bytes += n;
    size -= n;
  }
  return crc;
}

}  // namespace

std::unique_ptr<McapWriter> McapWriter::Create(const std::string& path, const std::string& name,
                                               const McapOptions& options) {
  std::FILE* file = std::fopen(path.c_str(), "wbe");  // e: not inherited by a controller
  if (!file) throw std::runtime_error(name + ": cannot create file: " + std::strerror(errno));
  std::unique_ptr<McapWriter> w(new McapWriter(file, name, options));
  w->zstd_ = ZSTD_createCCtx();
  if (!w->zstd_) throw std::runtime_error(name + ": cannot make a zstd context");
  std::string bytes(kMagic, kMagicSize), header;
  PutMcapString(&header, options.profile);
  PutMcapString(&header, "vlab");
  PutRecord(&bytes, kOpHeader, header);
  w->Emit(bytes);
  return w;
}

McapWriter::McapWriter(std::FILE* file, std::string name, McapOptions options)
    : file_(file), name_(std::move(name)), options_(std::move(options)) {
  chunk_.reserve(options_.chunk_bytes + (options_.chunk_bytes >> 2));
}

McapWriter::~McapWriter() {
  if (file_) std::fclose(file_);
  ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(zstd_));
}

std::string McapWriter::Error(const std::string& what) {
  if (error_.empty()) error_ = name_ + ": write failed: " + what;
  return error_;
}

void McapWriter::Emit(const std::string& bytes) {
  if (!error_.empty()) return;
  errno = 0;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    Error(std::strerror(errno ? errno : EIO));
    return;
  }
  data_crc_ = Crc32Of(data_crc_, bytes.data(), bytes.size());
  position_ += bytes.size();
}

std::uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  std::string content, record;
  PutLe<std::uint16_t>(&content, id);
  PutMcapString(&content, name);
  PutMcapString(&content, encoding);
  PutMcapString(&content, data);  // (uint32 length-prefixed bytes)
  PutRecord(&record, kOpSchema, content);
  Emit(record);
  schemas_.push_back(record);
  return id;
}

std::uint16_t McapWriter::AddChannel(std::uint16_t schema, const std::string& topic,
                                     const std::string& message_encoding) {
  const auto id = static_cast<std::uint16_t>(channels_.size());
  std::string content, record;
  PutLe<std::uint16_t>(&content, id);
  PutLe<std::uint16_t>(&content, schema);
  PutMcapString(&content, topic);
  PutMcapString(&content, message_encoding);
  PutLe<std::uint32_t>(&content, 0);  // metadata: an empty map
  PutRecord(&record, kOpChannel, content);
  Emit(record);
  channels_.push_back(record);
  channel_counts_.push_back(0);
  chunk_index_.emplace_back();
  return id;
}

std::string McapWriter::Write(std::uint16_t channel, std::uint64_t time_ns, const void* data, std::size_t size) {
  if (!error_.empty()) return error_;
  if (channel >= channels_.size()) return Error("message on channel " + std::to_string(channel) + ", never added");
  if (options_.message_indexes) {
    chunk_index_[channel].push_back(time_ns);
    chunk_index_[channel].push_back(chunk_.size());
  }
  // the Message record: channel, sequence, log time, publish time, data
  PutLe<std::uint8_t>(&chunk_, kOpMessage);
  PutLe<std::uint64_t>(&chunk_, 2 + 4 + 8 + 8 + size);
  PutLe<std::uint16_t>(&chunk_, channel);
  PutLe<std::uint32_t>(&chunk_, static_cast<std::uint32_t>(channel_counts_[channel]));
  PutLe<std::uint64_t>(&chunk_, time_ns);
  PutLe<std::uint64_t>(&chunk_, time_ns);
  chunk_.append(static_cast<const char*>(data), size);
  ++channel_counts_[channel];
  chunk_start_ns_ = chunk_has_messages_ ? std::min(chunk_start_ns_, time_ns) : time_ns;
  chunk_end_ns_ = chunk_has_messages_ ? std::max(chunk_end_ns_, time_ns) : time_ns;
  start_ns_ = messages_ ? std::min(start_ns_, time_ns) : time_ns;
  end_ns_ = messages_ ? std::max(end_ns_, time_ns) : time_ns;
  chunk_has_messages_ = true;
  ++messages_;
  return chunk_.size() >= options_.chunk_bytes ? FlushChunk() : "";
}

std::string McapWriter::FlushChunk() {
  if (!error_.empty()) return error_;
  if (chunk_.empty()) return "";
  // zstd, unless that saves nothing (PNG frames): then the records as they are
  auto* zstd = static_cast<ZSTD_CCtx*>(zstd_);
  compressed_.resize(ZSTD_compressBound(chunk_.size()));
  const std::size_t packed = ZSTD_compressCCtx(zstd, compressed_.data(), compressed_.size(), chunk_.data(),
                                               chunk_.size(), options_.zstd_level);
  if (ZSTD_isError(packed)) return Error(std::string("zstd: ") + ZSTD_getErrorName(packed));
  const bool compress = packed < chunk_.size();
  const std::string& records = compress ? compressed_ : chunk_;
  const std::size_t records_size = compress ? packed : chunk_.size();
  ChunkIndex index{chunk_start_ns_, chunk_end_ns_,          position_, 0, 0, records_size,
                   chunk_.size(),   compress ? "zstd" : "", {}};
  // the Chunk record, its head then the records
  record_.clear();
  std::string head;
  PutLe<std::uint64_t>(&head, chunk_start_ns_);
  PutLe<std::uint64_t>(&head, chunk_end_ns_);
  PutLe<std::uint64_t>(&head, chunk_.size());
  PutLe<std::uint32_t>(&head, Crc32Of(0, chunk_.data(), chunk_.size()));
  PutMcapString(&head, index.compression);
  PutLe<std::uint64_t>(&head, records_size);
  PutLe<std::uint8_t>(&record_, kOpChunk);
  PutLe<std::uint64_t>(&record_, head.size() + records_size);
  record_.append(head);
  record_.append(records.data(), records_size);
  Emit(record_);
  index.length = record_.size();
  // one Message Index per channel with messages in the chunk, in channel order
  if (options_.message_indexes) {
    std::string indexes;
    for (std::size_t c = 0; c < chunk_index_.size(); ++c) {
      std::vector<std::uint64_t>& pairs = chunk_index_[c];
      if (pairs.empty()) continue;
      index.index_offsets.emplace_back(static_cast<std::uint16_t>(c), position_ + indexes.size());
      std::string content;
      PutLe<std::uint16_t>(&content, static_cast<std::uint16_t>(c));
      PutLe<std::uint32_t>(&content, static_cast<std::uint32_t>(pairs.size() * 8));
      for (std::uint64_t v : pairs) PutLe<std::uint64_t>(&content, v);
      PutRecord(&indexes, kOpMessageIndex, content);
      pairs.clear();
    }
    Emit(indexes);
    index.index_length = indexes.size();
  }
  chunks_.push_back(std::move(index));
  chunk_.clear();
  chunk_has_messages_ = false;
  // on disk now: a run cut short keeps every chunk up to here
  errno = 0;
  if (error_.empty() && std::fflush(file_) != 0) Error(std::strerror(errno ? errno : EIO));
  return error_;
}

std::string McapWriter::Close() {
  if (!file_) return error_;
  FlushChunk();
  // Data End: the CRC of everything before it
  std::string bytes, content;
  PutLe<std::uint32_t>(&content, data_crc_);
  PutRecord(&bytes, kOpDataEnd, content);
  Emit(bytes);
  // the summary, grouped by opcode, and where each group starts
  const std::uint64_t summary_start = position_;
  std::string summary;
  std::vector<std::pair<McapOp, std::pair<std::uint64_t, std::uint64_t>>> groups;
  const auto group = [&](McapOp op, const std::string& records) {
    if (records.empty()) return;
    groups.push_back({op, {summary_start + summary.size(), records.size()}});
    summary.append(records);
  };
  std::string records;
  for (const std::string& s : schemas_) records += s;
  group(kOpSchema, records);
  records.clear();
  for (const std::string& c : channels_) records += c;
  group(kOpChannel, records);
  content.clear();
  PutLe<std::uint64_t>(&content, messages_);
  PutLe<std::uint16_t>(&content, static_cast<std::uint16_t>(schemas_.size()));
  PutLe<std::uint32_t>(&content, static_cast<std::uint32_t>(channels_.size()));
  PutLe<std::uint32_t>(&content, 0);  // attachments
  PutLe<std::uint32_t>(&content, 0);  // metadata
  PutLe<std::uint32_t>(&content, static_cast<std::uint32_t>(chunks_.size()));
  PutLe<std::uint64_t>(&content, start_ns_);
  PutLe<std::uint64_t>(&content, end_ns_);
  PutLe<std::uint32_t>(&content, static_cast<std::uint32_t>(channel_counts_.size() * 10));
  for (std::size_t c = 0; c < channel_counts_.size(); ++c) {
    PutLe<std::uint16_t>(&content, static_cast<std::uint16_t>(c));
    PutLe<std::uint64_t>(&content, channel_counts_[c]);
  }
  records.clear();
  PutRecord(&records, kOpStatistics, content);
  group(kOpStatistics, records);
  records.clear();
  for (const ChunkIndex& chunk : chunks_) {
    content.clear();
    PutLe<std::uint64_t>(&content, chunk.start_ns);
    PutLe<std::uint64_t>(&content, chunk.end_ns);
    PutLe<std::uint64_t>(&content, chunk.offset);
    PutLe<std::uint64_t>(&content, chunk.length);
    PutLe<std::uint32_t>(&content, static_cast<std::uint32_t>(chunk.index_offsets.size() * 10));
    for (const auto& [channel, offset] : chunk.index_offsets) {
      PutLe<std::uint16_t>(&content, channel);
      PutLe<std::uint64_t>(&content, offset);
    }
    PutLe<std::uint64_t>(&content, chunk.index_length);
    PutMcapString(&content, chunk.compression);
    PutLe<std::uint64_t>(&content, chunk.compressed);
    PutLe<std::uint64_t>(&content, chunk.uncompressed);
    PutRecord(&records, kOpChunkIndex, content);
  }
  group(kOpChunkIndex, records);
  const std::uint64_t offsets_start = summary_start + summary.size();
  for (const auto& [op, where] : groups) {
    content.clear();
    PutLe<std::uint8_t>(&content, op);
    PutLe<std::uint64_t>(&content, where.first);
    PutLe<std::uint64_t>(&content, where.second);
    PutRecord(&summary, kOpSummaryOffset, content);
  }
  // the footer; its CRC covers the summary up to its own summary_offset_start field
  PutLe<std::uint8_t>(&summary, kOpFooter);
  PutLe<std::uint64_t>(&summary, 8 + 8 + 4);
  PutLe<std::uint64_t>(&summary, summary_start);
  PutLe<std::uint64_t>(&summary, offsets_start);
  PutLe<std::uint32_t>(&summary, Crc32Of(0, summary.data(), summary.size()));
  summary.append(kMagic, kMagicSize);
  Emit(summary);
  errno = 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!closed) Error(std::strerror(errno ? errno : EIO));
  return error_;
}

}  // namespace vlab::lab
