#include "kccd/overlay/golden/golden_check.hpp"

#include <filesystem>

#include "kccd/calib/image_file.hpp"
#include "kccd/file_reader.hpp"
#include "kccd/overlay/common/staged_output.hpp"

namespace kccd::overlay {
namespace {

namespace fs = std::filesystem;

nlohmann::json toleranceJson(const GoldenCase& c, GoldenOutput o) {
  if (o == GoldenOutput::Mask)
    return {{"max_cluster_px", c.mask.max_cluster_px},
            {"max_centroid_shift_px", c.mask.max_centroid_shift_px},
            {"max_area_change_per_boundary_px", c.mask.max_area_change_per_boundary_px},
            {"from", c.tolerance_source.mask}};
  const ColourTolerance& t = o == GoldenOutput::Colour ? c.colour : c.overlay;
  return {{"channel_threshold", t.channel_threshold},
          {"max_cluster_px", t.max_cluster_px},
          {"max_diff_px", t.max_diff_px},
          {"from", o == GoldenOutput::Colour ? c.tolerance_source.colour : c.tolerance_source.overlay}};
}

std::string fileOf(const nlohmann::json& side, const char* key) {
  const nlohmann::json* e = side.contains("inputs") && side["inputs"].contains(key) ? &side["inputs"][key] : nullptr;
  return e && e->is_object() && e->contains("file") && (*e)["file"].is_string() ? (*e)["file"].get<std::string>() : key;
}

const nlohmann::json& at(const nlohmann::json& j, const char* a, const char* b) {
  static const nlohmann::json none;
  if (!j.is_object() || !j.contains(a) || !j[a].is_object() || !j[a].contains(b)) return none;
  return j[a][b];
}

}  // namespace

const char* goldenStatusName(GoldenStatus status) {
  switch (status) {
    case GoldenStatus::Passed:
      return "passed";
    case GoldenStatus::Failed:
      return "failed";
    case GoldenStatus::Missing:
      return "missing";
  }
  return "?";
}

bool CaseResult::passed() const {
  if (!unsafe.empty()) return false;
  for (const OutputResult& o : outputs)
    if (o.status != GoldenStatus::Passed) return false;
  return true;
}

std::string goldenFolder(const GoldenManifest& manifest, const std::string& id) {
  return (fs::path(manifest.goldens) / id).string();
}

std::string likelyCause(const nlohmann::json& golden, const nlohmann::json& actual) {
  std::vector<std::string> changed;
  const auto differs = [&](const char* key) {
    const nlohmann::json& g = at(golden, "inputs", key);
    const nlohmann::json& a = at(actual, "inputs", key);
    if (g.is_object() && a.is_object() && g.contains("sha256") && a.contains("sha256"))
      return g["sha256"] != a["sha256"];
    return g != a;
  };
  if (differs("model")) changed.push_back("the model changed (" + fileOf(actual, "model") + ")");
  if (differs("meshes")) changed.push_back("the model's meshes changed");
  if (differs("camera")) changed.push_back("the camera changed (" + fileOf(actual, "camera") + ")");
  if (differs("states")) changed.push_back("the state log changed (" + fileOf(actual, "states") + ")");
  if (differs("video_frame"))
    changed.push_back("the video frame's pixels changed (" + fileOf(actual, "video") + ": re-encoded or replaced)");
  if (differs("video")) changed.push_back("the frame or time offset changed");
  if (differs("state")) changed.push_back("the state changed");
  if (differs("box")) changed.push_back("the box changed");
  if (!changed.empty()) {
    std::string s;
    for (const std::string& c : changed) s += (s.empty() ? "" : "; ") + c;
    return s;
  }
  if (golden.value("renderer", nlohmann::json()) != actual.value("renderer", nlohmann::json()))
    return "inputs unchanged; the GL renderer changed (" + golden.value("renderer", std::string("?")) + " -> " +
           actual.value("renderer", std::string("?")) + ")";
  if (golden.value("kccd_version", nlohmann::json()) != actual.value("kccd_version", nlohmann::json()))
    return "inputs unchanged; kccd's version changed (" + golden.value("kccd_version", std::string("?")) + " -> " +
           actual.value("kccd_version", std::string("?")) + ")";
  if (golden.value("options", nlohmann::json()) != actual.value("options", nlohmann::json()))
    return "inputs unchanged; the render options changed";
  return "nothing recorded changed (inputs, renderer, version, options): the rendering is not deterministic";
}

CaseResult checkCase(const GoldenCase& c, const GoldenRendering& rendering, const std::string& folder) {
  CaseResult r;
  r.id = c.id;
  r.unsafe = rendering.unsafe;
  nlohmann::json golden;
  bool have_sidecar = false;
  std::string sidecar_problem;
  const fs::path sidecar = fs::path(folder) / "golden.json";
  if (fs::exists(sidecar)) {
    try {
      golden = nlohmann::json::parse(readRegularFile(sidecar.string(), 16u << 20, "golden sidecar"));
      have_sidecar = golden.is_object();
      if (!have_sidecar) sidecar_problem = sidecar.string() + ": not a JSON object";
    } catch (const std::exception& e) {
      sidecar_problem = sidecar.string() + ": " + e.what();
    }
  }
  for (const GoldenImage& img : rendering.images) {
    OutputResult o;
    o.output = img.output;
    o.tolerance = toleranceJson(c, img.output);
    const char* name = goldenOutputName(img.output);
    const fs::path file = fs::path(folder) / (std::string(name) + ".png");
    if (!fs::exists(file)) {
      o.status = GoldenStatus::Missing;
      o.reason = "no golden " + file.string() + " (kccd golden update writes it)";
      r.outputs.push_back(std::move(o));
      continue;
    }
    o.status = GoldenStatus::Failed;
    try {
      o.expected = calib::readImageFile(file.string(), calib::ImageColour::Unchanged);
    } catch (const calib::ImageError& e) {
      o.reason = e.what();
    }
    if (!o.reason.empty()) {
      // the golden itself is unreadable: that is the reason
    } else if (!sidecar_problem.empty() || !have_sidecar) {
      o.reason = sidecar_problem.empty() ? sidecar.string() + ": missing (it names the mask's bodies and the inputs)"
                                         : sidecar_problem;
    } else if (img.output == GoldenOutput::Mask) {
      const nlohmann::json& labels = at(golden, "outputs", "mask");
      std::vector<std::string> names;
      bool ok = labels.is_object() && labels.contains("labels") && labels["labels"].is_object();
      if (ok) {
        names.resize(labels["labels"].size());
        for (const auto& [k, v] : labels["labels"].items()) {
          std::size_t idx = 0;
          try {
            idx = std::stoul(k);
          } catch (const std::exception&) {
            idx = 0;
          }
          if (idx < 1 || idx > names.size() || !v.is_string())
            ok = false;
          else
            names[idx - 1] = v.get<std::string>();
        }
      }
      if (!ok) {
        o.reason = sidecar.string() + ": outputs.mask.labels does not map the mask's labels to body names";
      } else {
        o.comparison = compareMasks(o.expected, names, img.image, img.labels, c.mask);
        o.reason = o.comparison.reason;
        if (o.comparison.passed) o.status = GoldenStatus::Passed;
      }
    } else {
      const ColourTolerance& t = img.output == GoldenOutput::Colour ? c.colour : c.overlay;
      o.comparison = compareColour(o.expected, img.image, t);
      o.reason = o.comparison.reason;
      if (o.comparison.passed) o.status = GoldenStatus::Passed;
    }
    r.outputs.push_back(std::move(o));
  }
  bool failed = false;
  for (const OutputResult& o : r.outputs) failed |= o.status == GoldenStatus::Failed;
  if (failed && have_sidecar) r.cause = likelyCause(golden, rendering.sidecar);
  return r;
}

void writeGoldens(const GoldenRendering& rendering, const std::string& folder) {
  fs::create_directories(folder);
  for (const GoldenImage& img : rendering.images)
    writeFileAtomically(fs::path(folder) / (std::string(goldenOutputName(img.output)) + ".png"),
                        std::string(img.png.begin(), img.png.end()), "golden");
  writeFileAtomically(fs::path(folder) / "golden.json", rendering.sidecar.dump(2) + "\n", "golden sidecar");
}

}  // namespace kccd::overlay
