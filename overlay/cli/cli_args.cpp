#include "cli_args.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <map>
#include <regex>
#include <sstream>

#include "cli_output.hpp"

namespace kccd::cli {

std::string optionMessage(const std::string& text) {
  // CLI11 writes bounds such as DBL_MAX with every digit: shorten long numbers.
  static const std::regex long_number("[-+]?[0-9]{16,}(\\.[0-9]*)?(e[-+]?[0-9]+)?");
  std::string out;
  auto it = std::sregex_iterator(text.begin(), text.end(), long_number);
  std::size_t last = 0;
  for (; it != std::sregex_iterator(); ++it) {
    out += text.substr(last, it->position() - last);
    out += formatNumber(std::strtod(it->str().c_str(), nullptr), 6);
    last = it->position() + it->length();
  }
  out += text.substr(last);
  // CLI11's phrasing, said plainly.
  static const std::pair<std::regex, const char*> plain[] = {
      {std::regex("^(\\S+): [0-9]+ required \\S+ missing$"), "$1: needs a value"},
      {std::regex("^The following arguments? (was|were) not expected: (.*)$"), "unknown option or extra argument: $2"},
      {std::regex("^--([A-Za-z-]+): Value (.*) not in range (.*) to (.*)$"),
       "--$1: expected a whole number from $3 to $4, got '$2'"},
      {std::regex("^(.*) is required$"), "$1 is required"},
  };
  for (const auto& [pattern, replacement] : plain)
    if (std::regex_match(out, pattern)) {
      out = std::regex_replace(out, pattern, replacement);
      break;
    }
  return oneLine(out);
}

CLI::Validator seedNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t v = 0;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || end != text.data() + text.size())
          return "expected a whole number 0 ... 18446744073709551615, got '" + printable(text, 40) + "'";
        return std::string();
      },
      "SEED");
}

CLI::Validator finiteIn(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        if (text.empty() || end != begin + text.size()) return "'" + printable(text, 40) + "' is not a number";
        if (!std::isfinite(v)) return "must be a finite number, got '" + printable(text, 40) + "'";
        if (v < lo || v > hi)
          return "must be in [" + formatNumber(lo, 6) + ", " + formatNumber(hi, 6) + "], got " + formatNumber(v, 6);
        return std::string();
      },
      "NUMBER in [" + formatNumber(lo, 6) + ", " + formatNumber(hi, 6) + "]");
}

std::vector<double> parseList(const std::string& text, const std::string& option) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  int index = 0;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
    if (used == 0 || used != item.size())
      throw UsageError(option + ": value " + std::to_string(index + 1) + " ('" + printable(item, 40) +
                       "') is not a number");
    out.push_back(v);
    ++index;
  }
  if (!text.empty() && text.back() == ',') throw UsageError(option + ": trailing comma");
  return out;
}

namespace {

std::vector<double> stateVector(const Model& m, const std::string& text, const std::string& option, bool finite) {
  std::vector<double> v = parseList(text, option);
  if (static_cast<int>(v.size()) != m.stateSize()) {
    std::string names;
    for (const std::string& n : m.stateNames()) names += (names.empty() ? "" : ", ") + n;
    throw UsageError(option + " has " + std::to_string(v.size()) + " values but model '" + m.name + "' has " +
                     std::to_string(m.stateSize()) + " state values (" + names + ")");
  }
  for (std::size_t i = 0; finite && i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw UsageError(option + ": value " + std::to_string(i + 1) + " (" + m.stateNames()[i] + ") is not finite");
  return v;
}

}  // namespace

StateBox parseStateBox(const Model& m, const std::string& state, const std::string& lower, const std::string& upper,
                       const std::string& missing, bool finite) {
  StateBox box;
  if (m.stateSize() == 0 && lower.empty() && upper.empty()) {      // only fixed joints: one configuration
    if (!state.empty()) stateVector(m, state, "--state", finite);  // explains a value given anyway
    box.point = true;
    return box;
  }
  if (!state.empty()) {
    if (!lower.empty() || !upper.empty()) throw UsageError("give either --state or --lower/--upper, not both");
    box.lower = box.upper = stateVector(m, state, "--state", finite);
    box.point = true;
    return box;
  }
  if (lower.empty() || upper.empty()) throw UsageError(missing);
  box.lower = stateVector(m, lower, "--lower", finite);
  box.upper = stateVector(m, upper, "--upper", finite);
  return box;
}

std::string optionSpelling(const std::string& field, const std::map<std::string, std::string>& spelling) {
  if (const auto s = spelling.find(field); s != spelling.end()) return s->second;
  std::string option = "--" + field.substr(field.rfind('.') + 1);
  std::replace(option.begin(), option.end(), '_', '-');
  return option;
}

void rethrowAsOption(const InputError& e, const std::map<std::string, std::string>& spelling) {
  const InputLocation& at = e.location();
  if (!at.source.empty() || at.field.empty() || at.line != 0) throw;
  throw UsageError(optionSpelling(at.field, spelling) + ": " + e.problem());
}

std::vector<std::string> splitCommas(const std::string& text) {
  std::vector<std::string> out;
  for (std::size_t at = 0; at <= text.size() && !text.empty();) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    out.push_back(text.substr(at, comma - at));
    at = comma + 1;
  }
  return out;
}

void addBrakingOptions(CLI::App& sub, BrakingParams& braking) {
  sub.add_option("--latency", braking.latency,
                 "Braking (with --swept): reaction latency t_l (s, 0 ... 1e3), every joint")
      ->capture_default_str();
  sub.add_option("--deceleration", braking.deceleration,
                 "Braking: guaranteed deceleration (rad/s^2 or m/s^2, 1e-9 ... 1e9), every joint")
      ->capture_default_str();
  sub.add_option("--max-acceleration", braking.max_acceleration,
                 "Braking: worst-case acceleration during the latency (0 ... 1e9)")
      ->capture_default_str();
  sub.add_option("--position-error", braking.position_error, "Braking: position measurement error bound (0 ... 1e3)")
      ->capture_default_str();
  sub.add_option("--velocity-error", braking.velocity_error, "Braking: velocity measurement error bound (0 ... 1e6)")
      ->capture_default_str();
}

bool brakingGiven(const CLI::App& sub) {
  for (const char* name : {"--latency", "--deceleration", "--max-acceleration", "--position-error", "--velocity-error"})
    if (sub.get_option(name)->count() > 0) return true;
  return false;
}

void addLerobotOptions(CLI::App& sub, std::string& dataset, long& episode, std::string& state_key,
                       std::string* frame_by) {
  sub.add_option("--lerobot", dataset,
                 "A LeRobot dataset's folder (v2.0, v2.1 or v3.0, as downloaded): one episode (--episode) is the "
                 "recording, its rows the states and its camera the frames (see kccd dataset info)");
  sub.add_option("--episode", episode, "With --lerobot: the episode (its episode_index; -1: none given)")
      ->capture_default_str();
  sub.add_option("--state-key", state_key, "With --lerobot: the vector feature read as the state")
      ->capture_default_str();
  if (!frame_by) return;
  sub.add_option("--frame-by", *frame_by,
                 "With --lerobot: how a row finds its video frame: timestamp (the nearest frame within 1e-4 s, as "
                 "LeRobot's loader does), index (frame_index) or auto (timestamp when every row is on the "
                 "frame grid, else index with a warning)")
      ->capture_default_str();
}

}  // namespace kccd::cli
