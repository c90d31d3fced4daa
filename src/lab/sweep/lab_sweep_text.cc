#include "lab/sweep/lab_sweep_text.h"

#include <cstdio>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

bool IsControl(char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }

bool NodeHasControl(const YAML::Node& node) {
  if (node.IsScalar()) return HasControlCharacter(node.Scalar());
  if (node.IsSequence()) {
    for (const auto& item : node) {
      if (NodeHasControl(item)) return true;
    }
  } else if (node.IsMap()) {
    for (const auto& kv : node) {
      if (NodeHasControl(kv.first) || NodeHasControl(kv.second)) return true;
    }
  }
  return false;
}

// a scalar that was plain in its file and needs no quotes in a flow collection either
bool SafePlain(const YAML::Node& node) {
  const std::string& s = node.Scalar();
  if (node.Tag() != "?" || s.empty() || (s[0] == '-' && s.size() == 1)) return false;
  return s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._+-") == std::string::npos;
}

// YAML double quotes: \\, \" and \xHH for control characters; everything else as it is
std::string DoubleQuoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      q += '\\';
      q += c;
    } else if (IsControl(c)) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(c));
      q += hex;
    } else {
      q += c;
    }
  }
  return q + "\"";
}

// flow YAML, every scalar plain or in double quotes; stops once past the limit
// (a list of aliases can stand for far more text than its file holds)
void WriteFlow(const YAML::Node& node, std::string& out) {
  if (out.size() > kMaxValueText) return;
  if (node.IsSequence()) {
    out += '[';
    bool first = true;
    for (const auto& item : node) {
      out += first ? "" : ", ";
      first = false;
      WriteFlow(item, out);
      if (out.size() > kMaxValueText) return;
    }
    out += ']';
  } else if (node.IsMap()) {
    out += '{';
    bool first = true;
    for (const auto& kv : node) {
      out += first ? "" : ", ";
      first = false;
      WriteFlow(kv.first, out);
      out += ": ";
      WriteFlow(kv.second, out);
      if (out.size() > kMaxValueText) return;
    }
    out += '}';
  } else if (node.IsScalar()) {
    out += SafePlain(node) ? node.Scalar() : DoubleQuoted(node.Scalar());
  } else {
    out += '~';
  }
}

}  // namespace

bool HasControlCharacter(const std::string& text) {
  for (char c : text) {
    if (IsControl(c)) return true;
  }
  return false;
}

std::string Printable(const std::string& text) {
  std::string p;
  for (char c : text) {
    if (IsControl(c) || c == '\\') {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(c));
      p += hex;
    } else {
      p += c;
    }
  }
  return p;
}

std::string ValueText(const YAML::Node& node, const std::string& where) {
  std::string text;
  if (node.IsScalar() && !NodeHasControl(node)) {
    YAML::Emitter out;
    out << node;
    text = out.c_str();
  } else {
    WriteFlow(node, text);
  }
  if (text.size() > kMaxValueText) {
    throw InputError(where + ": the value is longer than " + std::to_string(kMaxValueText) +
                     " bytes as text (one command line argument holds at most 131072)");
  }
  if (HasControlCharacter(text)) throw InputError(where + ": the value cannot be written without control characters");
  return text;
}

std::string ShellQuote(const std::string& word) {
  if (!word.empty() &&
      word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=./:,@%") ==
          std::string::npos) {
    return word;
  }
  std::string quoted = "'";
  for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string JobLine(const std::vector<std::string>& words) {
  std::string line;
  for (const std::string& w : words) {
    if (HasControlCharacter(w)) {
      throw InputError("'" + Printable(w) +
                       "': holds a control character, which a job line cannot carry (a newline "
                       "would end the command there); rename it");
    }
    line += (line.empty() ? "" : " ") + ShellQuote(w);
  }
  return line;
}

}  // namespace vlab::lab
