// A case's images checked against its goldens (GOLDENS/<id>/<output>.png and golden.json), the
// likely cause of a difference from the two sidecars' hashes, and the goldens written.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kccd/overlay/golden/golden_compare.hpp"
#include "kccd/overlay/golden/golden_manifest.hpp"
#include "kccd/overlay/golden/golden_render.hpp"

namespace kccd::overlay {

/// How one output of a case ended.
enum class GoldenStatus { Passed, Failed, Missing };

/// "passed", "failed" or "missing".
const char* goldenStatusName(GoldenStatus status);

/// One output of one case.
struct OutputResult {
  GoldenOutput output = GoldenOutput::Mask;
  GoldenStatus status = GoldenStatus::Missing;
  std::string reason;        ///< one line: why it failed, what was forgiven, or empty when identical
  Comparison comparison;     ///< empty when missing
  nlohmann::json tolerance;  ///< the tolerances in force, with "from": built-in, defaults or case
  cv::Mat expected;          ///< the golden as read (empty when missing)
};

/// One case.
struct CaseResult {
  std::string id;
  std::vector<OutputResult> outputs;
  std::string cause;   ///< the likely cause of a failure from the sidecars; empty when all passed
  std::string unsafe;  ///< the query's status word when it was not ok
  bool passed() const;
};

/// The folder of case `id`'s goldens.
std::string goldenFolder(const GoldenManifest& manifest, const std::string& id);

/// Compares `rendering` (of `c`) with the goldens in `folder`. A golden image that cannot be read
/// or a sidecar that does not describe it is a failure saying so, never a pass.
CaseResult checkCase(const GoldenCase& c, const GoldenRendering& rendering, const std::string& folder);

/// The likely cause of a difference: the inputs that changed (model, meshes, camera, state log,
/// video frame, state or box), else the renderer, kccd version or options, else "nothing changed"
/// (the rendering is not deterministic).
std::string likelyCause(const nlohmann::json& golden, const nlohmann::json& actual);

/// Writes `rendering`'s images and its golden.json into `folder` (made when missing): each file
/// under a temporary name, then renamed. Other files in the folder are left alone.
void writeGoldens(const GoldenRendering& rendering, const std::string& folder);

}  // namespace kccd::overlay
