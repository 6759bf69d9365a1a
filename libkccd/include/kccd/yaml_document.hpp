// Structural checks of a YAML input before any node tree is built.
#pragma once

#include <string>
#include <string_view>

namespace kccd {

/// Limits of checkYamlDocument().
struct YamlLimits {
  int max_depth = 64;                ///< nested mappings and sequences
  std::size_t max_bytes = 64 << 20;  ///< size of the whole text
  /// Nodes the document holds with every alias counted as a copy of what it names: aliases of
  /// aliases would otherwise make a reader walk a few kilobytes as billions of values.
  std::size_t max_expanded_nodes = 4u << 20;
};

/// Checks that `text` holds at most one YAML document, that no mapping repeats a key, that every
/// key is a plain value, and that nesting and the nodes with aliases expanded stay within `limits`. Streams the
/// parser's events (no node tree), so hostile input costs time linear in its size. Throws InputError
/// ("source:line:column: field: problem", the field as a path such as joints[2].axis).
void checkYamlDocument(std::string_view text, const std::string& source, const YamlLimits& limits = {});

}  // namespace kccd
