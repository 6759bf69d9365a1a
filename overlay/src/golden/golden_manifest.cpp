// The golden manifest (docs/formats.md section 9): read node by node, every mistake placed at its
// line and column; loading stops at the first one.
#include "kccd/overlay/golden/golden_manifest.hpp"

#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "kccd/file_reader.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd::overlay {
namespace {

constexpr std::size_t kMaxStateValues = 4096;

bool validId(const std::string& id) {
  if (id.empty() || id.size() > 128 || id[0] == '.' || id[0] == '-') return false;
  for (const char c : id)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) return false;
  return true;
}

// The values shared by the cases: the defaults block, then each case on top of it.
struct Shared {
  std::string model, camera, states, video, bag, image_topic, joint_topic, lerobot, camera_key;
  long episode = -1;
  bool log_time = false;
  double time_offset = 0.0;
  double supersample = 1.0;
  std::vector<GoldenOutput> outputs{GoldenOutput::Mask, GoldenOutput::Colour};
  MaskTolerance mask;
  ColourTolerance colour, overlay;
  ToleranceSource source;
};

class ManifestReader {
 public:
  ManifestReader(const std::string& path) : r_(path, 60), folder_(std::filesystem::path(path).parent_path().string()) {}

  GoldenManifest read(const std::string& text) {
    const YAML::Node root = r_.load(text);
    if (!root.IsMap()) r_.fail(root, "manifest", "expected a mapping with kccd_golden: 1, goldens and cases");
    r_.onlyKeys(root, "manifest", {"kccd_golden", "goldens", "defaults", "cases"});
    const YAML::Node version = r_.require(root, "kccd_golden", "manifest");
    if (!version.IsScalar() || version.Scalar() != "1")
      r_.fail(version, "kccd_golden", "expected 1 (the manifest format's version)");
    GoldenManifest m;
    m.path = r_.source();
    m.folder = folder_.empty() ? "." : folder_;
    m.goldens = root["goldens"] ? resolve(r_.text(root["goldens"], "goldens")) : resolve("goldens");
    Shared defaults;
    if (const YAML::Node d = root["defaults"]) {
      if (!d.IsMap())
        r_.fail(d, "defaults",
                "expected a mapping of model, camera, outputs, compare, states, video, bag, time_offset, supersample");
      r_.onlyKeys(d, "defaults",
                  {"model", "camera", "outputs", "compare", "states", "video", "bag", "image_topic", "joint_topic",
                   "time_source", "time_offset", "supersample", "lerobot", "episode", "camera_key"});
      shared(d, "defaults", "defaults", defaults);
    }
    const YAML::Node cases = r_.require(root, "cases", "manifest");
    if (!cases.IsSequence()) r_.fail(cases, "cases", "expected a list of cases");
    if (cases.size() == 0) r_.fail(cases, "cases", "at least one case is needed");
    if (cases.size() > kMaxGoldenCases)
      r_.fail(cases, "cases", "more than " + std::to_string(kMaxGoldenCases) + " cases");
    std::map<std::string, std::size_t> ids;
    for (std::size_t i = 0; i < cases.size(); ++i) m.cases.push_back(readCase(cases[i], i, defaults, ids));
    return m;
  }

 private:
  std::string resolve(const std::string& p) const {
    const std::filesystem::path path(p);
    return path.is_absolute() || folder_.empty() ? path.lexically_normal().string()
                                                 : (std::filesystem::path(folder_) / path).lexically_normal().string();
  }

  std::vector<double> numbers(const YAML::Node& n, const std::string& field) const {
    if (!n.IsSequence()) r_.fail(n, field, "expected a list of numbers");
    if (n.size() == 0) r_.fail(n, field, "expected at least one value");
    if (n.size() > kMaxStateValues) r_.fail(n, field, "more than " + std::to_string(kMaxStateValues) + " values");
    std::vector<double> out;
    for (std::size_t k = 0; k < n.size(); ++k) out.push_back(r_.number(n[k], field + "[" + std::to_string(k) + "]"));
    return out;
  }

  int count(const YAML::Node& n, const std::string& field, int lo, int hi) const {
    const double v = r_.number(n, field);
    if (v != std::floor(v) || v < lo || v > hi)
      r_.fail(n, field, "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
    return static_cast<int>(v);
  }

  double amount(const YAML::Node& n, const std::string& field, double hi) const {
    const double v = r_.number(n, field);
    if (v < 0 || v > hi) r_.fail(n, field, "expected a number from 0 to " + std::to_string(static_cast<long>(hi)));
    return v;
  }

  void compare(const YAML::Node& c, const std::string& field, const std::string& level, Shared& s) const {
    if (!c.IsMap()) r_.fail(c, field, "expected a mapping of mask, colour, overlay");
    r_.onlyKeys(c, field, {"mask", "colour", "overlay"});
    if (const YAML::Node m = c["mask"]) {
      const std::string f = field + ".mask";
      if (!m.IsMap())
        r_.fail(m, f, "expected a mapping of max_cluster_px, max_centroid_shift_px, max_area_change_per_boundary_px");
      r_.onlyKeys(m, f, {"max_cluster_px", "max_centroid_shift_px", "max_area_change_per_boundary_px"});
      if (m["max_cluster_px"]) s.mask.max_cluster_px = count(m["max_cluster_px"], f + ".max_cluster_px", 0, 1 << 30);
      if (m["max_centroid_shift_px"])
        s.mask.max_centroid_shift_px = amount(m["max_centroid_shift_px"], f + ".max_centroid_shift_px", 1e6);
      if (m["max_area_change_per_boundary_px"])
        s.mask.max_area_change_per_boundary_px =
            amount(m["max_area_change_per_boundary_px"], f + ".max_area_change_per_boundary_px", 1e6);
      s.source.mask = level;
    }
    for (const char* key : {"colour", "overlay"}) {
      const YAML::Node m = c[key];
      if (!m) continue;
      const std::string f = field + "." + key;
      if (!m.IsMap()) r_.fail(m, f, "expected a mapping of channel_threshold, max_cluster_px, max_diff_px");
      r_.onlyKeys(m, f, {"channel_threshold", "max_cluster_px", "max_diff_px"});
      ColourTolerance& t = std::string(key) == "colour" ? s.colour : s.overlay;
      if (m["channel_threshold"]) t.channel_threshold = count(m["channel_threshold"], f + ".channel_threshold", 0, 255);
      if (m["max_cluster_px"]) t.max_cluster_px = count(m["max_cluster_px"], f + ".max_cluster_px", 0, 1 << 30);
      if (m["max_diff_px"]) t.max_diff_px = count(m["max_diff_px"], f + ".max_diff_px", 0, 1 << 30);
      (std::string(key) == "colour" ? s.source.colour : s.source.overlay) = level;
    }
  }

  void shared(const YAML::Node& n, const std::string& field, const std::string& level, Shared& s) const {
    if (n["model"]) s.model = resolve(r_.text(n["model"], field + ".model"));
    if (n["camera"]) s.camera = resolve(r_.text(n["camera"], field + ".camera"));
    if (n["states"]) s.states = resolve(r_.text(n["states"], field + ".states"));
    if (n["video"]) s.video = resolve(r_.text(n["video"], field + ".video"));
    if (n["bag"]) s.bag = resolve(r_.text(n["bag"], field + ".bag"));
    if (n["image_topic"]) s.image_topic = r_.text(n["image_topic"], field + ".image_topic");
    if (n["joint_topic"]) s.joint_topic = r_.text(n["joint_topic"], field + ".joint_topic");
    if (n["lerobot"]) s.lerobot = resolve(r_.text(n["lerobot"], field + ".lerobot"));
    if (n["camera_key"]) s.camera_key = r_.text(n["camera_key"], field + ".camera_key");
    if (const YAML::Node e = n["episode"]) {
      const double v = r_.number(e, field + ".episode");
      if (v != std::floor(v) || v < 0 || v > 1e12) r_.fail(e, field + ".episode", "expected an episode index from 0");
      s.episode = static_cast<long>(v);
    }
    if (const YAML::Node t = n["time_source"]) {
      const std::string word = r_.text(t, field + ".time_source");
      if (word != "header" && word != "log") r_.fail(t, field + ".time_source", "expected header or log");
      s.log_time = word == "log";
    }
    if (n["time_offset"]) s.time_offset = r_.bounded(n["time_offset"], field + ".time_offset", 1e6, "1e6 s");
    if (const YAML::Node ss = n["supersample"]) {
      s.supersample = r_.number(ss, field + ".supersample");
      if (!(s.supersample >= 1.0 && s.supersample <= 4.0)) r_.fail(ss, field + ".supersample", "must be in 1..4");
    }
    if (const YAML::Node o = n["outputs"]) {
      if (!o.IsSequence() || o.size() == 0) r_.fail(o, field + ".outputs", "expected a list of mask, colour, overlay");
      s.outputs.clear();
      for (std::size_t k = 0; k < o.size(); ++k) {
        const std::string f = field + ".outputs[" + std::to_string(k) + "]";
        const std::string word = r_.text(o[k], f);
        GoldenOutput out;
        if (word == "mask")
          out = GoldenOutput::Mask;
        else if (word == "colour" || word == "color")
          out = GoldenOutput::Colour;
        else if (word == "overlay")
          out = GoldenOutput::Overlay;
        else
          r_.fail(o[k], f, "expected mask, colour or overlay, got '" + printable(word, 40) + "'");
        for (const GoldenOutput g : s.outputs)
          if (g == out) r_.fail(o[k], f, "'" + word + "' is listed twice");
        s.outputs.push_back(out);
      }
    }
    if (n["compare"]) compare(n["compare"], field + ".compare", level, s);
  }

  GoldenCase readCase(const YAML::Node& n, std::size_t i, const Shared& defaults,
                      std::map<std::string, std::size_t>& ids) const {
    std::string f = "cases[" + std::to_string(i) + "]";
    if (!n.IsMap()) r_.fail(n, f, "expected a mapping with id and state, lower/upper or video/frame");
    r_.onlyKeys(n, f, {"id",          "model",       "camera",      "outputs", "compare", "state",       "lower",
                       "upper",       "video",       "frame",       "states",  "bag",     "image_topic", "joint_topic",
                       "time_source", "time_offset", "supersample", "lerobot", "episode", "camera_key"});
    GoldenCase c;
    c.where = r_.where(n);
    const YAML::Node id = r_.require(n, "id", f);
    c.id = r_.text(id, f + ".id");
    if (!validId(c.id))
      r_.fail(id, f + ".id",
              "'" + printable(c.id, 40) +
                  "' is not a folder name: letters, digits, '-', '_' and '.' (not first), at most 128");
    if (const auto it = ids.find(c.id); it != ids.end())
      r_.fail(id, f + ".id", "'" + c.id + "' is given twice (also cases[" + std::to_string(it->second) + "])");
    ids.emplace(c.id, i);
    f = "case '" + c.id + "'";
    Shared s = defaults;
    shared(n, f, "case", s);
    c.model = s.model;
    c.camera = s.camera;
    c.outputs = s.outputs;
    c.time_offset = s.time_offset;
    c.supersample = s.supersample;
    c.mask = s.mask;
    c.colour = s.colour;
    c.overlay = s.overlay;
    c.tolerance_source = s.source;
    if (c.model.empty()) r_.fail(n, f + ".model", "no model (give one here or in defaults)");
    if (c.camera.empty()) r_.fail(n, f + ".camera", "no camera (give one here or in defaults)");
    const bool state = n["state"].IsDefined(), box = n["lower"].IsDefined() || n["upper"].IsDefined(),
               frame = n["frame"].IsDefined();
    if (state + box + frame != 1)
      r_.fail(n, f, "give exactly one of state, lower with upper, or frame (with video and states)");
    if (state) c.state = numbers(n["state"], f + ".state");
    if (box) {
      c.lower = numbers(r_.require(n, "lower", f), f + ".lower");
      c.upper = numbers(r_.require(n, "upper", f), f + ".upper");
      if (c.lower.size() != c.upper.size())
        r_.fail(n["upper"], f + ".upper",
                std::to_string(c.upper.size()) + " values, lower has " + std::to_string(c.lower.size()));
      for (std::size_t k = 0; k < c.lower.size(); ++k)
        if (c.lower[k] > c.upper[k])
          r_.fail(n["upper"][k], f + ".upper[" + std::to_string(k) + "]", "below lower[" + std::to_string(k) + "]");
    }
    if (frame) {
      const double v = r_.number(n["frame"], f + ".frame");
      if (v != std::floor(v) || v < 0 || v > 1e9) r_.fail(n["frame"], f + ".frame", "expected a frame index from 0");
      c.frame = static_cast<std::int64_t>(v);
      // A case's own video, bag or dataset replaces the others given in defaults.
      const bool own_bag = n["bag"].IsDefined(), own_video = n["video"].IsDefined() || n["states"].IsDefined(),
                 own_lerobot = n["lerobot"].IsDefined();
      if (own_bag + own_video + own_lerobot > 1)
        r_.fail(n, f, "give video and states, a bag, or a lerobot dataset, one of them");
      c.lerobot = own_video || own_bag ? std::string() : s.lerobot;
      c.bag = own_video || !c.lerobot.empty() ? std::string() : s.bag;
      if (!c.lerobot.empty()) {
        c.episode = s.episode;
        c.camera_key = s.camera_key;
        if (c.episode < 0) r_.fail(n, f + ".episode", "a lerobot frame case needs its episode (here or in defaults)");
      } else if (c.bag.empty()) {
        c.video = s.video;
        c.states = s.states;
        if (c.video.empty())
          r_.fail(n, f + ".video", "a frame case needs the video and state log, or a bag (here or in defaults)");
        if (c.states.empty()) r_.fail(n, f + ".states", "a frame case needs the state log (here or in defaults)");
      } else {
        c.image_topic = s.image_topic;
        c.joint_topic = s.joint_topic;
        c.log_time = s.log_time;
      }
    } else {
      for (const char* key :
           {"video", "states", "bag", "image_topic", "joint_topic", "time_source", "lerobot", "episode", "camera_key"})
        if (n[key]) r_.fail(n[key], f + "." + key, std::string(key) + " belongs to a frame case (give frame)");
      for (const GoldenOutput o : c.outputs)
        if (o == GoldenOutput::Overlay)
          r_.fail(n, f + ".outputs",
                  "overlay needs a recorded frame (give frame, with video and states, a bag or a lerobot dataset)");
    }
    return c;
  }

  YamlReader r_;
  std::string folder_;
};

}  // namespace

const char* goldenOutputName(GoldenOutput output) {
  switch (output) {
    case GoldenOutput::Mask:
      return "mask";
    case GoldenOutput::Colour:
      return "colour";
    case GoldenOutput::Overlay:
      return "overlay";
  }
  return "?";
}

GoldenManifest parseGoldenManifest(const std::string& text, const std::string& path) {
  try {
    return ManifestReader(path).read(text);
  } catch (const InputError&) {
    throw;
  } catch (const YAML::Exception& e) {
    throw InputError(InputLocation{path, 0, 0, "yaml"}, printable(e.what(), 100));
  }
}

GoldenManifest loadGoldenManifest(const std::string& path) {
  return parseGoldenManifest(readRegularFile(path, kMaxManifestBytes, "golden manifest"), path);
}

}  // namespace kccd::overlay
