#include "lab/scenario/lab_yaml.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "lab/scenario/lab_yaml_check.h"

namespace vlab::lab {

namespace {

std::string Describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

// a scalar of decimal digits with an optional sign, whatever its size
bool LooksInteger(const YAML::Node& node) {
  if (!node.IsScalar()) return false;
  const std::string& s = node.Scalar();
  const std::size_t from = !s.empty() && (s[0] == '-' || s[0] == '+') ? 1 : 0;
  if (from >= s.size()) return false;
  for (std::size_t i = from; i < s.size(); ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
  }
  return true;
}

}  // namespace

YAML::Node LoadYamlFile(const std::string& path, const std::string& kind) {
  return ParseYamlText(path, ReadInputFile(path, kind + " '" + path + "'", kMaxYamlBytes));
}

YAML::Node ParseYamlText(const std::string& file, const std::string& text) {
  CheckYamlText(file, text);
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(file + ":" + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
  }
}

bool ParseSeed(const std::string& text, unsigned long long* seed) {
  if (text.empty() || text.size() > 20) return false;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
  }
  errno = 0;
  const unsigned long long value = std::strtoull(text.c_str(), nullptr, 10);
  if (errno == ERANGE || value > kMaxSeed) return false;
  *seed = value;
  return true;
}

std::string CheckSeedText(std::string& text) {
  unsigned long long seed = 0;
  if (!ParseSeed(text, &seed)) return std::string("must be ") + kSeedRange + ", got '" + text + "'";
  text = std::to_string(seed);
  return "";
}

unsigned long long YamlSeed(const std::string& file, const YAML::Node& node, const std::string& path) {
  unsigned long long seed = 0;
  if (!node.IsScalar() || !ParseSeed(node.Scalar(), &seed)) {
    throw InputError(YamlError(
        file, node, path, "must be a non-negative integer, at most 9007199254740992 (2^53); got " + Describe(node)));
  }
  return seed;
}

std::string YamlWhere(const std::string& file, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? file + ":" + std::to_string(mark.line + 1) : file;
}

std::string YamlError(const std::string& file, const YAML::Node& node, const std::string& path,
                      const std::string& message) {
  return YamlWhere(file, node) + ": " + (path.empty() ? "" : path + ": ") + message;
}

double YamlNumber(const std::string& file, const YAML::Node& node, const std::string& path) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
    throw InputError(YamlError(file, node, path, "expected a finite number, got " + Describe(node)));
  }
  return value;
}

std::vector<double> YamlNumbers(const std::string& file, const YAML::Node& node, const std::string& path) {
  if (!node.IsSequence()) {
    throw InputError(YamlError(file, node, path, "expected a list of numbers, got " + Describe(node)));
  }
  std::vector<double> values;
  for (std::size_t i = 0; i < node.size(); ++i) {
    values.push_back(YamlNumber(file, node[i], path + "[" + std::to_string(i) + "]"));
  }
  return values;
}

MapReader::MapReader(std::string file, YAML::Node node, std::string path)
    : file_(std::move(file)), node_(std::move(node)), path_(std::move(path)) {
  if (!node_.IsMap()) {
    throw InputError(YamlError(file_, node_, path_, "expected a mapping, got " + Describe(node_)));
  }
}

std::string MapReader::Child(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

void MapReader::Fail(const std::string& key, const std::string& message) const {
  YAML::Node at = node_;
  for (const auto& item : node_) {
    if (item.first.Scalar() == key) at.reset(item.second);
  }
  throw InputError(YamlError(file_, at, Child(key), message));
}

YAML::Node MapReader::Get(const std::string& key) {
  known_.insert(key);
  for (const auto& item : node_) {
    if (item.first.IsScalar() && item.first.Scalar() == key) return item.second;
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

bool MapReader::Has(const std::string& key) {
  known_.insert(key);
  return Get(key).IsDefined();
}

YAML::Node MapReader::Raw(const std::string& key) { return Get(key); }

double MapReader::Number(const std::string& key) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) throw InputError(YamlError(file_, node_, Child(key), "missing required key"));
  return YamlNumber(file_, n, Child(key));
}

double MapReader::Number(const std::string& key, double fallback) {
  YAML::Node n = Get(key);
  return n.IsDefined() ? YamlNumber(file_, n, Child(key)) : fallback;
}

int MapReader::Integer(const std::string& key, int fallback) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) return fallback;
  long long value = 0;
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, value) || value < -2147483647LL || value > 2147483647LL) {
    const std::string what = LooksInteger(n) ? "out of range: expected an integer from -2147483647 to 2147483647, got "
                                             : "expected an integer, got ";
    throw InputError(YamlError(file_, n, Child(key), what + Describe(n)));
  }
  return static_cast<int>(value);
}

bool MapReader::Bool(const std::string& key, bool fallback) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) return fallback;
  bool value = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, value)) {
    throw InputError(YamlError(file_, n, Child(key), "expected true or false, got " + Describe(n)));
  }
  return value;
}

std::string MapReader::String(const std::string& key) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) throw InputError(YamlError(file_, node_, Child(key), "missing required key"));
  if (!n.IsScalar()) throw InputError(YamlError(file_, n, Child(key), "expected a string, got " + Describe(n)));
  return n.Scalar();
}

std::string MapReader::String(const std::string& key, const std::string& fallback) {
  return Has(key) ? String(key) : fallback;
}

std::vector<double> MapReader::Numbers(const std::string& key, std::vector<double> fallback) {
  YAML::Node n = Get(key);
  return n.IsDefined() ? YamlNumbers(file_, n, Child(key)) : fallback;
}

std::vector<std::string> MapReader::Strings(const std::string& key, std::vector<std::string> fallback) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) return fallback;
  if (!n.IsSequence()) {
    throw InputError(YamlError(file_, n, Child(key), "expected a list of names, got " + Describe(n)));
  }
  std::vector<std::string> values;
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar()) {
      throw InputError(
          YamlError(file_, n[i], Child(key) + "[" + std::to_string(i) + "]", "expected a name, got " + Describe(n[i])));
    }
    values.push_back(n[i].Scalar());
  }
  return values;
}

MapReader MapReader::Map(const std::string& key) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) return MapReader(file_, YAML::Node(YAML::NodeType::Map), Child(key));
  return MapReader(file_, n, Child(key));
}

YAML::Node MapReader::Sequence(const std::string& key) {
  YAML::Node n = Get(key);
  if (!n.IsDefined()) return YAML::Node(YAML::NodeType::Sequence);
  if (!n.IsSequence()) throw InputError(YamlError(file_, n, Child(key), "expected a list, got " + Describe(n)));
  return n;
}

void MapReader::Finish() const {
  for (const auto& item : node_) {
    const std::string key = item.first.IsScalar() ? item.first.Scalar() : "?";
    if (known_.count(key)) continue;
    std::string list;
    for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
    throw InputError(YamlError(file_, item.first, Child(key), "unknown key (known: " + list + ")"));
  }
}

}  // namespace vlab::lab
