#include "lab/scenario/lab_yaml_check.h"

#include <cstdint>
#include <map>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

// One open mapping or list.
struct Frame {
  bool map = false;
  YAML::anchor_t anchor = YAML::NullAnchor;
  std::uint64_t nodes = 1;                 // expanded nodes in it so far, itself included
  std::string path;                        // its key path ("" for the document)
  std::size_t items = 0;                   // nodes seen in it: in a mapping, keys and values alternate
  std::string key;                         // a mapping's key whose value comes next
  std::map<std::string, YAML::Mark> keys;  // a mapping's keys, where each first appeared
};

class Checker : public YAML::EventHandler {
 public:
  Checker(const std::string& where, bool lines) : where_(where), lines_(lines) {}

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1) Fail(mark, "", "a second YAML document ('---'); a file holds one");
  }
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { Leaf(mark, anchor, true, "~", 1); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, const std::string& value) override {
    Leaf(mark, anchor, true, value, 1);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto size = sizes_.find(anchor);
    if (size == sizes_.end()) Fail(mark, ChildPath(), "an alias inside the node it names (a cycle)");
    const auto scalar = scalars_.find(anchor);
    const bool is_scalar = scalar != scalars_.end();
    Leaf(mark, YAML::NullAnchor, is_scalar, is_scalar ? scalar->second : "", size->second);
  }

  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    Open(mark, anchor, false);
  }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    Open(mark, anchor, true);
  }
  void OnSequenceEnd() override { Close(); }
  void OnMapEnd() override { Close(); }

 private:
  [[noreturn]] void Fail(const YAML::Mark& mark, const std::string& path, const std::string& message) const {
    std::string at = where_;
    if (lines_ && mark.line >= 0) at += ":" + std::to_string(mark.line + 1);
    // a deep path is cut: its start locates it
    const std::string shown = path.size() > 100 ? path.substr(0, 60) + "..." : path;
    throw InputError(at + ": " + (shown.empty() ? "" : shown + ": ") + message);
  }

  std::string Place(const YAML::Mark& mark) const {
    return lines_ ? "line " + std::to_string(mark.line + 1) : "column " + std::to_string(mark.column + 1);
  }

  // the key path of the node that comes next
  std::string ChildPath() const {
    if (stack_.empty()) return "";
    const Frame& f = stack_.back();
    if (!f.map) return f.path + "[" + std::to_string(f.items) + "]";
    if (f.items % 2 == 0) return f.path;  // a key: messages name the mapping
    return f.path.empty() ? f.key : f.path + "." + f.key;
  }

  void Count(const YAML::Mark& mark, std::uint64_t nodes) {
    total_ += nodes;
    if (total_ > kMaxYamlNodes) {
      Fail(mark, ChildPath(),
           "the document expands to more than " + std::to_string(kMaxYamlNodes) +
               " nodes (each alias counts the nodes it names; an alias bomb?)");
    }
    if (!stack_.empty()) stack_.back().nodes += nodes;
  }

  // a node is complete: a mapping's key is checked for a repeat
  void Placed(const YAML::Mark& mark, bool scalar_key, const std::string& key) {
    if (stack_.empty()) return;
    Frame& f = stack_.back();
    if (f.map && f.items % 2 == 0 && scalar_key) {
      const auto [first, added] = f.keys.emplace(key, mark);
      if (!added) {
        const std::string path = f.path.empty() ? key : f.path + "." + key;
        Fail(mark, path, "duplicate key (first at " + Place(first->second) + ")");
      }
      f.key = key;
    } else if (f.map && f.items % 2 == 0) {
      f.key = "?";
    }
    ++f.items;
  }

  void Leaf(const YAML::Mark& mark, YAML::anchor_t anchor, bool scalar, const std::string& value, std::uint64_t nodes) {
    Count(mark, nodes);
    if (anchor != YAML::NullAnchor) {
      sizes_[anchor] = 1;
      scalars_[anchor] = value;
    }
    Placed(mark, scalar, value);
  }

  void Open(const YAML::Mark& mark, YAML::anchor_t anchor, bool map) {
    if (static_cast<int>(stack_.size()) >= kMaxYamlDepth) {
      Fail(mark, ChildPath(), "nested more than " + std::to_string(kMaxYamlDepth) + " deep");
    }
    const std::string path = ChildPath();
    Count(mark, 1);
    if (!stack_.empty()) stack_.back().nodes -= 1;  // counted again when this one closes
    marks_.push_back(mark);
    Frame f;
    f.map = map;
    f.anchor = anchor;
    f.path = path;
    stack_.push_back(std::move(f));
  }

  void Close() {
    const Frame f = std::move(stack_.back());
    stack_.pop_back();
    const YAML::Mark mark = marks_.back();
    marks_.pop_back();
    if (f.anchor != YAML::NullAnchor) sizes_[f.anchor] = f.nodes;
    if (!stack_.empty()) stack_.back().nodes += f.nodes;
    Placed(mark, false, "");
  }

  std::string where_;
  bool lines_ = true;
  int documents_ = 0;
  std::uint64_t total_ = 0;
  std::vector<Frame> stack_;
  std::vector<YAML::Mark> marks_;
  std::unordered_map<YAML::anchor_t, std::uint64_t> sizes_;  // expanded nodes of each finished anchor
  std::unordered_map<YAML::anchor_t, std::string> scalars_;  // the value of each scalar anchor
};

}  // namespace

void CheckYamlText(const std::string& where, const std::string& text, bool lines) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  Checker checker(where, lines);
  try {
    while (parser.HandleNextDocument(checker)) {
    }
  } catch (const YAML::Exception& e) {
    std::string at = where;
    if (lines && e.mark.line >= 0) at += ":" + std::to_string(e.mark.line + 1);
    throw InputError(at + (lines ? ": malformed YAML: " : ": the value is not valid YAML: ") + e.msg);
  }
}

}  // namespace vlab::lab
