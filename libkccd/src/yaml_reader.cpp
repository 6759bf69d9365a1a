#include "kccd/yaml_reader.hpp"

#include <algorithm>

namespace kccd {

YamlReader::YamlReader(std::string source, std::size_t quote_bytes)
    : source_(std::move(source)), quote_bytes_(quote_bytes) {}

YAML::Node YamlReader::load(const std::string& text, const YamlLimits& limits) const {
  checkYamlDocument(text, source_, limits);
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {  // the check above parsed the same text: not expected
    InputLocation where{source_, 0, 0, {}};
    if (e.mark.line >= 0) {
      where.line = static_cast<std::size_t>(e.mark.line) + 1;
      where.column = static_cast<std::size_t>(e.mark.column) + 1;
    }
    throw InputError(std::move(where), "YAML syntax error: " + printable(e.msg, 120));
  }
}

InputLocation YamlReader::at(const YAML::Node& node, const std::string& field) const {
  InputLocation where{source_, 0, 0, field};
  if (node.IsDefined() && node.Mark().line >= 0) {
    where.line = static_cast<std::size_t>(node.Mark().line) + 1;
    where.column = static_cast<std::size_t>(node.Mark().column) + 1;
  }
  return where;
}

std::string YamlReader::where(const YAML::Node& node) const { return at(node, {}).text(); }

void YamlReader::fail(const YAML::Node& node, const std::string& field, const std::string& problem) const {
  throw InputError(at(node, field), problem);
}

void YamlReader::onlyKeys(const YAML::Node& map, const std::string& field,
                          std::initializer_list<const char*> keys) const {
  if (!map.IsMap()) fail(map, field, "expected a mapping");
  for (const auto& kv : map) {
    const std::string k = kv.first.Scalar();
    if (std::none_of(keys.begin(), keys.end(), [&](const char* allowed) { return k == allowed; }))
      fail(kv.first, field + "." + printable(k, 40), "unknown field");
  }
}

YAML::Node YamlReader::require(const YAML::Node& map, const char* key, const std::string& field) const {
  YAML::Node n = map[key];
  if (!n.IsDefined() || n.IsNull()) fail(map, field + "." + key, "required field is missing");
  return n;
}

std::string YamlReader::text(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) fail(n, field, "expected a string");
  if (n.Scalar().empty()) fail(n, field, "must not be empty");
  for (const char c : n.Scalar())
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F)
      fail(n, field, "contains a control character: '" + printable(n.Scalar(), quote_bytes_) + "'");
  if (!isUtf8(n.Scalar())) fail(n, field, "is not UTF-8 text: '" + printable(n.Scalar(), quote_bytes_) + "'");
  return n.Scalar();
}

double YamlReader::number(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) fail(n, field, "expected a number");
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    fail(n, field, "expected a number, got '" + printable(n.Scalar(), quote_bytes_) + "'");
  }
  if (!std::isfinite(v)) fail(n, field, "must be finite");
  return v;
}

double YamlReader::bounded(const YAML::Node& n, const std::string& field, double bound, const std::string& unit) const {
  const double v = number(n, field);
  if (std::abs(v) > bound) fail(n, field, "beyond the largest magnitude accepted (" + unit + ")");
  return v;
}

void YamlReader::checkList(const YAML::Node& n, const std::string& field, int count) const {
  if (!n.IsSequence()) fail(n, field, "expected a list of " + std::to_string(count) + " numbers");
  if (n.size() != static_cast<std::size_t>(count))
    fail(n, field, "expected " + std::to_string(count) + " numbers, got " + std::to_string(n.size()));
}

}  // namespace kccd
