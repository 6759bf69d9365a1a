#include "kccd/modelling/yaml_edit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "kccd/format_number.hpp"
#include "kccd/model.hpp"

namespace kccd::modelling {
namespace {

YAML::Node load(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw EditError(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

// End of a flow collection starting at `pos` ('[' or '{'), skipping quotes and comments.
std::size_t flowEnd(const std::string& t, std::size_t pos) {
  int depth = 0;
  for (std::size_t i = pos; i < t.size(); ++i) {
    const char c = t[i];
    if (c == '"' || c == '\'') {
      for (++i; i < t.size() && t[i] != c; ++i)
        if (c == '"' && t[i] == '\\') ++i;
    } else if (c == '#' && (i == 0 || std::isspace(static_cast<unsigned char>(t[i - 1])))) {
      while (i < t.size() && t[i] != '\n') ++i;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      if (--depth == 0) return i + 1;
    }
  }
  return t.size();
}

std::size_t lineStart(const std::string& t, std::size_t pos) {
  while (pos > 0 && t[pos - 1] != '\n') --pos;
  return pos;
}

int indentAt(const std::string& t, std::size_t line_start) {
  int n = 0;
  while (line_start + n < t.size() && t[line_start + n] == ' ') ++n;
  return n;
}

// End of the text of `value` (which starts at its mark).
std::size_t valueEnd(const std::string& t, const YAML::Node& value) {
  const std::size_t start = static_cast<std::size_t>(value.Mark().pos);
  if (start < t.size() && (t[start] == '[' || t[start] == '{')) return flowEnd(t, start);
  if (value.IsScalar()) {
    std::size_t i = start;
    if (t[i] == '"' || t[i] == '\'')
      return flowEnd(t, start) == t.size() ? t.size() : [&] {
        const char q = t[i];
        for (++i; i < t.size() && t[i] != q; ++i)
          if (q == '"' && t[i] == '\\') ++i;
        return i + 1;
      }();
    while (i < t.size() && t[i] != '\n' && t[i] != ',' && t[i] != ']' && t[i] != '}' &&
           !(t[i] == '#' && std::isspace(static_cast<unsigned char>(t[i - 1]))))
      ++i;
    while (i > start && std::isspace(static_cast<unsigned char>(t[i - 1]))) --i;
    return i;
  }
  // A block collection: the lines indented more than its first line, or list items at its column.
  const int column = static_cast<int>(value.Mark().column);
  std::size_t end = t.find('\n', start);
  if (end == std::string::npos) return t.size();
  std::size_t pos = end + 1;
  while (pos < t.size()) {
    std::size_t next = t.find('\n', pos);
    if (next == std::string::npos) next = t.size();
    const int ind = indentAt(t, pos);
    const bool blank = pos + ind >= next || t[pos + ind] == '#';
    if (!blank) {
      const bool item = ind == column && value.IsSequence() && t[pos + ind] == '-';
      if (ind <= column && !item) break;
      end = next;
    }
    pos = next + 1;
  }
  return end;
}

struct Found {
  YAML::Node key, value;
};

bool findKey(const YAML::Node& map, const std::string& name, Found& out) {
  if (!map.IsMap()) return false;
  for (auto it = map.begin(); it != map.end(); ++it)
    if (it->first.IsScalar() && it->first.Scalar() == name) {
      out = {it->first, it->second};
      return true;
    }
  return false;
}

// Replaces the value of `key` (from just after its ':' to the end of the value) with `text`.
std::string replaceValue(const std::string& t, const Found& f, const std::string& text) {
  const std::size_t colon = t.find(':', static_cast<std::size_t>(f.key.Mark().pos));
  const std::size_t end = f.value.IsNull() && f.value.Mark().pos <= f.key.Mark().pos ? colon + 1 : valueEnd(t, f.value);
  return t.substr(0, colon + 1) + " " + text + t.substr(end);
}

void check(const std::string& text, const std::string& source) {
  try {
    (void)parseModel(text, source + " (edited)");
  } catch (const ModelError& e) {
    throw EditError(std::string("the edited model would not load: ") + e.what());
  }
}

}  // namespace

std::string yamlQuoted(const std::string& text, bool bare_when_safe) {
  bool bare = bare_when_safe && !text.empty();
  for (const char c : text)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.' && c != '/') bare = false;
  if (bare) return text;
  std::string out = "\"";
  for (const char ch : text) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (u < 0x20 || u == 0x7f) {
      char buffer[5];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", u);
      out += buffer;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

std::string yamlNumber(double value, bool up) {
  const auto print = [](double v) { return formatNumber(v == 0.0 ? 0.0 : v, 10); };  // no "-0"
  std::string s = print(value);
  for (int i = 1; up && std::stod(s) < value && i < 64; ++i) s = print(value + std::abs(value) * 1e-10 * i);
  return s;
}

std::string flowPoints(std::span<const Vec3> points) {
  std::string s = "[";
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i) s += ", ";
    s.append("[").append(yamlNumber(points[i].x())).append(", ").append(yamlNumber(points[i].y()));
    s.append(", ").append(yamlNumber(points[i].z())).append("]");
  }
  return s + "]";
}

std::string flowPairs(const std::vector<IgnoreEntry>& pairs, int indent) {
  std::string s = "[", line;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    std::string item = "[";
    item.append(yamlQuoted(pairs[i].a, true)).append(", ").append(yamlQuoted(pairs[i].b, true));
    if (pairs[i].reason != IgnoreReason::User) item.append(", ").append(toString(pairs[i].reason));
    item.append("]");
    if (i > 0) {
      s += ",";
      if (line.size() + item.size() > 90) {
        s += '\n';
        s.append(static_cast<std::size_t>(indent), ' ');
        line.clear();
      } else {
        s += " ";
      }
    }
    s += item;
    line += item + ", ";
  }
  return s + "]";
}

std::string withBodyGeometry(const std::string& text, const std::string& source, const std::string& body,
                             const std::string& points_yaml, const std::string& radius_yaml,
                             const std::string& tolerance_yaml) {
  const YAML::Node root = load(text, source);
  const YAML::Node bodies = root["bodies"];
  if (!bodies || !bodies.IsSequence()) throw EditError(source + ": no bodies list");
  for (const YAML::Node& b : bodies) {
    if (!b.IsMap() || !b["name"] || b["name"].Scalar() != body) continue;
    Found points, radius, tolerance;
    if (!findKey(b, "points", points) || !findKey(b, "radius", radius))
      throw EditError(source + ":" + std::to_string(b.Mark().line + 1) + ": body " + body +
                      " has no points/radius to replace");
    const bool has_tolerance = findKey(b, "tolerance", tolerance);
    const bool flow = text[static_cast<std::size_t>(b.Mark().pos)] == '{';
    // The edits as (start, end, new text), made from the last to the first so earlier positions
    // stay valid. The old tolerance is the old geometry's bound: replaced, or dropped when none is given.
    struct Edit {
      std::size_t start, end;
      std::string text;
    };
    std::vector<Edit> edits;
    const auto valueEdit = [&](const Found& f, const std::string& value) {
      const std::size_t colon = text.find(':', static_cast<std::size_t>(f.key.Mark().pos));
      return Edit{colon + 1, valueEnd(text, f.value), " " + value};
    };
    edits.push_back(valueEdit(points, points_yaml));
    edits.push_back(valueEdit(radius, radius_yaml));
    if (has_tolerance && !tolerance_yaml.empty()) {
      edits.push_back(valueEdit(tolerance, tolerance_yaml));
    } else if (has_tolerance) {
      const std::size_t key = static_cast<std::size_t>(tolerance.key.Mark().pos), end = valueEnd(text, tolerance.value);
      const std::size_t line = lineStart(text, key);
      if (flow) {
        std::size_t comma = key;
        while (comma > 0 && text[comma - 1] != ',' && text[comma - 1] != '{') --comma;
        edits.push_back({comma > 0 && text[comma - 1] == ',' ? comma - 1 : key, end, ""});
      } else if (text.find_first_not_of(' ', line) == key) {  // a line of its own
        const std::size_t eol = text.find('\n', end);
        edits.push_back({line, eol == std::string::npos ? text.size() : eol + 1, ""});
      } else {
        throw EditError(source + ":" + std::to_string(tolerance.key.Mark().line + 1) + ": body " + body +
                        ": its tolerance is not on a line of its own; remove it by hand");
      }
    } else if (!tolerance_yaml.empty()) {
      const std::size_t at = valueEnd(text, radius.value);
      const int column = static_cast<int>(radius.key.Mark().column);
      edits.push_back(
          {at, at,
           flow ? ", tolerance: " + tolerance_yaml
                : "\n" + std::string(static_cast<std::size_t>(column), ' ') + "tolerance: " + tolerance_yaml});
    }
    std::sort(edits.begin(), edits.end(), [](const Edit& x, const Edit& y) { return x.start > y.start; });
    std::string out = text;
    for (const Edit& e : edits) out = out.substr(0, e.start) + e.text + out.substr(e.end);
    check(out, source);
    return out;
  }
  throw EditError(source + ": no body named '" + body + "'");
}

std::string withIgnoreList(const std::string& text, const std::string& source, const std::vector<IgnoreEntry>& pairs) {
  const YAML::Node root = load(text, source);
  std::string out;
  Found section;
  if (!findKey(root, "pairs", section) || section.value.IsNull()) {
    out = text;
    if (!out.empty() && out.back() != '\n') out += "\n";
    if (findKey(root, "pairs", section)) {  // `pairs:` with nothing under it
      out = replaceValue(text, section, "\n  ignore: " + flowPairs(pairs, 11));
    } else {
      out += "pairs:\n  ignore: " + flowPairs(pairs, 11) + "\n";
    }
  } else if (!section.value.IsMap()) {
    throw EditError(source + ":" + std::to_string(section.value.Mark().line + 1) + ": pairs is not a map");
  } else {
    Found ignore;
    if (findKey(section.value, "ignore", ignore)) {
      const int column = static_cast<int>(ignore.key.Mark().column);
      out = replaceValue(text, ignore, flowPairs(pairs, column + 9));
    } else {
      const std::size_t start = static_cast<std::size_t>(section.value.Mark().pos);
      if (text[start] == '{') {
        out = text.substr(0, start + 1) + "ignore: " + flowPairs(pairs, 4) + ", " + text.substr(start + 1);
      } else {
        const std::size_t line = lineStart(text, start);
        const int column = static_cast<int>(section.value.Mark().column);
        out = text.substr(0, line) + std::string(column, ' ') + "ignore: " + flowPairs(pairs, column + 9) + "\n" +
              text.substr(line);
      }
    }
  }
  check(out, source);
  return out;
}

}  // namespace kccd::modelling
