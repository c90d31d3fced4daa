// Strict reading of YAML documents (scenario files).
//
// A MapReader reads one YAML mapping: every key the program asks for is marked
// as known, and Finish() rejects any other key. Every error is an InputError
// whose message names the file, the line, and the key path, e.g.
//   "scenes/reach.yaml:14: devices[0].filtr: unknown key (known: name, kind, ...)"
//   "scenes/reach.yaml:5: duration: expected a number, got 'ten'"
#pragma once

#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace vlab::lab {

/// Reads and parses a YAML file through ReadInputFile (a regular file of at most
/// kMaxYamlBytes, UTF-8) and CheckYamlText (one document, no duplicate keys,
/// aliases bounded); throws InputError naming the file as "KIND 'PATH'", or
/// "PATH:LINE" for a fault at a line.
YAML::Node LoadYamlFile(const std::string& path, const std::string& kind = "YAML file");

/// Parses YAML text read from `file` with the checks of LoadYamlFile but the
/// reading; InputError messages start "FILE:LINE".
YAML::Node ParseYamlText(const std::string& file, const std::string& text);

/// The largest seed: 2^53, the largest integer below which every integer is
/// exact in a double (JSON readers, the sweep table), so no two seeds collapse.
constexpr unsigned long long kMaxSeed = 9007199254740992ULL;
/// The range of a seed in words, for messages and --help.
inline constexpr char kSeedRange[] = "an integer from 0 to 9007199254740992 (2^53)";

/// Parses a seed written in decimal digits only, at most kMaxSeed; false when
/// `text` is not one (a sign, a point, an exponent, or out of range).
bool ParseSeed(const std::string& text, unsigned long long* seed);

/// A seed typed on the command line: "" when ParseSeed accepts it, and then
/// `text` is rewritten without leading zeros (CLI11 would read "010" as octal);
/// otherwise the problem ("must be an integer from 0 to ..., got 'TEXT'").
/// Used as a CLI11 validator, so that a seed is never clamped to fit.
std::string CheckSeedText(std::string& text);

/// A seed node: a scalar ParseSeed accepts; InputError "FILE:LINE: PATH: must be
/// a non-negative integer ..." otherwise.
unsigned long long YamlSeed(const std::string& file, const YAML::Node& node, const std::string& path);

/// "FILE:LINE" of a node (FILE alone for a node without a line).
std::string YamlWhere(const std::string& file, const YAML::Node& node);

/// Formats "FILE:LINE: PATH: MESSAGE" for a node.
std::string YamlError(const std::string& file, const YAML::Node& node, const std::string& path,
                      const std::string& message);

class MapReader {
 public:
  /// `path` names this mapping in messages ("" for the document root).
  MapReader(std::string file, YAML::Node node, std::string path);

  bool Has(const std::string& key);
  /// Required values: InputError when missing or of the wrong type.
  double Number(const std::string& key);
  std::string String(const std::string& key);
  /// Optional values with a default.
  double Number(const std::string& key, double fallback);
  /// An integer from -2147483647 to 2147483647, never rounded or clamped.
  int Integer(const std::string& key, int fallback);
  bool Bool(const std::string& key, bool fallback);
  std::string String(const std::string& key, const std::string& fallback);
  std::vector<double> Numbers(const std::string& key, std::vector<double> fallback);
  std::vector<std::string> Strings(const std::string& key, std::vector<std::string> fallback);
  /// A nested mapping (required to be a map when present; empty map when absent).
  MapReader Map(const std::string& key);
  /// A sequence node (empty when absent); InputError if present but not a sequence.
  YAML::Node Sequence(const std::string& key);
  /// The raw node of a key (marks it known); Null node when absent.
  YAML::Node Raw(const std::string& key);

  /// Throws InputError on the first key that was never asked for.
  void Finish() const;

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  const YAML::Node& node() const { return node_; }
  /// Key path of a child ("devices[0].filter").
  std::string Child(const std::string& key) const;
  [[noreturn]] void Fail(const std::string& key, const std::string& message) const;

 private:
  YAML::Node Get(const std::string& key);

  std::string file_;
  YAML::Node node_;
  std::string path_;
  std::set<std::string> known_;
};

/// Converts a scalar node, with errors in the MapReader style.
double YamlNumber(const std::string& file, const YAML::Node& node, const std::string& path);
std::vector<double> YamlNumbers(const std::string& file, const YAML::Node& node, const std::string& path);

}  // namespace vlab::lab
