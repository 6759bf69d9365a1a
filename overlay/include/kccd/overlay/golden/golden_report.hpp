// What `kccd golden run` leaves for a person and for CI: results.json (machine-readable, with the
// actual images' hashes `approve` checks), junit.xml (a test case per case and output),
// summary.md, a self-contained report.html (expected | actual | diff and an 8x crop around the
// largest changed cluster, the tolerances in force and where they came from), and the evidence
// images of the cases that did not pass.
#pragma once

#include <string>
#include <vector>

#include "kccd/overlay/golden/golden_check.hpp"
#include "kccd/overlay/golden/golden_manifest.hpp"
#include "kccd/overlay/golden/golden_render.hpp"

namespace kccd::overlay {

/// One run, as the reports describe it.
struct GoldenRun {
  const GoldenManifest* manifest = nullptr;
  std::vector<std::size_t> cases;           ///< the manifest's cases run, in order
  std::vector<GoldenRendering> renderings;  ///< per case run
  std::vector<CaseResult> results;          ///< per case run
  std::string renderer;                     ///< the GL renderer's name
  double seconds = 0.0;                     ///< the run's wall time
};

/// Writes the reports and evidence into `folder` (made when missing; files staged then renamed):
/// results.json, junit.xml, summary.md, report.html, and for each case that did not pass (every
/// case with `keep_passing`) `<id>/<output>.actual.png`, .expected.png, .diff.png, .crop.png and
/// `<id>/golden.json` (the actual sidecar).
void writeGoldenReports(const GoldenRun& run, const std::string& folder, bool keep_passing);

/// The one-line summary of a run: "N cases: P passed, F failed, M missing".
std::string goldenSummaryLine(const GoldenRun& run);

}  // namespace kccd::overlay
