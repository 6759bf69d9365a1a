// Small edits of model text that keep everything else (comments, order, layout): only the
// edited values are rewritten, and the result is checked by loading it again. Also the number
// and list formats the tools write into model files.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/types.hpp"

namespace kccd::modelling {

/// An in-place model edit that cannot be made: one line naming the file and the place.
class EditError : public InputError {
 public:
  using InputError::InputError;
};

/// One `pairs: ignore` entry as written: two body names and why (User: no reason written).
struct IgnoreEntry {
  std::string a, b;
  IgnoreReason reason = IgnoreReason::User;
};

/// Replaces the `points` and `radius` of body `body` in model text (`source` names it in
/// messages) with the given YAML texts and returns the edited text. The body's `tolerance` (the
/// bound its old geometry met) becomes `tolerance_yaml`, or is removed when that is empty (the
/// new geometry's bound unknown). Throws EditError when the body is missing or the edited model
/// would not load.
std::string withBodyGeometry(const std::string& text, const std::string& source, const std::string& body,
                             const std::string& points_yaml, const std::string& radius_yaml,
                             const std::string& tolerance_yaml = "");
/// Sets `pairs: ignore:` of model text to `pairs` (creating the keys if needed); same errors.
std::string withIgnoreList(const std::string& text, const std::string& source, const std::vector<IgnoreEntry>& pairs);
/// A number as written into model files: 10 significant digits, rounded up when `up` (for radii,
/// which must not shrink).
std::string yamlNumber(double value, bool up = false);
/// `text` as a YAML scalar: double-quoted, with '"' and '\\' escaped and control bytes as \xNN; bare
/// when `bare_when_safe` and it holds only letters, digits and _ - . /.
std::string yamlQuoted(const std::string& text, bool bare_when_safe = false);
/// Points as a YAML flow list [[x, y, z], ...] with yamlNumber digits.
std::string flowPoints(std::span<const Vec3> points);

/// A YAML flow list of ignore entries (`[a, b]`, or `[a, b, reason]` when the reason is not User),
/// wrapped to lines of about 100 characters after `indent`.
std::string flowPairs(const std::vector<IgnoreEntry>& pairs, int indent);

}  // namespace kccd::modelling
