// YAML text checked before it is built into a tree.
//
// yaml-cpp accepts a mapping with a key twice (the first wins) and shares the
// node an alias names, so a few lines of anchors and aliases ("billion laughs")
// become a tree of billions of nodes as soon as anything walks, copies or emits
// it. CheckYamlText reads the text as parser events, before any tree exists,
// and refuses both, and a nesting too deep for the recursive code that reads it.
#pragma once

#include <cstddef>
#include <string>

namespace vlab::lab {

/// Nodes a YAML document may expand to, an aliased node counted each time an
/// alias names it: 100,000, some 200 times the largest shipped scenario.
constexpr std::size_t kMaxYamlNodes = 100000;
/// Nesting depth of mappings and lists a YAML document may have.
constexpr int kMaxYamlDepth = 64;

/// Throws InputError unless `text` is at most one YAML document whose mappings
/// have no key twice ("WHERE:LINE: PATH: duplicate key (first at line N)"),
/// whose aliases expand to at most kMaxYamlNodes nodes and never name a node
/// they are inside, nested at most kMaxYamlDepth deep. Syntax errors are
/// "WHERE:LINE: malformed YAML: ...". `where` names the source: a file, whose
/// line numbers are given, or a flag (`lines` false: "--set K=V: ...", columns,
/// and "the value is not valid YAML: ..." for syntax errors).
void CheckYamlText(const std::string& where, const std::string& text, bool lines = true);

}  // namespace vlab::lab
