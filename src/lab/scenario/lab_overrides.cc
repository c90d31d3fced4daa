#include "lab/scenario/lab_overrides.h"

#include <cctype>
#include <cstdio>

#include "core/core_errors.h"
#include "core/core_input_file.h"
#include "lab/scenario/lab_yaml_check.h"

namespace vlab::lab {

namespace {

std::string Flag(const Override& o) { return "--set " + o.key + "=" + o.value; }

std::vector<std::string> Segments(const std::string& key) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = key.find('.', start);
    parts.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) return parts;
    start = dot + 1;
  }
}

bool IsIndex(const std::string& s) {
  if (s.empty() || s.size() > 9) return false;
  for (char c : s) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

// A copy of `node` with no source marks, so that messages about it do not point
// at a line of the scenario file.
YAML::Node Unmarked(const YAML::Node& node) {
  if (node.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& item : node) out.push_back(Unmarked(item));
    return out;
  }
  if (node.IsMap()) {
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& item : node) out[item.first.Scalar()] = Unmarked(item.second);
    return out;
  }
  if (node.IsScalar()) return YAML::Node(node.Scalar());
  return YAML::Node(std::string());
}

YAML::Node ParseValue(const Override& o) {
  // duplicate keys, alias bombs and deep nesting are refused before a tree exists
  CheckYamlText(Flag(o), o.value, false);
  try {
    return Unmarked(YAML::Load(o.value));
  } catch (const YAML::Exception& e) {
    throw InputError(Flag(o) + ": the value is not valid YAML: " + e.msg);
  }
}

// The index of the list item named `segment` (its `name` key), or the item at
// that index; -1 when there is none.
long FindItem(const YAML::Node& list, const std::string& segment) {
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node item = list[i];
    if (!item.IsMap()) continue;
    for (const auto& kv : item) {
      if (kv.first.Scalar() == "name" && kv.second.IsScalar() && kv.second.Scalar() == segment) {
        return static_cast<long>(i);
      }
    }
  }
  if (IsIndex(segment) && std::stoul(segment) < list.size()) return static_cast<long>(std::stoul(segment));
  return -1;
}

std::string ItemNames(const YAML::Node& list) {
  std::string names;
  for (std::size_t i = 0; i < list.size(); ++i) {
    std::string name = std::to_string(i);
    if (list[i].IsMap() && list[i]["name"] && list[i]["name"].IsScalar()) name = list[i]["name"].Scalar();
    names += (names.empty() ? "" : ", ") + name;
  }
  return names.empty() ? "the list is empty" : "items: " + names;
}

bool HasKey(const YAML::Node& map, const std::string& key) {
  for (const auto& kv : map) {
    if (kv.first.IsScalar() && kv.first.Scalar() == key) return true;
  }
  return false;
}

}  // namespace

Override ParseOverride(const std::string& text) {
  const std::size_t bad = FirstNonUtf8(text);
  if (bad != std::string::npos) {
    char byte[8];
    std::snprintf(byte, sizeof byte, "0x%02X", static_cast<unsigned char>(text[bad]));
    throw InputError("--set: byte " + std::string(byte) + " at column " + std::to_string(bad + 1) +
                     " of KEY=VALUE is not UTF-8 (input text must be UTF-8)");
  }
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos) {
    throw InputError("--set '" + text +
                     "': expected KEY=VALUE (KEY a dotted scenario path, e.g. devices.jr3.filter=2)");
  }
  Override o{text.substr(0, eq), text.substr(eq + 1)};
  for (const std::string& segment : Segments(o.key)) {
    if (segment.empty()) throw InputError("--set '" + text + "': KEY has an empty part (expected a.b.c)");
  }
  return o;
}

std::vector<std::string> ReadOverridesFile(const std::string& path) {
  const std::string text = ReadInputFile(path, "overrides file '" + path + "'", kMaxYamlBytes);
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (int number = 1; start < text.size(); ++number) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    try {
      ParseOverride(line);
    } catch (const InputError& e) {
      throw InputError(path + ":" + std::to_string(number) + ": " + e.what());
    }
    lines.push_back(line);
  }
  return lines;
}

std::vector<std::string> ApplyOverrides(const std::string& file, YAML::Node root,
                                        const std::vector<Override>& overrides) {
  std::vector<std::string> paths;
  for (const Override& o : overrides) {
    const std::vector<std::string> segments = Segments(o.key);
    const YAML::Node value = ParseValue(o);
    // walk to the parent of the last segment; reset() rebinds, '=' would assign
    YAML::Node at;
    at.reset(root);
    std::string path;
    for (std::size_t i = 0; i < segments.size(); ++i) {
      const std::string& segment = segments[i];
      const bool last = i + 1 == segments.size();
      if (at.IsSequence()) {
        const long index = FindItem(at, segment);
        if (index < 0) {
          throw InputError(file + ": " + Flag(o) + ": " + (path.empty() ? "the document" : path) +
                           " has no item named '" + segment + "' (" + ItemNames(at) + ")");
        }
        path += "[" + std::to_string(index) + "]";
        if (last) {
          at[static_cast<std::size_t>(index)] = value;
        } else {
          at.reset(at[static_cast<std::size_t>(index)]);
        }
        continue;
      }
      if (!at.IsMap()) {
        throw InputError(file + ": " + Flag(o) + ": " + path + " is a value, not a mapping or a list; cannot set '" +
                         segment + "' in it");
      }
      path += (path.empty() ? "" : ".") + segment;
      if (last) {
        at[segment] = value;
      } else {
        // a missing mapping on the way is created; the parser then judges its keys
        if (!HasKey(at, segment)) at[segment] = YAML::Node(YAML::NodeType::Map);
        at.reset(at[segment]);
      }
    }
    paths.push_back(path);
  }
  return paths;
}

}  // namespace vlab::lab
