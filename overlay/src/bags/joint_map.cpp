#include "kccd/overlay/bags/joint_map.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kccd/file_reader.hpp"
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
  const std::vector<std::string> names = model.stateNames();
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
      r.fail(e, f, "expected a logged joint's name, or a mapping of from, scale, offset, degrees, or constant");
    r.onlyKeys(e, f, {"from", "scale", "offset", "degrees", "constant"});
    if (e["constant"]) {
      for (const char* k : {"from", "scale", "offset", "degrees"})
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
  }
  return map;
}

JointMap loadJointMap(const std::string& path, const Model& model) {
  return parseJointMap(readRegularFile(path, 1 << 20, "joint map"), path, model);
}

}  // namespace kccd::overlay
