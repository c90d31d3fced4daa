// A sweep's values as text: the VALUE of each `vlab run --set KEY=VALUE`, and
// the job lines of `vlab sweep --list`.
//
// A job line is one line of text that GNU parallel, tools/vlab_sweep_array.sh
// (awk) and sh read in turn, and that people read before running it. Every
// value is written as YAML that reads back as the same value, on one line of
// printable characters: a string that holds a control character (0x01-0x1f,
// 0x7f) goes in YAML double quotes with \xHH escapes, which vlab's YAML reader
// turns back into those bytes. No raw control character is ever written: a
// newline would split the line into two commands, and a carriage return or an
// escape sequence would make the line look other than it is on a terminal. Each
// word is then quoted for POSIX sh. A word that cannot be written this way (a
// path or key holding a control character) is refused, never altered.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace vlab::lab {

/// The longest value text, bytes: one command line argument holds at most
/// 131072 bytes on Linux (MAX_ARG_STRLEN), and KEY= needs room beside it.
inline constexpr std::size_t kMaxValueText = 100000;

/// True when `text` holds a byte below 0x20 or 0x7f.
bool HasControlCharacter(const std::string& text);

/// `text` with each such byte, and the backslash, written as \xHH (for messages).
std::string Printable(const std::string& text);

/// `node` as one line of YAML (flow style) that reads back as the same value,
/// with no control character in it. A scalar without control characters is
/// written as yaml-cpp's emitter writes it (10, 0.5, a b, "a: b"). Throws
/// InputError("WHERE: ...") when the text would exceed kMaxValueText.
std::string ValueText(const YAML::Node& node, const std::string& where);

/// A command line word quoted for POSIX sh when it needs it: in single quotes,
/// a ' written as '\''. Every byte reads back as itself.
std::string ShellQuote(const std::string& word);

/// The words as one sh command line, each quoted. Throws InputError naming the
/// word when one holds a control character (it cannot go on a job line).
std::string JobLine(const std::vector<std::string>& words);

}  // namespace vlab::lab
