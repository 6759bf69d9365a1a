// Golden-image regression harness shared by the image tests.
//
// compareGolden(actual, name) compares an image with data/golden/<name>.png:
// - identical images pass;
// - otherwise the test passes when at most `max_pixels` pixels (default 0.25% of the image,
//   at least 4) differ by more than `threshold` levels in some channel (default 24 of 255;
//   0 for label masks, where any change of label counts);
// - on failure <build>/tests/golden_out/<name>.actual.png and <name>.diff.png (absolute
//   difference amplified 8x, alpha made opaque) are written and their paths printed.
// Goldens are rewritten only with UPDATE_GOLDEN=1 in the environment (never by a normal run);
// data/golden/golden.yaml records the renderer string they were made with, and a differing
// renderer is reported (as a warning) next to any failure.
#pragma once

#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace kccd::testing {

struct GoldenTolerance {
  int threshold = 24;            ///< per-channel difference that counts a pixel as different
  double max_fraction = 0.0025;  ///< allowed fraction of different pixels
  int min_pixels = 4;            ///< allowed different pixels at least
};

/// Compares `actual` with the golden `name` (see above). `renderer` is the GL renderer string.
::testing::AssertionResult compareGolden(const cv::Mat& actual, const std::string& name, const std::string& renderer,
                                         const GoldenTolerance& tolerance = {});

}  // namespace kccd::testing
