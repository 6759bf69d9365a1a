// The tag layout file (docs/formats.md section 4). Every error names the file, the line and
// column, and the field; loading stops at the first one.
#include "kccd/calib/tag_layout.hpp"

#include <cmath>

#include "kccd/file_reader.hpp"
#include "kccd/rotation.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd::calib {

Pose Tag::pose() const {
  Pose p = Pose::Identity();
  p.linear() = rotationFromRpy(rpy);
  p.translation() = xyz;
  return p;
}

std::array<cv::Point3d, 4> Tag::corners() const {
  const double h = size / 2.0;
  const Vec3 local[4] = {{-h, -h, 0.0}, {h, -h, 0.0}, {h, h, 0.0}, {-h, h, 0.0}};
  const Pose p = pose();
  std::array<cv::Point3d, 4> out;
  for (int i = 0; i < 4; ++i) {
    const Vec3 w = p * local[i];
    out[static_cast<std::size_t>(i)] = cv::Point3d(w.x(), w.y(), w.z());
  }
  return out;
}

const Tag* TagLayout::find(int id) const {
  for (const Tag& t : tags)
    if (t.id == id) return &t;
  return nullptr;
}

TagLayout parseTagLayout(const std::string& yaml_text, const std::string& source) {
  const YamlReader r(source, 40);
  try {
    const YAML::Node root = r.load(yaml_text);
    if (!root.IsMap()) r.fail(root, "layout", "expected a mapping with tags: [...]");
    r.onlyKeys(root, "layout", {"tags"});
    const YAML::Node list = r.require(root, "tags", "layout");
    if (!list.IsSequence()) r.fail(list, "tags", "expected a list of {id, size, xyz, rpy}");
    if (list.size() == 0) r.fail(list, "tags", "a layout needs at least one tag");
    TagLayout layout;
    std::array<std::size_t, kMaxTagId + 1> seen{};  // 1 + index of the tag with this id, 0 if none
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YAML::Node n = list[i];
      const std::string f = "tags[" + std::to_string(i) + "]";
      r.onlyKeys(n, f, {"id", "size", "xyz", "rpy"});
      Tag t;
      const YAML::Node id = r.require(n, "id", f);
      const double v = r.number(id, f + ".id");
      if (v != std::floor(v) || v < 0 || v > kMaxTagId)
        r.fail(id, f + ".id",
               "'" + printable(id.Scalar(), 40) + "' is not a tag36h11 id (an integer in 0.." +
                   std::to_string(kMaxTagId) + ")");
      t.id = static_cast<int>(v);
      if (seen[static_cast<std::size_t>(t.id)])
        r.fail(id, f + ".id",
               "tag " + std::to_string(t.id) + " is listed twice (also tags[" +
                   std::to_string(seen[static_cast<std::size_t>(t.id)] - 1) + "])");
      seen[static_cast<std::size_t>(t.id)] = i + 1;
      const YAML::Node size = r.require(n, "size", f);
      t.size = r.number(size, f + ".size");
      if (!(t.size > 0.0) || t.size > kMaxTagSize)
        r.fail(size, f + ".size", "the edge of the black square must be > 0 and at most 100 m");
      t.xyz = r.vec<3>(r.require(n, "xyz", f), f + ".xyz", kMaxTagPosition, "1e6 m");
      t.rpy = r.vec<3>(r.require(n, "rpy", f), f + ".rpy", HUGE_VAL, "finite");
      layout.tags.push_back(t);
    }
    return layout;
  } catch (const TagLayoutError&) {
    throw;
  } catch (const InputError& e) {
    throw TagLayoutError(e.location(), e.problem());
  } catch (const YAML::Exception& e) {
    throw TagLayoutError(InputLocation{source, 0, 0, "yaml"}, printable(e.what(), 100));
  }
}

TagLayout loadTagLayout(const std::string& path) {
  std::string text;
  try {
    text = readRegularFile(path, kMaxTagLayoutBytes, "tag layout");
  } catch (const FileError& e) {
    throw TagLayoutError(e.location(), e.problem());
  }
  return parseTagLayout(text, path);
}

}  // namespace kccd::calib
