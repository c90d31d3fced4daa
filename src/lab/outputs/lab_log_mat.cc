#include "lab/outputs/lab_log_mat.h"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "lab/outputs/lab_log_formats.h"

namespace vlab::lab {

namespace {

// MAT 5 data types and array classes (MATLAB's "MAT-File Format", level 5)
constexpr std::uint32_t kMiInt8 = 1, kMiInt32 = 5, kMiUint32 = 6, kMiDouble = 9, kMiMatrix = 14, kMiCompressed = 15,
                        kMiUtf8 = 16;
constexpr std::uint32_t kStructClass = 2, kCharClass = 4, kDoubleClass = 6;
constexpr std::uint32_t kFieldNameLength = 32;  // bytes per field name, its NUL included
// the deflate settings of every piece: fast (the writer thread keeps pace with the step loop),
// a 4 KiB window and a small hash (about 48 KiB of state per column)
constexpr int kLevel = 1, kWindowBits = -12, kMemLevel = 6;
// a column's compressed bytes are spilled to the hidden file in pieces of this size
constexpr std::size_t kSpillBytes = 64 * 1024;

void PutU32(std::string* out, std::uint32_t v) { out->append(reinterpret_cast<const char*>(&v), 4); }
void PutI32(std::string* out, std::int32_t v) { out->append(reinterpret_cast<const char*>(&v), 4); }
void Pad8(std::string* out, std::size_t start) {
  while ((out->size() - start) % 8) out->push_back('\0');
}
// a data element: tag, bytes, padding to 8
void Element(std::string* out, std::uint32_t type, const std::string& bytes) {
  PutU32(out, type);
  PutU32(out, static_cast<std::uint32_t>(bytes.size()));
  const std::size_t start = out->size();
  out->append(bytes);
  Pad8(out, start);
}
// array flags, dimensions, name (the sub-elements that begin every matrix)
void MatrixHead(std::string* out, std::uint32_t array_class, std::int32_t rows, std::int32_t columns,
                const std::string& name) {
  std::string flags, dims;
  PutU32(&flags, array_class);
  PutU32(&flags, 0);
  Element(out, kMiUint32, flags);
  PutI32(&dims, rows);
  PutI32(&dims, columns);
  Element(out, kMiInt32, dims);
  Element(out, kMiInt8, name);
}

// a char matrix of one row per string, blank-padded, UTF-8, as a whole element
std::string CharMatrix(const std::vector<std::string>& values) {
  std::size_t width = 0;
  for (const std::string& v : values) width = std::max(width, v.size());
  std::string text(values.size() * width, ' ');  // column-major
  for (std::size_t r = 0; r < values.size(); ++r) {
    for (std::size_t c = 0; c < values[r].size(); ++c) text[c * values.size() + r] = values[r][c];
  }
  std::string body;
  MatrixHead(&body, kCharClass, static_cast<std::int32_t>(values.size()), static_cast<std::int32_t>(width), "");
  Element(&body, kMiUtf8, text);
  std::string element;
  PutU32(&element, kMiMatrix);
  PutU32(&element, static_cast<std::uint32_t>(body.size()));
  return element + body;
}

// one raw deflate stream; Finish ends it with a full flush: byte-aligned, no final block, no
// reference before its own start, so that such streams concatenate into one deflate stream
class Deflater {
 public:
  Deflater() {
    if (deflateInit2(&z_, kLevel, Z_DEFLATED, kWindowBits, kMemLevel, Z_DEFAULT_STRATEGY) != Z_OK) {
      throw std::runtime_error("zlib: cannot start a deflate stream");
    }
    ready_ = true;
  }
  ~Deflater() {
    if (ready_) deflateEnd(&z_);
  }
  Deflater(const Deflater&) = delete;
  Deflater& operator=(const Deflater&) = delete;

  void Add(const void* data, std::size_t size, std::string* out) { Run(data, size, Z_NO_FLUSH, out); }
  void Finish(std::string* out) { Run(nullptr, 0, Z_FULL_FLUSH, out); }
  // the Adler-32 and the length of what went in (the zlib wrapper's check needs them)
  std::uint32_t adler() const { return adler_; }
  std::size_t in_bytes() const { return in_bytes_; }

 private:
  void Run(const void* data, std::size_t size, int flush, std::string* out) {
    // (adler32 of a null buffer is the initial value, not the running one)
    if (size > 0)
      adler_ = static_cast<std::uint32_t>(adler32(adler_, static_cast<const Bytef*>(data), static_cast<uInt>(size)));
    in_bytes_ += size;
    z_.next_in = const_cast<Bytef*>(static_cast<const Bytef*>(data));
    z_.avail_in = static_cast<uInt>(size);
    unsigned char buffer[16384];
    do {
      z_.next_out = buffer;
      z_.avail_out = sizeof buffer;
      deflate(&z_, flush);
      out->append(reinterpret_cast<const char*>(buffer), sizeof buffer - z_.avail_out);
    } while (z_.avail_in > 0 || z_.avail_out == 0);
  }
  z_stream z_{};
  bool ready_ = false;
  std::uint32_t adler_ = static_cast<std::uint32_t>(adler32(0, nullptr, 0));
  std::size_t in_bytes_ = 0;
};

// bytes compressed whole, as one piece (the heads and tails built at the end)
std::string DeflateWhole(const std::string& bytes, std::uint32_t* adler) {
  Deflater d;
  std::string out;
  d.Add(bytes.data(), bytes.size(), &out);
  d.Finish(&out);
  *adler = d.adler();
  return out;
}

class MatSink : public LogSink {
 public:
  MatSink(std::FILE* spill, std::string spill_path, std::string path, std::vector<std::string> columns)
      : spill_(spill), spill_path_(std::move(spill_path)), path_(std::move(path)), columns_(std::move(columns)) {
    streams_.resize(columns_.size());
    for (Column& c : streams_) c.deflater = std::make_unique<Deflater>();
  }
  ~MatSink() override {
    if (spill_) std::fclose(spill_);
    ::unlink(spill_path_.c_str());
  }

  std::string Write(const double* rows, int count) override {
    const std::size_t n = columns_.size();
    column_.resize(static_cast<std::size_t>(count));
    for (std::size_t c = 0; c < n; ++c) {
      for (int r = 0; r < count; ++r) column_[r] = rows[static_cast<std::size_t>(r) * n + c];
      streams_[c].deflater->Add(column_.data(), column_.size() * sizeof(double), &streams_[c].pending);
      if (streams_[c].pending.size() >= kSpillBytes && !Spill(&streams_[c])) return SpillFailed();
    }
    if (std::fflush(spill_) != 0) return SpillFailed();
    count_ += count;
    return "";
  }

  std::string Close() override {
    if (!spill_) return "";
    std::string why = BuildMat();
    std::fclose(spill_);
    spill_ = nullptr;
    ::unlink(spill_path_.c_str());
    return why;
  }

 private:
  struct Piece {
    long offset;
    std::size_t size;
  };
  struct Column {
    std::unique_ptr<Deflater> deflater;
    std::string pending;        // compressed, not yet spilled
    std::vector<Piece> pieces;  // spilled, in order
  };

  bool Spill(Column* c) {
    const long at = std::ftell(spill_);
    if (at < 0 || std::fseek(spill_, 0, SEEK_END) != 0) return false;
    const long end = std::ftell(spill_);
    if (std::fwrite(c->pending.data(), 1, c->pending.size(), spill_) != c->pending.size()) return false;
    c->pieces.push_back({end, c->pending.size()});
    c->pending.clear();
    return true;
  }
  std::string SpillFailed() const { return "log '" + path_ + "': write failed: " + std::strerror(errno ? errno : EIO); }

  // the zlib stream of one group's variable: its head, its columns' data, its tail
  std::string BuildVariable(const std::string& name, const ColumnGroupIndex& group, std::string* why) {
    const std::uint64_t data_bytes = static_cast<std::uint64_t>(count_) * group.columns.size() * sizeof(double);
    std::vector<std::string> names, units;
    for (int c : group.columns) {
      names.push_back(columns_[c]);
      units.push_back(ColumnUnit(columns_[c]));
    }
    const std::string tail = CharMatrix(names) + CharMatrix(units);
    // the field `data`: its head, then the doubles (a multiple of 8 bytes: no padding)
    std::string data_head;
    MatrixHead(&data_head, kDoubleClass, static_cast<std::int32_t>(count_),
               static_cast<std::int32_t>(group.columns.size()), "");
    PutU32(&data_head, kMiDouble);
    PutU32(&data_head, static_cast<std::uint32_t>(data_bytes));
    const std::uint64_t data_element = data_head.size() + data_bytes;
    // the struct: head, field names, then the three fields
    std::string fields(3 * kFieldNameLength, '\0');
    const char* field_names[] = {"data", "names", "units"};
    for (int f = 0; f < 3; ++f) std::memcpy(&fields[f * kFieldNameLength], field_names[f], std::strlen(field_names[f]));
    std::string body;
    MatrixHead(&body, kStructClass, 1, 1, name);
    PutU32(&body, (4u << 16) | kMiInt32);  // field name length, a small data element
    PutU32(&body, kFieldNameLength);
    Element(&body, kMiInt8, fields);
    const std::uint64_t total = body.size() + 8 + data_element + tail.size();
    if (total + 8 > 0xFFFFFFFFull) {
      *why = "log '" + path_ + "': variable '" + name + "' would exceed MAT 5's 4 GiB";
      return "";
    }
    std::string head;
    PutU32(&head, kMiMatrix);
    PutU32(&head, static_cast<std::uint32_t>(total));
    head += body;
    PutU32(&head, kMiMatrix);
    PutU32(&head, static_cast<std::uint32_t>(data_element));
    head += data_head;

    std::uint32_t adler = 0, tail_adler = 0;
    std::string stream = "\x78\x01";  // zlib header: deflate, 32 KiB window at most, fastest level
    stream += DeflateWhole(head, &adler);
    std::string piece;
    for (int c : group.columns) {
      Column& column = streams_[c];
      column.deflater->Finish(&column.pending);
      for (const Piece& p : column.pieces) {
        piece.resize(p.size);
        if (std::fseek(spill_, p.offset, SEEK_SET) != 0 || std::fread(piece.data(), 1, p.size, spill_) != p.size) {
          *why = "log '" + path_ + "': cannot read back '" + spill_path_ + "'";
          return "";
        }
        stream += piece;
      }
      stream += column.pending;
      column.pending.clear();
      adler = static_cast<std::uint32_t>(
          adler32_combine(adler, column.deflater->adler(), static_cast<z_off_t>(column.deflater->in_bytes())));
    }
    stream += DeflateWhole(tail, &tail_adler);
    adler = static_cast<std::uint32_t>(adler32_combine(adler, tail_adler, static_cast<z_off_t>(tail.size())));
    stream += std::string("\x03\x00", 2);  // an empty final block (fixed Huffman)
    for (int shift = 24; shift >= 0; shift -= 8) stream.push_back(static_cast<char>((adler >> shift) & 0xFF));
    return stream;
  }

  std::string BuildMat() {
    const auto fail = [this](const std::string& what) { return "log '" + path_ + "': write failed: " + what; };
    std::FILE* out = std::fopen(path_.c_str(), "wbe");
    if (!out) return fail(std::strerror(errno));
    // the 128-byte header: text, no subsystem data, version 0x0100, "IM" (little-endian)
    std::string header = "MATLAB 5.0 MAT-file, written by vlab (one struct per column group)";
    header.resize(116, ' ');
    header.append(8, '\0');
    header += std::string("\x00\x01", 2) + "IM";
    bool ok = std::fwrite(header.data(), 1, header.size(), out) == header.size();
    std::string why;
    std::set<std::string> taken;
    for (const ColumnGroupIndex& group : GroupColumns(columns_)) {
      if (!ok) break;
      // a unique variable name per group (two groups may sanitise alike)
      std::string name = MatVariableName(group.name);
      for (int k = 2; taken.count(name); ++k) name = MatVariableName(group.name) + "_" + std::to_string(k);
      taken.insert(name);
      const std::string stream = BuildVariable(name, group, &why);
      if (!why.empty()) break;
      std::string tag;
      PutU32(&tag, kMiCompressed);
      PutU32(&tag, static_cast<std::uint32_t>(stream.size()));
      ok = std::fwrite(tag.data(), 1, tag.size(), out) == tag.size() &&
           std::fwrite(stream.data(), 1, stream.size(), out) == stream.size();
    }
    if (!ok && why.empty()) why = fail(std::strerror(errno ? errno : EIO));
    if (std::fclose(out) != 0 && why.empty()) why = fail(std::strerror(errno));
    return why;
  }

  std::FILE* spill_;
  std::string spill_path_;
  std::string path_;
  std::vector<std::string> columns_;
  std::vector<Column> streams_;
  std::vector<double> column_;  // one column of a block
  long count_ = 0;
};

}  // namespace

std::string MatFileVersion() { return "5 (compressed)"; }

std::string MatVariableName(const std::string& group) {
  std::string name;
  for (char c : group) name.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_');
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) name = "v" + name;
  return name.substr(0, 63);
}

std::unique_ptr<LogSink> OpenMatSink(const std::string& path, const std::vector<std::string>& columns) {
  const std::filesystem::path p(path);
  const std::string spill_path = (p.parent_path() / ("." + p.filename().string() + ".part")).string();
  std::FILE* spill = std::fopen(spill_path.c_str(), "w+be");
  if (!spill) {
    throw std::runtime_error("log '" + path + "': cannot create '" + spill_path + "': " + std::strerror(errno));
  }
  return std::make_unique<MatSink>(spill, spill_path, path, columns);
}

}  // namespace vlab::lab
