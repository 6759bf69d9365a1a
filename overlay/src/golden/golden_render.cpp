#include "kccd/overlay/golden/golden_render.hpp"
#include "kccd/calib/image_encode.hpp"

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <tuple>

#include <openssl/evp.h>

#include "kccd/calib/camera.hpp"
#include "kccd/file_reader.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/datasets/lerobot_recording.hpp"
#include "kccd/overlay/recording/frame_annotator.hpp"
#include "kccd/overlay/recording/frame_decoration.hpp"
#include "kccd/overlay/recording/legend_corner.hpp"
#include "kccd/render/model_view.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {
namespace {

// What names a bag's state log in the renderer's caches: the bag, its topics and clock.
std::string logKey(const GoldenCase& c) {
  if (!c.lerobot.empty()) return "lerobot\n" + c.lerobot + "\n" + std::to_string(c.episode) + "\n" + c.camera_key;
  return "bag\n" + c.bag + "\n" + c.image_topic + "\n" + c.joint_topic + "\n" + (c.log_time ? "log" : "header");
}

constexpr std::uintmax_t kMaxHashedBytes = std::uintmax_t(1) << 34;  // 16 GiB: a long recording

std::string hex(const unsigned char* d, unsigned n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (unsigned i = 0; i < n; ++i) s += digits[d[i] >> 4], s += digits[d[i] & 15];
  return s;
}

std::string relativeTo(const std::string& path, const std::string& folder) {
  std::error_code ec;
  const std::filesystem::path r = std::filesystem::relative(path, folder, ec);
  return ec || r.empty() ? path : r.generic_string();
}

struct LoadedFrame {
  cv::Mat bgr;
  double time = 0.0;
  std::string pixels_sha256;
};

// The renderer's options of a case: its images, mask included, at the case's pinhole scale.
render::RenderOptions renderOptions(const GoldenCase& c) {
  render::RenderOptions options;
  options.supersample = options.mask_supersample = c.supersample;
  return options;
}

}  // namespace

std::string sha256Hex(std::span<const unsigned char> bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &n, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 failed");
  return hex(digest, n);
}

std::vector<unsigned char> deterministicPng(const cv::Mat& image) {
  // Fixed compression and strategy; no time or text chunks.
  const std::vector<std::uint8_t> png = calib::encodePng(image, 6);
  return {png.begin(), png.end()};
}

const char* kccdVersion() { return KCCD_VERSION_STRING; }

struct GoldenRenderer::Impl {
  const GoldenManifest& manifest;
  std::map<std::string, std::unique_ptr<Model>> models;
  std::map<std::string, calib::Camera> cameras;
  std::map<std::pair<std::string, std::string>, std::unique_ptr<StateLog>> logs;              // (log, model)
  std::map<std::pair<std::string, std::string>, std::unique_ptr<BagRecording>> bags;          // (logKey, model)
  std::map<std::pair<std::string, std::string>, std::unique_ptr<LerobotRecording>> episodes;  // (logKey, model)
  std::map<std::size_t, LoadedFrame> frames;                                                  // per frame case
  std::map<std::string, std::string> hashes;                                                  // path -> sha256
  std::map<std::tuple<std::string, std::string, double>, std::unique_ptr<render::ModelView>> views;
  std::string renderer;

  const std::string& hash(const std::string& path) {
    auto it = hashes.find(path);
    if (it == hashes.end()) {
      const std::string bytes = readRegularFile(path, kMaxHashedBytes, "input");
      it = hashes
               .emplace(path, sha256Hex(std::span<const unsigned char>(
                                  reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size())))
               .first;
    }
    return it->second;
  }

  render::ModelView& view(const GoldenCase& c) {
    auto& v = views[{c.model, c.camera, c.supersample}];
    if (!v) {
      try {
        v = std::make_unique<render::ModelView>(*models.at(c.model), cameras.at(c.camera), renderOptions(c));
      } catch (const calib::CameraError& e) {
        throw InputError(e.messageFrom(c.camera));
      }
      renderer = v->renderer().rendererString();
    }
    return *v;
  }
};

GoldenRenderer::GoldenRenderer(const GoldenManifest& manifest)
    : impl_(std::make_unique<Impl>(Impl{manifest, {}, {}, {}, {}, {}, {}, {}})) {
  Impl& s = *impl_;
  for (std::size_t i = 0; i < manifest.cases.size(); ++i) {
    const GoldenCase& c = manifest.cases[i];
    const std::string where = c.where + ": case '" + c.id + "'";
    if (!s.models.count(c.model)) s.models.emplace(c.model, std::make_unique<Model>(loadModel(c.model)));
    const Model& m = *s.models.at(c.model);
    if (m.bodies.size() > 255)
      throw InputError(where + ".model: " + c.model + " has more than 255 bodies (an 8-bit mask)");
    if (!s.cameras.count(c.camera)) s.cameras.emplace(c.camera, calib::loadCamera(c.camera));
    const calib::Camera& cam = s.cameras.at(c.camera);
    const std::size_t n = static_cast<std::size_t>(m.stateSize());
    for (const auto* values : {&c.state, &c.lower})
      if (!values->empty() && values->size() != n)
        throw InputError(where + (values == &c.state ? ".state: " : ".lower: ") + std::to_string(values->size()) +
                         " values, model '" + m.name + "' has " + std::to_string(n) + " (" + c.model + ")");
    if (!c.bag.empty()) {
      // The bag's joint states as the state log (read once per bag, topics, clock and model), and
      // its image topic's frame with that frame's time.
      const auto key = std::make_pair(logKey(c), c.model);
      auto it = s.bags.find(key);
      if (it == s.bags.end()) {
        BagRecording rec;
        try {
          rec = readBagRecording({.bag = c.bag,
                                  .joint_topic = c.joint_topic,
                                  .image_topic = c.image_topic,
                                  .time_source = c.log_time ? TimeSource::Log : TimeSource::Header},
                                 m);
        } catch (const InputError& e) {
          throw InputError(where + ".bag: " + e.what());
        }
        it = s.bags.emplace(key, std::make_unique<BagRecording>(std::move(rec))).first;
        s.logs.emplace(key, std::make_unique<StateLog>(it->second->log));
      }
      const BagRecording& rec = *it->second;
      LoadedFrame f;
      f.bgr = framesAt(rec, {static_cast<long>(c.frame)}, where + ".frame:").front();
      checkPicture(f.bgr, cam, c.bag + "#" + std::to_string(c.frame), c.camera);
      f.time = rec.frame_times[static_cast<std::size_t>(c.frame)];
      const cv::Mat flat = f.bgr.isContinuous() ? f.bgr : f.bgr.clone();
      f.pixels_sha256 = sha256Hex(std::span<const unsigned char>(flat.data, flat.total() * flat.elemSize()));
      s.frames.emplace(i, std::move(f));
    } else if (!c.lerobot.empty()) {
      // The episode's rows as the state log (read once per episode, camera and model), and the frame.
      const auto key = std::make_pair(logKey(c), c.model);
      auto it = s.episodes.find(key);
      if (it == s.episodes.end()) {
        LerobotRecording rec;
        try {
          rec = readLerobotRecording({.dataset = c.lerobot, .episode = c.episode, .camera_key = c.camera_key}, m);
        } catch (const InputError& e) {
          throw InputError(where + ".lerobot: " + e.what());
        }
        it = s.episodes.emplace(key, std::make_unique<LerobotRecording>(std::move(rec))).first;
        s.logs.emplace(key, std::make_unique<StateLog>(it->second->log));
      }
      LoadedFrame f;
      std::vector<double> times;
      f.bgr = lerobotFramesAt(*it->second, {static_cast<long>(c.frame)}, where + ".frame:", times).front();
      checkPicture(f.bgr, cam, c.lerobot + "#" + std::to_string(c.episode) + "/" + std::to_string(c.frame), c.camera);
      f.time = times.front();
      const cv::Mat flat = f.bgr.isContinuous() ? f.bgr : f.bgr.clone();
      f.pixels_sha256 = sha256Hex(std::span<const unsigned char>(flat.data, flat.total() * flat.elemSize()));
      s.frames.emplace(i, std::move(f));
    } else if (c.hasVideo()) {
      const auto key = std::make_pair(c.states, c.model);
      if (!s.logs.count(key)) s.logs.emplace(key, std::make_unique<StateLog>(loadStateLog(c.states, m)));
      RecordingFrames rf = readRecordingFrames(c.video, {static_cast<int>(c.frame)});
      if (!(rf.fps > 0))
        throw InputError(where + ".video: " + c.video + " declares no frame rate (a frame's time needs one)");
      LoadedFrame f;
      f.bgr = std::move(rf.frames.at(0));
      checkPicture(f.bgr, cam, c.video + "#" + std::to_string(c.frame), c.camera);
      f.time = static_cast<double>(c.frame) / rf.fps;
      const cv::Mat flat = f.bgr.isContinuous() ? f.bgr : f.bgr.clone();
      f.pixels_sha256 = sha256Hex(std::span<const unsigned char>(flat.data, flat.total() * flat.elemSize()));
      s.frames.emplace(i, std::move(f));
    }
    (void)s.hash(c.model);
    (void)s.hash(c.camera);
    for (const Visual& v : m.visuals)
      if (!v.mesh.empty() && std::filesystem::is_regular_file(v.mesh)) (void)s.hash(v.mesh);
  }
}

GoldenRenderer::~GoldenRenderer() = default;

const std::string& GoldenRenderer::rendererString() const { return impl_->renderer; }

GoldenRendering GoldenRenderer::render(std::size_t index) {
  Impl& s = *impl_;
  const GoldenCase& c = s.manifest.cases.at(index);
  const Model& m = *s.models.at(c.model);
  GoldenRendering out;
  nlohmann::json inputs;
  inputs["model"] = {{"file", relativeTo(c.model, s.manifest.folder)}, {"sha256", s.hash(c.model)}};
  nlohmann::json meshes = nlohmann::json::object();
  for (const Visual& v : m.visuals)
    if (!v.mesh.empty() && s.hashes.count(v.mesh)) meshes[relativeTo(v.mesh, s.manifest.folder)] = s.hashes.at(v.mesh);
  inputs["meshes"] = meshes;
  inputs["camera"] = {{"file", relativeTo(c.camera, s.manifest.folder)}, {"sha256", s.hash(c.camera)}};

  std::vector<double> state = c.state, lower = c.lower, upper = c.upper;
  std::optional<cv::Mat> overlay;
  if (c.hasVideo()) {
    const LoadedFrame& f = s.frames.at(index);
    const StateLog& log = *s.logs.at({c.bag.empty() && c.lerobot.empty() ? c.states : logKey(c), c.model});
    if (!c.lerobot.empty()) {
      const LerobotRecording& rec = *s.episodes.at({logKey(c), c.model});
      // The frame's pixels are hashed below; the episode's table is hashed as its state log.
      inputs["lerobot"] = {{"dataset", relativeTo(c.lerobot, s.manifest.folder)},
                           {"episode", c.episode},
                           {"camera_key", rec.camera_key},
                           {"frame", c.frame},
                           {"table_sha256", s.hash(rec.data_file)},
                           {"time_offset", c.time_offset}};
    } else if (c.bag.empty()) {
      inputs["states"] = {{"file", relativeTo(c.states, s.manifest.folder)}, {"sha256", s.hash(c.states)}};
      inputs["video"] = {
          {"file", relativeTo(c.video, s.manifest.folder)}, {"frame", c.frame}, {"time_offset", c.time_offset}};
    } else {
      const BagRecording& rec = *s.bags.at({logKey(c), c.model});
      // A log may be large (or a folder): its frame's pixels are hashed below, not the whole log.
      inputs["bag"] = {{"file", relativeTo(c.bag, s.manifest.folder)},
                       {"frame", c.frame},
                       {"image_topic", rec.image_topic},
                       {"joint_topic", rec.joint_topic},
                       {"time_source", toString(c.log_time ? TimeSource::Log : TimeSource::Header)},
                       {"time_offset", c.time_offset}};
    }
    inputs["video_frame"] = {{"sha256", f.pixels_sha256}};
    const render::Projection projection(s.cameras.at(c.camera), c.supersample);
    AnnotatorSettings settings;
    settings.time_offset = c.time_offset;
    settings.max_gap = 1.5 * log.medianPeriod();
    // As kccd overlay draws the frame: its legend where it hides the fewest volume pixels.
    const FrameDecoration decoration(f.bgr.size(), LegendPlace::Auto, true);
    settings.legend_corners = decoration.corners();
    const AnnotatorScene scene{m, log, projection, renderOptions(c), {}, settings};
    FrameAnnotator annotator(scene);
    FrameRecord record;
    record.time = f.time;
    record.selected = true;
    cv::Mat bgr = f.bgr.clone(), tall;
    annotator.annotate(bgr, record);
    const std::size_t corners = settings.legend_corners.size();
    const int corner =
        corners > 1 ? LegendCorner(decoration.corners().front().area()).next({record.legend_cover.data(), corners}) : 0;
    overlay = decorateFrame(bgr, tall, decoration, record, m, settings, corner);
    state = record.values;
    inputs["state"] = record.values.empty() ? nlohmann::json(nullptr) : nlohmann::json(record.values);
    if (record.unsafe()) out.unsafe = record.queryStatusText();
  } else if (!state.empty()) {
    inputs["state"] = state;
  } else {
    inputs["box"] = {{"lower", lower}, {"upper", upper}};
  }

  bool want_mask = false, want_colour = false;
  for (const GoldenOutput o : c.outputs) want_mask |= o == GoldenOutput::Mask, want_colour |= o == GoldenOutput::Colour;
  std::optional<render::ModelFrame> drawn;
  if (want_mask || want_colour) {
    render::ModelViewRequest request;
    request.state = state;
    if (!lower.empty()) {
      request.lower = lower;
      request.upper = upper;
      state.resize(lower.size());
      for (std::size_t k = 0; k < lower.size(); ++k) state[k] = 0.5 * lower[k] + 0.5 * upper[k];
      request.state = state;
    }
    request.colour = want_colour;
    request.mask = want_mask;
    request.style.legend = false;
    drawn = s.view(c).draw(request);
    if (drawn->query && drawn->query->status != Status::Ok && out.unsafe.empty())
      out.unsafe = toString(drawn->query->status);
  } else {
    (void)s.view(c);  // the renderer string, for the sidecar
  }

  nlohmann::json outputs;
  for (const GoldenOutput o : c.outputs) {
    GoldenImage g;
    g.output = o;
    if (o == GoldenOutput::Mask) {
      g.image = drawn->images.mask;
      for (const Body& b : m.bodies) g.labels.push_back(b.name);
    } else if (o == GoldenOutput::Colour) {
      g.image = drawn->images.bgra;
    } else {
      g.image = *overlay;
    }
    g.png = deterministicPng(g.image);
    g.sha256 = sha256Hex(g.png);
    nlohmann::json entry = {{"file", std::string(goldenOutputName(o)) + ".png"}, {"sha256", g.sha256}};
    if (o == GoldenOutput::Mask) {
      nlohmann::json labels = nlohmann::json::object();
      for (std::size_t k = 0; k < g.labels.size(); ++k) labels[std::to_string(k + 1)] = g.labels[k];
      entry["labels"] = labels;
      // How far from its centre a pixel's label may come from (null: no bound, a volume at the camera).
      const double edge = drawn->images.mask_edge_px;
      entry["edge_px"] = std::isfinite(edge) ? nlohmann::json(std::round(edge * 1e4) / 1e4) : nlohmann::json(nullptr);
    }
    outputs[goldenOutputName(o)] = entry;
    out.images.push_back(std::move(g));
  }
  out.sidecar = {{"kccd_golden", 1},
                 {"case", c.id},
                 {"kccd_version", kccdVersion()},
                 {"renderer", s.renderer},
                 {"options", {{"supersample", c.supersample}, {"tight_volumes", true}, {"legend", false}}},
                 {"inputs", inputs},
                 {"outputs", outputs}};
  return out;
}

}  // namespace kccd::overlay
