// Shared by the calibration input readers (tag layouts, labels): a bounded regular-file read and
// a yaml-cpp reader whose every error is one line "source:line:col: field: problem" thrown as the
// reader's own InputError subclass. Internal to kccd_calib.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <string>

#include <Eigen/Core>

#include "kccd/input_error.hpp"
#include "kccd/yaml_document.hpp"

namespace kccd::calib::detail {

/// The whole file at `path`, refusing anything that is not a regular file (without blocking on a
/// FIFO or device) and anything larger than `max_bytes`. Throws InputError("path: file: problem").
std::string readInputFile(const std::string& path, std::size_t max_bytes, const char* what);

/// Reads nodes of one YAML text; E is the InputError subclass every failure is thrown as.
template <class E>
class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  const std::string& source() const { return source_; }

  /// The checked root: one document, unique plain keys, bounded nesting, parsed by yaml-cpp.
  YAML::Node load(const std::string& text) const {
    try {
      checkYamlDocument(text, source_);
    } catch (const E&) {
      throw;
    } catch (const InputError& e) {
      throw E(e.what());
    }
    try {
      return YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw E(source_ + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
              ": yaml: syntax error: " + printable(e.msg, 100));
    }
  }

  /// "source:line:col" of a node (just "source" when it has no place).
  std::string where(const YAML::Node& node) const {
    std::string at = source_;
    if (node.IsDefined() && node.Mark().line >= 0) {
      at.append(1, ':').append(std::to_string(node.Mark().line + 1));
      at.append(1, ':').append(std::to_string(node.Mark().column + 1));
    }
    return at;
  }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& field, const std::string& problem) const {
    throw E(where(node) + ": " + field + ": " + problem);
  }

  void onlyKeys(const YAML::Node& map, const std::string& field, std::initializer_list<const char*> keys) const {
    if (!map.IsMap()) fail(map, field, "expected a mapping");
    for (const auto& kv : map) {
      const std::string k = kv.first.Scalar();
      if (std::none_of(keys.begin(), keys.end(), [&](const char* allowed) { return k == allowed; }))
        fail(kv.first, field + "." + printable(k, 40), "unknown field");
    }
  }

  YAML::Node require(const YAML::Node& map, const char* key, const std::string& field) const {
    YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) fail(map, field + "." + key, "required field is missing");
    return n;
  }

  std::string text(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(n, field, "expected a string");
    if (n.Scalar().empty()) fail(n, field, "must not be empty");
    for (const char c : n.Scalar())
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F)
        fail(n, field, "contains a control character: '" + printable(n.Scalar(), 40) + "'");
    if (!isUtf8(n.Scalar())) fail(n, field, "is not UTF-8 text: '" + printable(n.Scalar(), 40) + "'");
    return n.Scalar();
  }

  double number(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) fail(n, field, "expected a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(n, field, "expected a number, got '" + printable(n.Scalar(), 40) + "'");
    }
    if (!std::isfinite(v)) fail(n, field, "must be finite");
    return v;
  }

  /// A finite number of magnitude at most `bound`; `unit` names the bound in the message.
  double bounded(const YAML::Node& n, const std::string& field, double bound, const std::string& unit) const {
    const double v = number(n, field);
    if (std::abs(v) > bound) fail(n, field, "beyond the largest magnitude accepted (" + unit + ")");
    return v;
  }

  /// A list of exactly `N` finite numbers, each of magnitude at most `bound`.
  template <int N>
  Eigen::Matrix<double, N, 1> vec(const YAML::Node& n, const std::string& field, double bound, const std::string& unit) const {
    if (!n.IsSequence()) fail(n, field, "expected a list of " + std::to_string(N) + " numbers");
    if (n.size() != N) fail(n, field, "expected " + std::to_string(N) + " numbers, got " + std::to_string(n.size()));
    Eigen::Matrix<double, N, 1> v;
    for (int k = 0; k < N; ++k) v[k] = bounded(n[k], field + "[" + std::to_string(k) + "]", bound, unit);
    return v;
  }

 private:
  std::string source_;
};

}  // namespace kccd::calib::detail
