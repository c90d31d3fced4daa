#include "core/core_input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/core_errors.h"

namespace vlab {

namespace {

std::string Bytes(std::size_t n) {
  char text[48];
  if (n >= (std::size_t{1} << 20)) {
    std::snprintf(text, sizeof text, "%.3g MiB", static_cast<double>(n) / (1 << 20));
  } else {
    std::snprintf(text, sizeof text, "%zu bytes", n);
  }
  return text;
}

// what a non-regular file is, in words
std::string KindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

void CheckStat(const struct stat& st, const std::string& what, std::size_t max_bytes) {
  if (!S_ISREG(st.st_mode)) throw InputError(what + ": " + KindOf(st.st_mode) + ", not a regular file");
  if (static_cast<unsigned long long>(st.st_size) > max_bytes) {
    throw InputError(what + ": " + Bytes(static_cast<std::size_t>(st.st_size)) + ", over the " + Bytes(max_bytes) +
                     " an input file of this kind may have");
  }
}

// stat() first, so that a device or FIFO is never opened (opening one can block or act)
void StatPath(const std::string& path, const std::string& what, std::size_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw InputError(what + ": cannot open file (" + std::strerror(errno) + ")");
  }
  CheckStat(st, what, max_bytes);
}

// the length of the UTF-8 sequence starting at `at`, or 0 when it is not one
std::size_t SequenceLength(const unsigned char* s, std::size_t at, std::size_t size) {
  const unsigned char c = s[at];
  if (c < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;  // no overlong forms
    if (c == 0xED) hi = 0x9F;  // no surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;  // no overlong forms
    if (c == 0xF4) hi = 0x8F;  // nothing past U+10FFFF
  } else {
    return 0;
  }
  if (at + n > size) return 0;
  if (s[at + 1] < lo || s[at + 1] > hi) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (s[at + k] < 0x80 || s[at + k] > 0xBF) return 0;
  }
  return n;
}

}  // namespace

std::size_t FirstNonUtf8(const std::string& text) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t n = SequenceLength(s, at, text.size());
    if (n == 0) return at;
    at += n;
  }
  return std::string::npos;
}

void CheckUtf8(const std::string& where, const std::string& text) {
  const std::size_t bad = FirstNonUtf8(text);
  if (bad == std::string::npos) return;
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i < bad; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  char byte[8];
  std::snprintf(byte, sizeof byte, "0x%02X", static_cast<unsigned char>(text[bad]));
  throw InputError(where + ":" + std::to_string(line) + ":" + std::to_string(bad - line_start + 1) + ": byte " + byte +
                   " is not UTF-8 (input text must be UTF-8)");
}

void CheckInputFile(const std::string& path, const std::string& what, std::size_t max_bytes) {
  StatPath(path, what, max_bytes);
}

std::string ReadInputFile(const std::string& path, const std::string& what, std::size_t max_bytes) {
  StatPath(path, what, max_bytes);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(what + ": cannot open file (" + std::strerror(errno) + ")");
  std::string text;
  try {
    // the file may have been swapped since stat(): judge what was opened
    struct stat st {};
    if (::fstat(fd, &st) != 0) throw InputError(what + ": cannot read file (" + std::strerror(errno) + ")");
    CheckStat(st, what, max_bytes);
    // at most max_bytes + 1, so that a file that grew past the cap is seen
    text.resize(static_cast<std::size_t>(st.st_size) + 1);
    std::size_t got = 0;
    while (true) {
      if (got == text.size()) {
        if (text.size() > max_bytes) break;
        text.resize(std::min(max_bytes + 1, text.size() * 2));
      }
      const ssize_t n = ::read(fd, text.data() + got, text.size() - got);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw InputError(what + ": cannot read file (" + std::strerror(errno) + ")");
      if (n == 0) break;
      got += static_cast<std::size_t>(n);
    }
    if (got > max_bytes) {
      throw InputError(what + ": over the " + Bytes(max_bytes) + " an input file of this kind may have");
    }
    text.resize(got);
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  CheckUtf8(path, text);
  return text;
}

}  // namespace vlab
