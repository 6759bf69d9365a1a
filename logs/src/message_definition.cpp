#include "kccd/logs/message_definition.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <set>

namespace kccd::logs {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

Primitive primitiveOf(std::string_view t, Dialect d) {
  static const std::pair<std::string_view, Primitive> table[] = {
      {"bool", Primitive::Bool},       {"byte", Primitive::Byte},     {"char", Primitive::Char},
      {"int8", Primitive::Int8},       {"uint8", Primitive::UInt8},   {"int16", Primitive::Int16},
      {"uint16", Primitive::UInt16},   {"int32", Primitive::Int32},   {"uint32", Primitive::UInt32},
      {"int64", Primitive::Int64},     {"uint64", Primitive::UInt64}, {"float32", Primitive::Float32},
      {"float64", Primitive::Float64}, {"string", Primitive::String}, {"wstring", Primitive::WString}};
  for (const auto& [name, p] : table)
    if (t == name) return p;
  if (d == Dialect::Ros1 && t == "time") return Primitive::Time;
  if (d == Dialect::Ros1 && t == "duration") return Primitive::Duration;
  return Primitive::None;
}

bool validName(std::string_view s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

bool validTypeName(std::string_view s) {
  if (s.empty()) return false;
  std::size_t start = 0;
  for (;;) {
    const std::size_t slash = s.find('/', start);
    if (!validName(s.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start)))
      return false;
    if (slash == std::string_view::npos) return true;
    start = slash + 1;
  }
}

// The package of a full name ("pkg/Type" -> "pkg"), empty without one.
std::string packageOf(const std::string& full) {
  const std::size_t slash = full.find('/');
  return slash == std::string::npos ? std::string() : full.substr(0, slash);
}

struct Section {
  std::string name;        // as written after "MSG:" (or the root's name)
  std::size_t first_line;  // 1-based line of its first text line
  std::vector<std::string_view> lines;
};

}  // namespace

std::string normalTypeName(std::string_view name) {
  std::string n(trim(name));
  const std::size_t a = n.find('/');
  if (a != std::string::npos) {
    const std::size_t b = n.find('/', a + 1);
    if (b != std::string::npos && n.find('/', b + 1) == std::string::npos) n = n.substr(0, a) + n.substr(b);
  }
  return n;
}

const MessageType* MessageDefinitions::find(const std::string& name) const {
  const auto it = types_.find(name);
  return it == types_.end() ? nullptr : &it->second;
}

MessageDefinitions MessageDefinitions::parse(std::string_view root_name, std::string_view text, Dialect dialect) {
  MessageDefinitions out;
  out.dialect_ = dialect;
  out.root_ = normalTypeName(root_name);
  if (!validTypeName(out.root_))
    throw DefinitionError(0, "the type name '" + std::string(root_name) + "' is not pkg/Type");
  // Split into sections: the root, then "MSG: name" after a line of '='.
  std::vector<Section> sections{{out.root_, 1, {}}};
  std::size_t line_no = 0;
  bool expect_msg = false;
  for (std::size_t start = 0; start <= text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(start, end - start);
    ++line_no;
    const std::string_view t = trim(line);
    if (!t.empty() && t.find_first_not_of('=') == std::string_view::npos && t.size() >= 3) {
      expect_msg = true;
    } else if (expect_msg && t.substr(0, 4) == "MSG:") {
      sections.push_back({normalTypeName(t.substr(4)), line_no + 1, {}});
      if (!validTypeName(sections.back().name))
        throw DefinitionError(line_no, "'" + std::string(t) + "': expected MSG: pkg/Type");
      expect_msg = false;
    } else {
      if (expect_msg && !t.empty())
        throw DefinitionError(line_no, "expected a 'MSG: pkg/Type' line after the line of '='");
      sections.back().lines.push_back(line);
    }
    if (end == text.size()) break;
    start = end + 1;
  }
  // Each section's fields.
  for (const Section& sec : sections) {
    std::string name = sec.name;
    // ROS 1 names dependencies without their package when they share it (and "Header").
    if (name.find('/') == std::string::npos) name = (name == "Header" ? "std_msgs" : packageOf(out.root_)) + "/" + name;
    if (out.types_.count(name)) continue;  // a dependency listed twice: the first wins
    MessageType type{name, {}};
    const std::string package = packageOf(name);
    for (std::size_t k = 0; k < sec.lines.size(); ++k) {
      const std::size_t at = sec.first_line + k;
      std::string_view l = sec.lines[k];
      l = trim(l.substr(0, l.find('#')));  // (a constant's string value may hold '#': constants are skipped)
      if (l.empty()) continue;
      const std::size_t sp = l.find_first_of(" \t");
      // A constant ("TYPE NAME=VALUE", "TYPE NAME = VALUE") is not a field; "<=" in a type is a bound.
      if (sp != std::string_view::npos) {
        const std::string_view after = trim(l.substr(sp));
        const std::size_t name_end = after.find_first_of(" \t=");
        if (name_end != std::string_view::npos && trim(after.substr(name_end)).substr(0, 1) == "=") continue;
      }
      if (sp == std::string_view::npos) throw DefinitionError(at, "'" + std::string(l) + "': expected TYPE NAME");
      std::string_view type_text = l.substr(0, sp);
      const std::string_view rest = trim(l.substr(sp));
      const std::string_view field_name =
          rest.substr(0, rest.find_first_of(" \t"));  // a ROS 2 default value may follow
      if (!validName(field_name)) throw DefinitionError(at, "'" + std::string(field_name) + "' is not a field name");
      Field f;
      f.name = std::string(field_name);
      if (const std::size_t bracket = type_text.find('['); bracket != std::string_view::npos) {
        if (type_text.back() != ']')
          throw DefinitionError(at, "'" + std::string(type_text) + "': an array type ends with ']'");
        std::string_view inside = type_text.substr(bracket + 1, type_text.size() - bracket - 2);
        type_text = type_text.substr(0, bracket);
        if (inside.empty() || inside.substr(0, 2) == "<=") {
          f.array = Field::Array::Dynamic;  // bounded arrays are sequences on the wire
        } else {
          std::size_t n = 0;
          const auto r = std::from_chars(inside.data(), inside.data() + inside.size(), n);
          if (r.ec != std::errc() || r.ptr != inside.data() + inside.size() || n > (1u << 24))
            throw DefinitionError(at, "'" + std::string(inside) + "': not an array length");
          f.array = Field::Array::Fixed;
          f.length = n;
        }
      }
      // Bounded strings ("string<=10") are strings on the wire.
      if (const std::size_t le = type_text.find("<="); le != std::string_view::npos)
        type_text = type_text.substr(0, le);
      f.primitive = primitiveOf(type_text, dialect);
      if (f.primitive == Primitive::None) {
        std::string t = normalTypeName(type_text);
        if (!validTypeName(t)) throw DefinitionError(at, "'" + std::string(type_text) + "' is not a type");
        if (t.find('/') == std::string::npos)
          t = (dialect == Dialect::Ros1 && t == "Header" ? "std_msgs" : package) + "/" + t;
        f.type_name = t;
      }
      type.fields.push_back(std::move(f));
    }
    out.types_.emplace(name, std::move(type));
  }
  // Every type used is defined, and no type contains itself (its messages would never end).
  std::set<std::string> done;
  std::vector<std::string> path;
  auto visit = [&](auto&& self, const std::string& n) -> void {
    if (done.count(n)) return;
    if (std::find(path.begin(), path.end(), n) != path.end())
      throw DefinitionError(0, "the type " + n + " contains itself");
    const MessageType* t = out.find(n);
    if (!t)
      throw DefinitionError(
          0, "the type " + n + " is used but not defined" + (path.empty() ? "" : " (in " + path.back() + ")"));
    path.push_back(n);
    for (const Field& f : t->fields)
      if (f.primitive == Primitive::None) self(self, f.type_name);
    path.pop_back();
    done.insert(n);
  };
  visit(visit, out.root_);
  return out;
}

}  // namespace kccd::logs
