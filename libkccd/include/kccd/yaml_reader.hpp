// Reading a YAML input node by node (models, tag layouts, labels): every failure is one line
// "source:line:column: field: problem" with its location as data. Needs yaml-cpp: a target that
// includes this header links yaml-cpp itself.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstddef>
#include <initializer_list>
#include <string>

#include <Eigen/Core>

#include "kccd/input_error.hpp"
#include "kccd/yaml_document.hpp"

namespace kccd {

/// Reads the nodes of one YAML text; every failure is an InputError placed at the node it is about.
class YamlReader {
 public:
  /// A reader of the input shown as `source`; messages quote at most `quote_bytes` of a bad value.
  explicit YamlReader(std::string source, std::size_t quote_bytes = 80);

  /// The input as messages show it.
  const std::string& source() const { return source_; }

  /// The root of `text`, which must pass checkYamlDocument (one document, unique plain keys,
  /// bounded nesting) before yaml-cpp builds its nodes.
  YAML::Node load(const std::string& text, const YamlLimits& limits = {}) const;

  /// The location of `node` (its line and column when it has a place in the text) with `field`.
  InputLocation at(const YAML::Node& node, const std::string& field) const;
  /// "source:line:column" of `node` (just the source when it has no place).
  std::string where(const YAML::Node& node) const;
  /// Throws InputError(at(node, field), problem).
  [[noreturn]] void fail(const YAML::Node& node, const std::string& field, const std::string& problem) const;

  /// Checks that `map` is a mapping whose keys are all among `keys`.
  void onlyKeys(const YAML::Node& map, const std::string& field, std::initializer_list<const char*> keys) const;
  /// `map[key]`, which must be given and not null (the failure is placed at `map`).
  YAML::Node require(const YAML::Node& map, const char* key, const std::string& field) const;
  /// A non-empty UTF-8 string without control characters.
  std::string text(const YAML::Node& n, const std::string& field) const;
  /// A finite number.
  double number(const YAML::Node& n, const std::string& field) const;
  /// A finite number of magnitude at most `bound`; `unit` names the bound in the message.
  double bounded(const YAML::Node& n, const std::string& field, double bound, const std::string& unit) const;

  /// A list of exactly `N` finite numbers, each of magnitude at most `bound` (named by `unit`).
  template <int N>
  Eigen::Matrix<double, N, 1> vec(const YAML::Node& n, const std::string& field, double bound = HUGE_VAL,
                                  const std::string& unit = {}) const {
    checkList(n, field, N);
    Eigen::Matrix<double, N, 1> v;
    for (int k = 0; k < N; ++k) v[k] = bounded(n[k], field + "[" + std::to_string(k) + "]", bound, unit);
    return v;
  }

 private:
  void checkList(const YAML::Node& n, const std::string& field, int count) const;

  std::string source_;
  std::size_t quote_bytes_;
};

}  // namespace kccd
