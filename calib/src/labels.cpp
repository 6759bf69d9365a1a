// The labels file (docs/formats.md section 5). Every error names the file, the line and column,
// and the field; loading stops at the first one.
#include "kccd/calib/labels.hpp"

#include <map>

#include "kccd/file_reader.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd::calib {

const Label* Labels::find(const std::string& name) const {
  for (const Label& l : labels)
    if (l.name == name) return &l;
  return nullptr;
}

Labels parseLabels(const std::string& yaml_text, const std::string& source) {
  const YamlReader r(source, 40);
  try {
    const YAML::Node root = r.load(yaml_text);
    if (!root.IsMap()) r.fail(root, "labels", "expected a mapping with labels: [...]");
    r.onlyKeys(root, "file", {"labels"});
    const YAML::Node list = r.require(root, "labels", "file");
    if (!list.IsSequence())
      r.fail(list, "labels", "expected a list of {name, pixel, world} or {name, pixel, body, point, state}");
    if (list.size() == 0) r.fail(list, "labels", "at least one label is needed");
    Labels out;
    std::map<std::string, std::size_t> seen;  // name -> index
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YAML::Node n = list[i];
      const std::string f = "labels[" + std::to_string(i) + "]";
      r.onlyKeys(n, f, {"name", "pixel", "world", "body", "point", "state"});
      Label l;
      l.where = r.where(n);
      const YAML::Node name = r.require(n, "name", f);
      l.name = r.text(name, f + ".name");
      if (const auto it = seen.find(l.name); it != seen.end())
        r.fail(
            name, f + ".name",
            "label '" + printable(l.name, 40) + "' is given twice (also labels[" + std::to_string(it->second) + "])");
      seen.emplace(l.name, i);
      const std::string fl = "label '" + printable(l.name, 40) + "'";
      const Eigen::Vector2d px = r.vec<2>(r.require(n, "pixel", fl), fl + ".pixel", kMaxLabelPixel, "1e6 px");
      l.pixel = cv::Point2d(px.x(), px.y());
      const bool world = n["world"].IsDefined(), body = n["body"].IsDefined();
      if (world && body) r.fail(n, fl, "give either world or body (with point), not both");
      if (!world && !body) r.fail(n, fl, "needs world: [x, y, z] or body: NAME with point: [x, y, z]");
      if (world) {
        if (n["point"]) r.fail(n["point"], fl + ".point", "point belongs to a body label (this one gives world)");
        if (n["state"]) r.fail(n["state"], fl + ".state", "state belongs to a body label (this one gives world)");
        const Vec3 w = r.vec<3>(n["world"], fl + ".world", kMaxLabelPoint, "1e6 m");
        l.world = cv::Point3d(w.x(), w.y(), w.z());
      } else {
        l.body = r.text(n["body"], fl + ".body");
        const Vec3 p = r.vec<3>(r.require(n, "point", fl), fl + ".point", kMaxLabelPoint, "1e6 m");
        l.point = cv::Point3d(p.x(), p.y(), p.z());
        if (const YAML::Node s = n["state"]) {
          if (!s.IsSequence()) r.fail(s, fl + ".state", "expected a list of numbers");
          if (s.size() > kMaxLabelState)
            r.fail(s, fl + ".state", "more than " + std::to_string(kMaxLabelState) + " values");
          std::vector<double> state;
          for (std::size_t k = 0; k < s.size(); ++k)
            state.push_back(r.number(s[k], fl + ".state[" + std::to_string(k) + "]"));
          l.state = std::move(state);
        }
      }
      out.labels.push_back(std::move(l));
    }
    return out;
  } catch (const LabelsError&) {
    throw;
  } catch (const InputError& e) {
    throw LabelsError(e.location(), e.problem());
  } catch (const YAML::Exception& e) {
    throw LabelsError(InputLocation{source, 0, 0, "yaml"}, printable(e.what(), 100));
  }
}

Labels loadLabels(const std::string& path) {
  std::string text;
  try {
    text = readRegularFile(path, kMaxLabelsBytes, "labels file");
  } catch (const FileError& e) {
    throw LabelsError(e.location(), e.problem());
  }
  return parseLabels(text, path);
}

cv::Point3d worldPoint(const Model& model, const Label& label, std::span<const double> state) {
  if (label.world) return *label.world;
  const std::string fl = label.where + ": label '" + printable(label.name, 40) + "'";
  const int b = model.bodyIndex(label.body);
  if (b < 0)
    throw LabelsError(fl + ".body: no body '" + printable(label.body, 40) + "' in model '" + printable(model.name, 40) +
                      "'");
  if (static_cast<int>(state.size()) != model.stateSize())
    throw LabelsError(fl + ".state: " + std::to_string(state.size()) + " state values, model '" +
                      printable(model.name, 40) + "' has " + std::to_string(model.stateSize()));
  std::vector<Pose> poses(model.joints.size());
  if (!framePoses(model, state, poses)) throw LabelsError(fl + ".state: a state value is not finite");
  const Vec3 w = framePose(poses, model.bodies[static_cast<std::size_t>(b)].frame) *
                 Vec3(label.point.x, label.point.y, label.point.z);
  return {w.x(), w.y(), w.z()};
}

cv::Point3d worldPoint(const Model& model, const Label& label) {
  if (label.world) return *label.world;
  if (!label.state)
    throw LabelsError(label.where + ": label '" + printable(label.name, 40) +
                      "'.state: no state given (a state log must place body '" + printable(label.body, 40) + "')");
  return worldPoint(model, label, *label.state);
}

}  // namespace kccd::calib
