#include "kccd/overlay/recording/mask_agreement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/input_error.hpp"
#include "kccd/kinematics.hpp"

namespace kccd::overlay {
namespace {

// The frame index of a file named frame_NNNNNN.png (six digits), if it is one.
std::optional<std::size_t> frameIndexOf(const std::string& name) {
  if (name.size() != 16 || name.rfind("frame_", 0) != 0 || name.substr(12) != ".png") return std::nullopt;
  std::size_t index = 0;
  for (std::size_t k = 6; k < 12; ++k) {
    if (name[k] < '0' || name[k] > '9') return std::nullopt;
    index = 10 * index + static_cast<std::size_t>(name[k] - '0');
  }
  return index;
}

// `bodies`, each checked to be one of the model's.
std::vector<int> checkedBodies(const Model& model, std::vector<int> bodies, const std::string& label) {
  for (const int b : bodies)
    if (b < 0 || b >= static_cast<int>(model.bodies.size()))
      throw InputError(label + ": body index " + std::to_string(b) + " out of range");
  return bodies;
}

}  // namespace

MaskAgreement::MaskAgreement(const std::string& folder, const calib::Camera& camera, const Model& model,
                             std::vector<int> bodies, std::string label)
    : folder_(folder),
      label_(std::move(label)),
      camera_(camera),
      robot_(model, checkedBodies(model, std::move(bodies), label_)) {
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    throw InputError(label_ + ": not a folder (give the folder holding frame_000000.png, frame_000001.png, ...)");
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec))
    if (const std::optional<std::size_t> i = frameIndexOf(entry.path().filename().string())) indices_.push_back(*i);
  if (ec) throw InputError(label_ + ": cannot list the folder (" + ec.message() + ")");
  if (indices_.empty())
    throw InputError(
        label_ + ": no mask in the folder (expected frame_000000.png, frame_000001.png, ...: one per frame, from 0)");
  std::sort(indices_.begin(), indices_.end());
}

MaskAgreement::MaskAgreement(const calib::Camera& camera, const Model& model, std::vector<int> bodies,
                             std::string label)
    : label_(std::move(label)),
      camera_(camera),
      robot_(model, movingBodies(model, checkedBodies(model, std::move(bodies), label_))) {
  if (robot_.bodies().empty())
    throw InputError(label_ + ": no body of the model (of those the masks show) moves with a joint");
}

cv::Mat MaskAgreement::regionAt(std::span<const double> state) const {
  const double widen = 0.015 * std::hypot(camera_.width, camera_.height);
  return calib::robotRegion(camera_, calib::placeVolumes(robot_.model(), state, robot_.bodies()), widen);
}

void MaskAgreement::learnBackground(FrameSource& frames, const std::function<double(std::size_t)>& log_time,
                                    const StateLog& log, double max_gap) {
  const Model& model = robot_.model();
  std::vector<calib::BackgroundSample> samples;
  indices_.clear();
  std::size_t read = 0;
  for (SampledFrame& f : sampleFrames(frames, 40)) {
    ++read;
    if (f.bgr.type() != CV_8UC3 || f.bgr.cols != camera_.width || f.bgr.rows != camera_.height)
      throw InputError(label_ + ": frame " + std::to_string(f.index) +
                       " is not an 8-bit colour picture of the camera's " + std::to_string(camera_.width) + "x" +
                       std::to_string(camera_.height));
    std::vector<double> state(static_cast<std::size_t>(model.stateSize()), 0.0);
    const double t = log_time(f.index);
    if (!std::isfinite(t) || stateAt(log, t, max_gap, state) == StateMatch::None) continue;
    samples.push_back({std::move(f.bgr), regionAt(state)});
    indices_.push_back(f.index);
  }
  if (samples.size() < 8)
    throw InputError(
        label_ + ": only " + std::to_string(samples.size()) + " of " + std::to_string(read) +
        " frames spread over the recording have a logged state (8 or more needed to learn its background)");
  background_ = calib::estimateBackground(samples);
}

std::optional<double> MaskAgreement::at(std::size_t index, std::span<const double> state,
                                        const cv::Mat& picture) const {
  if (state.empty()) return std::nullopt;
  const std::vector<calib::PlacedMesh> meshes = robot_.meshes(state);
  const calib::Silhouette drawn = meshes.empty() ? calib::drawSilhouette(camera_, robot_.volumes(state))
                                                 : calib::drawMeshSilhouette(camera_, meshes);
  if (fromRecording()) {
    if (!background_ || picture.empty()) return std::nullopt;
    const cv::Mat mask = calib::foregroundMask({picture, regionAt(state)}, *background_);
    // Where the background is unknown (the robot never leaves), nothing is said: a frame whose
    // drawn robot lies mostly there has no agreement.
    const cv::Mat seen = drawn.mask & background_->known;
    const int seen_pixels = cv::countNonZero(seen);
    if (seen_pixels == 0 || seen_pixels < 0.25 * cv::countNonZero(drawn.mask)) return std::nullopt;
    return calib::maskIou(seen, mask);
  }
  if (!std::binary_search(indices_.begin(), indices_.end(), index)) return std::nullopt;
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06zu.png", index);
  const cv::Mat mask =
      calib::readMask((std::filesystem::path(folder_) / name).string(), camera_.width, camera_.height, false);
  return calib::maskIou(drawn.mask, mask);
}

AgreementSummary summariseAgreement(std::span<const FrameRecord> frames, double low_share) {
  AgreementSummary s;
  std::vector<double> ious;
  for (const FrameRecord& f : frames)
    if (f.mask_iou) ious.push_back(*f.mask_iou);
  if (ious.empty()) return s;
  s.frames = ious.size();
  for (double v : ious) s.mean += v / static_cast<double>(ious.size());
  std::vector<double> sorted = ious;
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  const std::size_t n = sorted.size();
  s.median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  s.low_below = low_share * s.median;
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (frames[i].mask_iou && *frames[i].mask_iou < s.low_below) s.low.push_back(i);
  std::stable_sort(s.low.begin(), s.low.end(),
                   [&](std::size_t a, std::size_t b) { return *frames[a].mask_iou < *frames[b].mask_iou; });
  return s;
}

}  // namespace kccd::overlay
