#include "kccd/overlay/recording/mask_agreement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/input_error.hpp"

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
    if (b < 0 || b >= static_cast<int>(model.bodies.size())) throw InputError(label + ": body index " + std::to_string(b) + " out of range");
  return bodies;
}

}  // namespace

MaskAgreement::MaskAgreement(const std::string& folder, const calib::Camera& camera, const Model& model, std::vector<int> bodies,
                             std::string label)
    : folder_(folder), label_(std::move(label)), camera_(camera), robot_(model, checkedBodies(model, std::move(bodies), label_)) {
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec))
    throw InputError(label_ + ": not a folder (give the folder holding frame_000000.png, frame_000001.png, ...)");
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec))
    if (const std::optional<std::size_t> i = frameIndexOf(entry.path().filename().string())) indices_.push_back(*i);
  if (ec) throw InputError(label_ + ": cannot list the folder (" + ec.message() + ")");
  if (indices_.empty()) throw InputError(label_ + ": no mask in the folder (expected frame_000000.png, frame_000001.png, ...: one per frame, from 0)");
  std::sort(indices_.begin(), indices_.end());
}

std::optional<double> MaskAgreement::at(std::size_t index, std::span<const double> state) const {
  if (state.empty() || !std::binary_search(indices_.begin(), indices_.end(), index)) return std::nullopt;
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06zu.png", index);
  const cv::Mat mask = calib::readMask((std::filesystem::path(folder_) / name).string(), camera_.width, camera_.height, false);
  const std::vector<calib::PlacedMesh> meshes = robot_.meshes(state);
  const calib::Silhouette drawn =
      meshes.empty() ? calib::drawSilhouette(camera_, robot_.volumes(state)) : calib::drawMeshSilhouette(camera_, meshes);
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
  std::stable_sort(s.low.begin(), s.low.end(), [&](std::size_t a, std::size_t b) { return *frames[a].mask_iou < *frames[b].mask_iou; });
  return s;
}

}  // namespace kccd::overlay
