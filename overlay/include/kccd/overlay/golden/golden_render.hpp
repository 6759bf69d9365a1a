// The images of `kccd golden`'s cases, with what made them: each case's model seen by its camera
// at a state, over a box or on a recorded frame, drawn as a label mask, a colour layer or the
// overlay frame, written as deterministic PNG (equal pixels, equal bytes), and a sidecar recording
// the SHA-256 of every input, the kccd version, the GL renderer and the render options.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "kccd/overlay/golden/golden_manifest.hpp"

namespace kccd::overlay {

/// SHA-256 of bytes, as 64 lower-case hex digits.
std::string sha256Hex(std::span<const unsigned char> bytes);

/// PNG bytes of an 8-bit image (1, 3 or 4 channels) made the same way every time: equal pixels,
/// equal bytes (with the same libpng and zlib).
std::vector<unsigned char> deterministicPng(const cv::Mat& image);

/// One image a case made.
struct GoldenImage {
  GoldenOutput output = GoldenOutput::Mask;
  cv::Mat image;  ///< mask CV_8UC1 (0 background, k: labels[k - 1]); colour CV_8UC4 BGRA; overlay CV_8UC3 BGR
  std::vector<std::string> labels;  ///< mask: the body name of each label
  std::vector<unsigned char> png;   ///< deterministicPng(image)
  std::string sha256;               ///< of png
};

/// What a case made, and what it was made from.
struct GoldenRendering {
  std::vector<GoldenImage> images;  ///< in the case's output order
  /// golden.json: {kccd_golden, case, kccd_version, renderer, options, inputs: {name: sha256 or
  /// values}, outputs: {mask: {file, sha256, labels}, ...}}
  nlohmann::json sidecar;
  std::string unsafe;  ///< the query's status word when it is not ok (the case cannot be trusted); empty: ok
};

/// The kccd version golden sidecars record.
const char* kccdVersion();

/// Renders the cases of one manifest. Every input is read when it is made, so a mistake in any
/// case stops the run before anything is rendered; models, cameras and logs are read once, and
/// one GL view is kept per model and camera.
class GoldenRenderer {
 public:
  /// Reads every input the manifest's cases name (models and their meshes, cameras, state logs,
  /// the recorded frames) and checks that they fit together (state lengths, image sizes). Throws
  /// InputError naming the file, or the case and field.
  explicit GoldenRenderer(const GoldenManifest& manifest);
  ~GoldenRenderer();
  GoldenRenderer(const GoldenRenderer&) = delete;
  GoldenRenderer& operator=(const GoldenRenderer&) = delete;

  /// Renders case `index` of the manifest. Throws render::GlContextError without a GL context.
  GoldenRendering render(std::size_t index);

  /// The GL renderer's name (after the first render; empty before).
  const std::string& rendererString() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kccd::overlay
