// The state log CSV dialect (docs/formats.md section 6) and the state at a time. Every error is
// one line naming the file, the line and, where one applies, the column; reading stops at the first.
#include "kccd/state_log.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <system_error>
#include <unordered_map>
#include <unordered_set>

#include "kccd/file_reader.hpp"
#include "kccd/format_number.hpp"

namespace kccd {
namespace {

constexpr std::size_t kNoColumn = 0;

// One column of the header.
struct Column {
  enum class Kind : std::uint8_t { Time, Value, Velocity, Ignored } kind = Kind::Ignored;
  int index = 0;  // state value index (Value, Velocity)
  std::string_view name;
};

class Parser {
 public:
  explicit Parser(const std::string& source) : source_(printable(source, 1024)) {}

  [[noreturn]] void fail(std::size_t line, std::size_t col, std::string_view column, const std::string& problem) const {
    const std::string field = column.empty() ? std::string() : "column '" + printable(column, 60) + "'";
    throw StateLogError(InputLocation{source_, line, col, field}, problem);
  }

  // A number field: a C-locale decimal, finite, of magnitude at most kMaxStateLogMagnitude.
  double number(std::string_view field, std::size_t line, std::size_t col, std::string_view column) const {
    if (field.empty()) fail(line, col, column, "empty field (every field of a row needs a number)");
    const auto quoted = [&] {
      std::string q(1, '\'');
      return q.append(printable(field, 40)).append(1, '\'');
    };
    if (!isDecimal(field)) {
      const char first = field.front();
      const char last = field.back();
      if (first == ' ' || first == '\t' || last == ' ' || last == '\t')
        fail(line, col, column, "space around the number " + quoted() + " (the dialect has no padding)");
      if (first == '+') fail(line, col, column, "a leading '+' is not part of the dialect: " + quoted());
      std::string lower;
      for (const char c : field.substr(field.front() == '-' ? 1 : 0, 8))
        lower.push_back(static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c));
      if (lower.starts_with("inf") || lower.starts_with("nan"))
        fail(line, col, column, "must be a finite number, got " + quoted());
      fail(line, col, column, "not a decimal number: " + quoted());
    }
    double v = 0.0;
    const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), v);
    if (ec == std::errc::result_out_of_range) fail(line, col, column, quoted() + " is out of the range of a double");
    if (ec != std::errc() || end != field.data() + field.size())
      fail(line, col, column, "not a decimal number: " + quoted());
    if (!(std::abs(v) <= kMaxStateLogMagnitude))
      fail(line, col, column, quoted() + " is beyond the largest magnitude accepted (1e300)");
    return v;
  }

 private:
  static bool digit(char c) { return c >= '0' && c <= '9'; }

  // -?(D+(.D*)?|.D+)([eE][+-]?D+)?
  static bool isDecimal(std::string_view s) {
    std::size_t i = 0;
    const std::size_t n = s.size();
    if (i < n && s[i] == '-') ++i;
    std::size_t mantissa_digits = 0;
    while (i < n && digit(s[i])) ++i, ++mantissa_digits;
    if (i < n && s[i] == '.') {
      ++i;
      while (i < n && digit(s[i])) ++i, ++mantissa_digits;
    }
    if (mantissa_digits == 0) return false;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
      ++i;
      if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
      std::size_t exponent_digits = 0;
      while (i < n && digit(s[i])) ++i, ++exponent_digits;
      if (exponent_digits == 0) return false;
    }
    return i == n;
  }

  std::string source_;
};

// The lines of the text, one at a time, with the checks every line shares.
class Lines {
 public:
  Lines(std::string_view text, const Parser& parser) : text_(text), parser_(parser) {}

  // The next line without its line end (false at the end of the text). Checks: line ends LF or
  // CRLF, no empty line but one at the very end, no '"' and no comment line.
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const void* hit = std::memchr(text_.data() + pos_, '\n', text_.size() - pos_);
    const std::size_t end = hit ? static_cast<std::size_t>(static_cast<const char*>(hit) - text_.data()) : text_.size();
    line = text_.substr(pos_, end - pos_);
    const bool at_end = end + 1 >= text_.size();
    pos_ = end + 1;
    ++number_;
    if (hit && !line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (const std::size_t cr = line.find('\r'); cr != std::string_view::npos)
      parser_.fail(number_, cr + 1, {}, "a carriage return not followed by a line feed (line ends are LF or CRLF)");
    if (line.empty()) {
      if (number_ == 1)
        parser_.fail(1, kNoColumn, {}, "empty header line (expected time and the model's state value names)");
      if (at_end) return false;  // one empty line at the very end
      parser_.fail(number_, kNoColumn, {}, "empty line (the dialect has none between rows)");
    }
    if (line.front() == '#') parser_.fail(number_, 1, {}, "a comment line (the dialect has none)");
    if (const std::size_t quote = line.find('"'); quote != std::string_view::npos)
      parser_.fail(number_, quote + 1, {}, "a '\"': quoting is not part of the dialect");
    return true;
  }

  std::size_t number() const { return number_; }

 private:
  std::string_view text_;
  const Parser& parser_;
  std::size_t pos_ = 0;
  std::size_t number_ = 0;
};

std::vector<Column> parseHeader(std::string_view line, const Parser& parser, const Model& model,
                                std::span<const std::string> ignore_columns, StateLog& log) {
  const std::vector<std::string>& names = model.stateNames();
  std::unordered_map<std::string_view, int> values;  // state value name -> index
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "time")
      parser.fail(1, kNoColumn, names[i],
                  "the model has a state value named 'time', which a log cannot tell from its time column");
    if (!values.emplace(names[i], static_cast<int>(i)).second)
      parser.fail(1, kNoColumn, names[i], "the model names two state values so: a log cannot tell them apart");
  }
  for (const std::string& n : names)
    if (n.ends_with(".vel") && values.contains(std::string_view(n).substr(0, n.size() - 4)))
      parser.fail(1, kNoColumn, n,
                  "the model has a state value of this name, which a log cannot tell from a velocity column");
  const std::unordered_set<std::string_view> ignore(ignore_columns.begin(), ignore_columns.end());

  std::vector<Column> columns;
  std::unordered_map<std::string_view, std::size_t> seen;  // name -> byte column
  std::vector<std::uint8_t> has_value(names.size(), 0);
  bool has_time = false;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    const std::string_view name = line.substr(start, (comma == std::string_view::npos ? line.size() : comma) - start);
    const std::size_t col = start + 1;
    if (name.empty())
      parser.fail(1, col, {}, "empty column name (field " + std::to_string(columns.size() + 1) + " of the header)");
    if (const auto [it, fresh] = seen.emplace(name, col); !fresh)
      parser.fail(1, col, name, "named twice (also at 1:" + std::to_string(it->second) + ")");
    Column c;
    c.name = name;
    const bool ignored = ignore.contains(name);
    const auto value = values.find(name);
    if (name == "time" || value != values.end()) {
      if (ignored)
        parser.fail(1, col, name, "listed as ignored, but time and every state value of the model are required");
      c.kind = name == "time" ? Column::Kind::Time : Column::Kind::Value;
      if (c.kind == Column::Kind::Value) {
        c.index = value->second;
        has_value[static_cast<std::size_t>(c.index)] = 1;
      }
      has_time = has_time || c.kind == Column::Kind::Time;
    } else if (ignored) {
      c.kind = Column::Kind::Ignored;
      log.ignored.emplace_back(name);
    } else if (const auto of = name.ends_with(".vel") ? values.find(name.substr(0, name.size() - 4)) : values.end();
               of != values.end()) {
      c.kind = Column::Kind::Velocity;
      c.index = of->second;
      log.logged_velocity[static_cast<std::size_t>(c.index)] = 1;
    } else {
      const char first = name.front(), last = name.back();
      if (first == ' ' || first == '\t' || last == ' ' || last == '\t')
        parser.fail(1, col, name, "space around the name (the dialect has no padding)");
      parser.fail(1, col, name,
                  "unknown column (a state value of the model? see kccd info; a column to skip is listed as ignored)");
    }
    columns.push_back(c);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (!has_time) parser.fail(1, kNoColumn, "time", "missing (the sample times in seconds)");
  for (std::size_t i = 0; i < names.size(); ++i)
    if (!has_value[i])
      parser.fail(1, kNoColumn, names[i], "missing (a state value of the model: every one needs a column)");
  return columns;
}

}  // namespace

double StateLog::medianPeriod() const {
  if (times.size() < 2) return 0.0;
  std::vector<double> periods(times.size() - 1);
  for (std::size_t i = 0; i + 1 < times.size(); ++i) periods[i] = times[i + 1] - times[i];
  const std::size_t mid = periods.size() / 2;
  std::nth_element(periods.begin(), periods.begin() + static_cast<std::ptrdiff_t>(mid), periods.end());
  if (periods.size() % 2 == 1) return periods[mid];
  const double upper = periods[mid];
  const double lower = *std::max_element(periods.begin(), periods.begin() + static_cast<std::ptrdiff_t>(mid));
  return lower + (upper - lower) / 2;
}

StateLog parseStateLog(std::string_view text, const std::string& source, const Model& model,
                       std::span<const std::string> ignore_columns) {
  const Parser parser(source);
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  if (text.empty())
    parser.fail(1, kNoColumn, {}, "empty file (expected a header line: time and the model's state value names)");

  StateLog log;
  log.names = model.stateNames();
  const std::size_t n = log.names.size();
  log.circular.assign(n, 0);
  log.logged_velocity.assign(n, 0);
  for (const Joint& j : model.joints)
    if (j.type == JointType::Revolute && !j.limits) log.circular[static_cast<std::size_t>(j.state_offset)] = 1;

  Lines lines(text, parser);
  std::string_view line;
  lines.next(line);  // the text is not empty: a header line or an error
  const std::vector<Column> columns = parseHeader(line, parser, model, ignore_columns, log);
  const bool velocities =
      std::any_of(log.logged_velocity.begin(), log.logged_velocity.end(), [](std::uint8_t v) { return v != 0; });

  // Room for the rows the text can hold: each needs a byte per number, the commas and a line end,
  // so the numbers take at most about 4 bytes per byte of text (8 with velocity columns, stored
  // for every value), however hostile the text.
  const std::size_t parsed = static_cast<std::size_t>(
      std::count_if(columns.begin(), columns.end(), [](const Column& c) { return c.kind != Column::Kind::Ignored; }));
  const std::size_t expected_rows = std::min(static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1,
                                             text.size() / (parsed + columns.size()) + 1);
  log.times.reserve(expected_rows);
  log.values.reserve(expected_rows * n);
  if (velocities) log.velocities.reserve(expected_rows * n);

  const std::size_t commas = columns.size() - 1;
  while (lines.next(line)) {
    const std::size_t at = lines.number();
    const std::size_t found = static_cast<std::size_t>(std::count(line.begin(), line.end(), ','));
    if (found != commas)
      parser.fail(
          at, kNoColumn, {},
          std::to_string(found + 1) + " fields, but the header has " + std::to_string(columns.size()) + " columns");
    const std::size_t row = log.times.size();
    log.times.push_back(0.0);
    log.values.resize(log.values.size() + n);
    if (velocities) log.velocities.resize(log.velocities.size() + n, std::nan(""));
    std::size_t start = 0;
    for (const Column& c : columns) {
      std::size_t end = line.find(',', start);
      if (end == std::string_view::npos) end = line.size();
      const std::string_view field = line.substr(start, end - start);
      if (c.kind != Column::Kind::Ignored) {
        const double v = parser.number(field, at, start + 1, c.name);
        switch (c.kind) {
          case Column::Kind::Time:
            if (row > 0 && !(v > log.times[row - 1]))
              parser.fail(at, start + 1, c.name,
                          shortestNumber(v) + " is not after the previous row's " + shortestNumber(log.times[row - 1]) +
                              " (time must increase strictly)");
            log.times[row] = v;
            break;
          case Column::Kind::Value:
            log.values[row * n + static_cast<std::size_t>(c.index)] = v;
            break;
          case Column::Kind::Velocity:
            log.velocities[row * n + static_cast<std::size_t>(c.index)] = v;
            break;
          case Column::Kind::Ignored:
            break;
        }
      }
      start = end + 1;
    }
  }
  if (log.times.empty())
    parser.fail(1, kNoColumn, {}, "no data rows after the header (a log needs at least one sample)");
  return log;
}

StateLog loadStateLog(const std::string& path, const Model& model, std::span<const std::string> ignore_columns) {
  std::string text;
  try {
    text = readRegularFile(path, kMaxStateLogBytes, "state log");
  } catch (const FileError& e) {
    throw StateLogError(e.location(), e.problem());
  }
  return parseStateLog(text, path, model, ignore_columns);
}

const char* toString(StateMatch match) {
  switch (match) {
    case StateMatch::Exact:
      return "exact";
    case StateMatch::Interpolated:
      return "interpolated";
    case StateMatch::None:
      return "none";
  }
  return "?";
}

namespace {

// b - a, for an unwrapped value along the shorter arc (in [-pi, pi]).
double difference(double a, double b, bool circular) {
  const double d = b - a;
  return circular ? std::remainder(d, 2.0 * std::numbers::pi) : d;
}

}  // namespace

StateMatch stateAt(const StateLog& log, double time, double max_gap, std::span<double> state,
                   std::span<double> velocity) {
  const std::size_t n = log.names.size();
  if (state.size() != n || (!velocity.empty() && velocity.size() != n))
    throw std::invalid_argument("stateAt: state and velocity need the log's state size");
  const std::vector<double>& t = log.times;
  if (t.empty() || !std::isfinite(time)) return StateMatch::None;
  const auto value = [&](std::size_t row, std::size_t i) { return log.values[row * n + i]; };
  const bool logged_velocities = !log.velocities.empty();
  const auto logged = [&](std::size_t i) { return logged_velocities && log.logged_velocity[i] != 0; };
  const auto slope = [&](std::size_t a, std::size_t b, std::size_t i) {
    return difference(value(a, i), value(b, i), log.circular[i] != 0) / (t[b] - t[a]);
  };

  // First sample after `time`; the candidates for an exact match are it and the one before.
  const std::size_t after = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin());
  std::size_t nearest = t.size();
  double nearest_distance = kStateTimeTolerance;
  for (const std::size_t k : {after, after - 1}) {  // after - 1 wraps to a huge index when after == 0
    if (k >= t.size()) continue;
    const double distance = std::abs(t[k] - time);
    if (distance <= nearest_distance) {
      nearest = k;
      nearest_distance = distance;
    }
  }
  if (nearest < t.size()) {
    const std::size_t k = nearest;
    if (!velocity.empty()) {
      const bool has_before = k > 0 && t[k] - t[k - 1] <= max_gap;
      const bool has_after = k + 1 < t.size() && t[k + 1] - t[k] <= max_gap;
      if (!has_before && !has_after)
        for (std::size_t i = 0; i < n; ++i)
          if (!logged(i)) return StateMatch::None;  // a rate the log cannot give
      for (std::size_t i = 0; i < n; ++i) {
        if (logged(i)) {
          velocity[i] = log.velocities[k * n + i];
        } else if (has_before && has_after) {
          const bool c = log.circular[i] != 0;
          velocity[i] = (difference(value(k - 1, i), value(k, i), c) + difference(value(k, i), value(k + 1, i), c)) /
                        (t[k + 1] - t[k - 1]);
        } else {
          velocity[i] = has_before ? slope(k - 1, k, i) : slope(k, k + 1, i);
        }
      }
    }
    for (std::size_t i = 0; i < n; ++i) state[i] = value(k, i);
    return StateMatch::Exact;
  }
  if (after == 0 || after == t.size()) return StateMatch::None;  // before the first or after the last sample
  const std::size_t a = after - 1, b = after;
  if (!(t[b] - t[a] <= max_gap)) return StateMatch::None;
  const double f = (time - t[a]) / (t[b] - t[a]);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = difference(value(a, i), value(b, i), log.circular[i] != 0);
    // From the nearer sample, so an unwrapped value stays next to the value logged there.
    state[i] = f <= 0.5 ? value(a, i) + f * d : value(b, i) - (1.0 - f) * d;
    if (velocity.empty()) continue;
    if (logged(i)) {
      const double va = log.velocities[a * n + i], vb = log.velocities[b * n + i];
      velocity[i] = va + f * (vb - va);
    } else {
      velocity[i] = d / (t[b] - t[a]);
    }
  }
  return StateMatch::Interpolated;
}

}  // namespace kccd
