// Small in-place edits of model files that keep everything else (comments, order, layout):
// only the edited values are rewritten, and the result is checked by loading it again.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace kccd::modelling {

/// Replaces the `points` and `radius` of body `body` in the model file at `path` with the given
/// YAML texts. Throws std::runtime_error (naming the file) when the body is missing or the
/// edited file would not load; the file is then left untouched.
void setBodyGeometry(const std::string& path, const std::string& body, const std::string& points_yaml,
                     const std::string& radius_yaml);

/// Sets `pairs: ignore:` of the model file at `path` to `pairs` (creating the keys if needed).
void setIgnoreList(const std::string& path, const std::vector<std::array<std::string, 2>>& pairs);

/// The same edits on text (`source` names it in messages); return the edited text.
std::string withBodyGeometry(const std::string& text, const std::string& source, const std::string& body,
                             const std::string& points_yaml, const std::string& radius_yaml);
std::string withIgnoreList(const std::string& text, const std::string& source,
                           const std::vector<std::array<std::string, 2>>& pairs);

/// A YAML flow list of name pairs, wrapped to lines of about 100 characters after `indent`.
std::string flowPairs(const std::vector<std::array<std::string, 2>>& pairs, int indent);

}  // namespace kccd::modelling
