// The golden comparison never forgives a shift: a 1-pixel move of a long thin body across or
// along itself fails, a label boundary moved along an edge of 5 pixels fails; isolated
// single-pixel flips pass; labels are matched by body name; sizes and body sets are checked first.
#include <gtest/gtest.h>

#include <random>

#include <opencv2/imgproc.hpp>

#include "kccd/overlay/golden/golden_compare.hpp"

namespace kccd::overlay {
namespace {

const std::vector<std::string> kNames = {"base", "link", "tool"};

// A mask with a base block, a long thin link (3 px wide, 80 long) offset by (dx, dy), and a tool.
cv::Mat scene(int dx = 0, int dy = 0, int link_label = 2) {
  cv::Mat m(120, 160, CV_8UC1, cv::Scalar(0));
  cv::rectangle(m, cv::Rect(10, 80, 40, 30), cv::Scalar(1), cv::FILLED);
  cv::rectangle(m, cv::Rect(40 + dx, 50 + dy, 80, 3), cv::Scalar(link_label), cv::FILLED);
  cv::circle(m, cv::Point(130, 90), 12, cv::Scalar(3), cv::FILLED);
  return m;
}

TEST(GoldenCompare, IdenticalMasksAndRenumberedLabelsAreIdentical) {
  const Comparison same = compareMasks(scene(), kNames, scene(), kNames);
  EXPECT_TRUE(same.passed && same.identical) << same.reason;
  // The same picture from a re-ordered import: labels differ, names say they are the same bodies.
  cv::Mat renumbered = scene();
  renumbered.setTo(9, renumbered == 1);
  renumbered.setTo(1, renumbered == 3);
  renumbered.setTo(3, renumbered == 9);
  const Comparison r = compareMasks(scene(), kNames, renumbered, {"tool", "link", "base"});
  EXPECT_TRUE(r.passed && r.identical) << r.reason;
  ASSERT_EQ(r.bodies.size(), 3u);
  EXPECT_EQ(r.bodies[1].expected_px, 240);
}

TEST(GoldenCompare, AOnePixelMoveOfAThinLinkFailsAcrossAndAlong) {
  const Comparison across = compareMasks(scene(), kNames, scene(0, 1), kNames);
  EXPECT_FALSE(across.passed);
  EXPECT_NE(across.reason.find("largest cluster of changed pixels"), std::string::npos) << across.reason;
  EXPECT_GE(across.largest_cluster_px, 80);
  // Along: only the two 3-pixel ends change (each cluster within the cluster rule); the centroid
  // moved by a whole pixel.
  const Comparison along = compareMasks(scene(), kNames, scene(1, 0), kNames);
  EXPECT_FALSE(along.passed);
  EXPECT_EQ(along.largest_cluster_px, 3);
  EXPECT_NE(along.reason.find("body 'link': centroid moved 1 px"), std::string::npos) << along.reason;
}

TEST(GoldenCompare, ABoundaryMovedAlongFivePixelsFails) {
  cv::Mat moved = scene();
  // Five pixels of the base's top edge grow by one row.
  moved(cv::Rect(20, 79, 5, 1)).setTo(1);
  const Comparison c = compareMasks(scene(), kNames, moved, kNames);
  EXPECT_FALSE(c.passed) << c.reason;
  EXPECT_EQ(c.largest_cluster_px, 5);
  cv::Mat four = scene();
  four(cv::Rect(20, 79, 4, 1)).setTo(1);
  EXPECT_TRUE(compareMasks(scene(), kNames, four, kNames).passed) << "4 pixels in a row: within the cluster rule";
}

TEST(GoldenCompare, IsolatedFlipsAlongEdgesPass) {
  // A rasteriser that rounds differently where an edge passes a pixel centre: single pixels,
  // far apart, each flipped to the neighbouring label.
  cv::Mat flipped = scene();
  for (int x = 12; x < 50; x += 6) flipped.at<std::uint8_t>(80, x) = 0;   // the base's top edge
  for (int x = 42; x < 118; x += 7) flipped.at<std::uint8_t>(49, x) = 2;  // above the link
  flipped.at<std::uint8_t>(90, 142) = 0;                                  // the tool's rim
  const Comparison c = compareMasks(scene(), kNames, flipped, kNames);
  EXPECT_TRUE(c.passed) << c.reason;
  EXPECT_FALSE(c.identical);
  EXPECT_EQ(c.largest_cluster_px, 1);
  EXPECT_NE(c.reason.find("forgiven"), std::string::npos);
  EXPECT_LT(c.worst_centroid_shift_px, 0.25);
}

TEST(GoldenCompare, SizesAndBodySetsComeFirst) {
  const Comparison size = compareMasks(scene(), kNames, cv::Mat(100, 160, CV_8UC1, cv::Scalar(0)), kNames);
  EXPECT_FALSE(size.passed);
  EXPECT_EQ(size.reason, "size: the golden is 160x120, the image 160x100");
  cv::Mat without = scene();
  without.setTo(0, without == 3);
  const Comparison removed = compareMasks(scene(), kNames, without, {"base", "link"});
  EXPECT_FALSE(removed.passed);
  EXPECT_EQ(removed.reason, "bodies: missing 'tool'");
  const Comparison renamed = compareMasks(scene(), kNames, scene(), {"base", "arm", "tool"});
  EXPECT_EQ(renamed.reason, "bodies: missing 'link' new 'arm'");
  // A body with the same name whose pixels all went: its area rule fails.
  const Comparison hidden = compareMasks(scene(), kNames, without, kNames);
  EXPECT_FALSE(hidden.passed);
}

TEST(GoldenCompare, ColourChangesBeyondTheThresholdCountAndShiftsFail) {
  cv::Mat a(60, 80, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  cv::rectangle(a, cv::Rect(10, 10, 40, 30), cv::Scalar(40, 200, 40, 180), cv::FILLED);
  cv::Mat b = a.clone();
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> noise(-24, 24);
  for (int y = 0; y < b.rows; ++y)
    for (int x = 0; x < b.cols; ++x)
      for (int k = 0; k < 4; ++k)
        b.at<cv::Vec4b>(y, x)[k] = cv::saturate_cast<std::uint8_t>(b.at<cv::Vec4b>(y, x)[k] + noise(rng));
  const Comparison noisy = compareColour(a, b);
  EXPECT_TRUE(noisy.passed) << noisy.reason;
  EXPECT_FALSE(noisy.identical);
  EXPECT_EQ(noisy.changed_px, 0) << "no channel beyond 24 grey levels";

  cv::Mat shifted(60, 80, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  cv::rectangle(shifted, cv::Rect(11, 10, 40, 30), cv::Scalar(40, 200, 40, 180), cv::FILLED);
  const Comparison shift = compareColour(a, shifted);
  EXPECT_FALSE(shift.passed);
  EXPECT_EQ(shift.largest_cluster_px, 30);

  cv::Mat scattered = a.clone();
  for (int k = 0; k < 50; ++k)
    scattered.at<cv::Vec4b>(2 + (k / 10) * 3, 2 + (k % 10) * 7) = cv::Vec4b(255, 255, 255, 255);
  const Comparison many = compareColour(a, scattered);
  EXPECT_FALSE(many.passed);
  EXPECT_EQ(many.reason, "50 changed pixels (allowed 40)");
  EXPECT_TRUE(compareColour(a, scattered, {.channel_threshold = 24, .max_cluster_px = 4, .max_diff_px = 50}).passed);
  EXPECT_FALSE(compareColour(a, cv::Mat(60, 80, CV_8UC3, cv::Scalar(0, 0, 0))).passed);
}

TEST(GoldenCompare, EvidencePictures) {
  const Comparison c = compareMasks(scene(), kNames, scene(0, 1), kNames);
  const cv::Mat diff = diffPicture(scene(), scene(0, 1), c, true);
  EXPECT_EQ(diff.size(), cv::Size(160, 120));
  EXPECT_EQ(diff.type(), CV_8UC3);
  EXPECT_EQ(diff.at<cv::Vec3b>(50, 60), cv::Vec3b(40, 40, 255)) << "a changed pixel is red";
  const cv::Mat crop = magnifiedCrop(diff, c.largest_cluster);
  EXPECT_EQ(crop.cols % 8, 0);
  EXPECT_GE(crop.cols, 8 * 24);
  const cv::Mat fc = falseColour(scene());
  EXPECT_EQ(fc.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  EXPECT_NE(fc.at<cv::Vec3b>(90, 20), fc.at<cv::Vec3b>(51, 60)) << "bodies in different colours";
}

}  // namespace
}  // namespace kccd::overlay
