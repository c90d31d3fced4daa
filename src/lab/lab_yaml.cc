#include "lab/lab_yaml.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

std::string Describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

}  // namespace

YAML::Node LoadYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("scenario '" + path + "': cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    throw InputError(path + ":" + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
  }
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
    if (item.first.Scalar() == key) at = item.second;
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
  if (!n.IsScalar() || !YAML::convert<long long>::decode(n, value) || value < -2147483647LL ||
      value > 2147483647LL) {
    throw InputError(YamlError(file_, n, Child(key), "expected an integer, got " + Describe(n)));
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
      throw InputError(YamlError(file_, n[i], Child(key) + "[" + std::to_string(i) + "]",
                                 "expected a name, got " + Describe(n[i])));
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
