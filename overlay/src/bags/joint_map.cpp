#include "kccd/overlay/bags/joint_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "kccd/file_reader.hpp"
#include "kccd/format_number.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd::overlay {

std::vector<std::string> JointMap::logged() const {
  std::vector<std::string> out;
  for (const JointSource& s : states)
    if (!s.constant && std::find(out.begin(), out.end(), s.from) == out.end()) out.push_back(s.from);
  return out;
}

JointMap identityJointMap(const Model& model) {
  JointMap map;
  for (const std::string& n : model.stateNames()) map.states.push_back({.state = n, .from = n});
  return map;
}

namespace {

// The position limits of state value `k` (a 1-DOF joint's), or NaNs.
std::array<double, 2> stateLimits(const Model& model, std::size_t k) {
  for (const Joint& j : model.joints)
    if (j.dof == 1 && static_cast<std::size_t>(j.state_offset) == k && j.limits) return *j.limits;
  return {std::nan(""), std::nan("")};
}

}  // namespace

JointMap parseJointMap(const std::string& text, const std::string& source, const Model& model) {
  constexpr double kBound = 1e6;
  const YamlReader r(source, 60);
  JointMap map = identityJointMap(model);
  map.source = source;
  const YAML::Node root = r.load(text);
  if (!root.IsMap()) r.fail(root, "joint map", "expected a mapping with kccd_joint_map: 1 and joints");
  r.onlyKeys(root, "joint map", {"kccd_joint_map", "joints"});
  const YAML::Node version = r.require(root, "kccd_joint_map", "joint map");
  if (!version.IsScalar() || version.Scalar() != "1")
    r.fail(version, "kccd_joint_map", "expected 1 (the joint map format's version)");
  const YAML::Node joints = r.require(root, "joints", "joint map");
  if (!joints.IsMap())
    r.fail(joints, "joints",
           "expected a mapping of the model's state values, e.g. elbow: {from: elbow_deg, degrees: true}");
  const std::vector<std::string>& names = model.stateNames();
  for (const auto& kv : joints) {
    const std::string state = r.text(kv.first, "joints");
    const std::string f = "joints." + printable(state, 60);
    const auto it = std::find(names.begin(), names.end(), state);
    if (it == names.end()) {
      std::string have;
      for (const std::string& n : names) have += (have.empty() ? "" : ", ") + printable(n, 40);
      r.fail(kv.first, f, "the model has no state value of that name (it has: " + have + ")");
    }
    JointSource& s = map.states[static_cast<std::size_t>(it - names.begin())];
    s.line = kv.first.Mark().line + 1;
    const YAML::Node e = kv.second;
    if (e.IsScalar()) {  // `state: logged_name`, the short form of a rename
      s.from = r.text(e, f);
      continue;
    }
    if (!e.IsMap())
      r.fail(e, f, "expected a logged joint's name, or a mapping of from, scale, offset, degrees, range, or constant");
    r.onlyKeys(e, f, {"from", "scale", "offset", "degrees", "range", "constant"});
    if (e["constant"]) {
      for (const char* k : {"from", "scale", "offset", "degrees", "range"})
        if (e[k]) r.fail(e[k], f + "." + k, "not with constant (a constant is the value itself)");
      s.constant = r.bounded(e["constant"], f + ".constant", 1e300, "1e300");
      s.from.clear();
      continue;
    }
    if (e["from"]) s.from = r.text(e["from"], f + ".from");
    if (e["scale"]) {
      s.scale = r.bounded(e["scale"], f + ".scale", kBound, "1e6");
      if (s.scale == 0.0) r.fail(e["scale"], f + ".scale", "0 would ignore the log (give constant: VALUE instead)");
    }
    if (e["offset"]) s.offset = r.bounded(e["offset"], f + ".offset", kBound, "1e6");
    if (const YAML::Node d = e["degrees"]) {
      if (!d.IsScalar() || (d.Scalar() != "true" && d.Scalar() != "false"))
        r.fail(d, f + ".degrees", "expected true or false");
      if (d.Scalar() == "true") s.scale *= std::numbers::pi / 180.0;
    }
    if (const YAML::Node g = e["range"]) {
      for (const char* k : {"scale", "degrees"})
        if (e[k]) r.fail(e[k], f + "." + k, "not with range (the range sets the scale)");
      const std::array<double, 2> limits = stateLimits(model, static_cast<std::size_t>(it - names.begin()));
      if (!std::isfinite(limits[0]) || !std::isfinite(limits[1]))
        r.fail(g, f + ".range", "the model's joint has no limits to map the range onto");
      if (!g.IsSequence() || g.size() != 2)
        r.fail(g, f + ".range", "expected [LOW, HIGH], the logged values at the joint's limits");
      const double lo = r.bounded(g[0], f + ".range[0]", kBound, "1e6"),
                   hi = r.bounded(g[1], f + ".range[1]", kBound, "1e6");
      if (!(lo < hi)) r.fail(g, f + ".range", "expected LOW < HIGH");
      // logged lo -> lower limit, hi -> upper limit; an offset given too is added after.
      s.scale = (limits[1] - limits[0]) / (hi - lo);
      s.offset += limits[0] - lo * s.scale;
    }
  }
  return map;
}

StateLog mappedStateLog(const JointMap& given, const Model& model, std::span<const std::string> names,
                        std::span<const double> times, std::span<const double> values, const std::string& source,
                        const std::string& map_option) {
  const JointMap map = given.states.empty() ? identityJointMap(model) : given;
  const std::vector<std::string>& states = model.stateNames();
  std::vector<std::size_t> column(states.size(), 0);
  for (std::size_t k = 0; k < states.size(); ++k) {
    const JointSource& s = map.states[k];
    if (s.constant) continue;
    auto at = std::find(names.begin(), names.end(), s.from);
    if (at == names.end()) at = std::find(names.begin(), names.end(), s.from + ".pos");
    if (at == names.end()) {
      std::string have;
      for (const std::string& n : names) have += (have.empty() ? "" : ", ") + printable(n, 40);
      const std::string what = s.line > 0 ? "'" + printable(s.from, 60) + "', which " + map.source + " (line " +
                                                std::to_string(s.line) + ") reads '" + printable(s.state, 60) + "' from"
                                          : "the model's state value '" + printable(s.from, 60) + "'";
      throw InputError(source + ": the rows do not name " + what + " (they name: " + have + ")" +
                       (map.source.empty() ? "; " + map_option + " can rename, scale or fix a state value" : ""));
    }
    column[k] = static_cast<std::size_t>(at - names.begin());
  }
  // As text the state log reader checks like a file: the same rules as a CSV log.
  std::string text = "time";
  for (const std::string& n : states) text += "," + n;
  text += "\n";
  const std::size_t width = names.size();
  for (std::size_t i = 0; i < times.size(); ++i) {
    text += shortestNumber(times[i]);
    for (std::size_t k = 0; k < states.size(); ++k) {
      const JointSource& s = map.states[k];
      const double v = values[i * width + column[k]];
      text += ',';
      text += shortestNumber(s.constant ? *s.constant : s.scale == 1.0 && s.offset == 0.0 ? v : s.scale * v + s.offset);
    }
    text += "\n";
  }
  return parseStateLog(text, source, model);
}

JointMap loadJointMap(const std::string& path, const Model& model) {
  return parseJointMap(readRegularFile(path, 1 << 20, "joint map"), path, model);
}

}  // namespace kccd::overlay
