// Label masks against an independent CPU silhouette, nearest-body labels, degenerate and
// undrawable volumes, tiny images, and the GL context.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/renderer.hpp"
#include "support/cameras.hpp"
#include "support/silhouette.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
using namespace kccd::calib;
using kccd::testing::cpuSilhouette;
using kccd::testing::cpuSilhouetteFine;
using kccd::testing::lookAt;
using kccd::testing::randomCamera;

TEST(RenderCamera, TinyImagesRender) {
  for (const auto& [w, h] : {std::pair{8, 3}, std::pair{3, 8}, std::pair{1, 1}}) {
    Camera c = lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), w, h, 3.0 * w, {-0.1, 0.01, 0, 0, 0});
    c.camera_matrix(0, 2) = (w - 1) / 2.0;
    c.camera_matrix(1, 2) = (h - 1) / 2.0;
    Renderer r(c);
    const std::vector<Vec3> ball = {Vec3(0, 0, 0)};
    const Volume v[] = {{ball, 1.5, SafetyStatus::Clear, "ball"}};  // wider than the view
    const Frame f = r.render(v, Style{.labels = true, .legend = true});
    EXPECT_EQ(f.bgra.cols, w);
    EXPECT_EQ(f.bgra.rows, h);
    EXPECT_EQ(f.pixels[0], w * h) << w << "x" << h;
  }
}

// ---------------------------------------------------------------------------------------------
// Masks against an independent CPU silhouette

TEST(RenderMask, MatchesIndependentCpuSilhouette) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_iou = 1.0, worst_boundary = 0.0;
  for (int trial = 0; trial < 12; ++trial) {
    const Camera c = randomCamera(rng, trial % 4 != 3);  // mostly with distortion
    std::vector<Vec3> pts;
    const int n = 1 + trial % 4;
    for (int i = 0; i < n; ++i) pts.push_back(Vec3(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng)));
    const double radius = 0.15 + 0.1 * std::abs(u(rng));
    const cv::Mat cpu = cpuSilhouette(c, pts, radius);
    Renderer r(c);
    const Volume v{pts, radius, SafetyStatus::Clear, ""};
    const Frame f = r.render(std::span<const Volume>(&v, 1), Style{}, false, true);
    const cv::Mat gl = f.mask > 0, ref = cpu > 0;
    const double inter = cv::countNonZero(gl & ref), uni = cv::countNonZero(gl | ref);
    const double iou = inter / uni;
    worst_iou = std::min(worst_iou, iou);
    // Containment up to a one-pixel boundary: every CPU pixel is in the mask or next to it.
    cv::Mat grown;
    cv::dilate(gl, grown, cv::Mat::ones(3, 3, CV_8U));
    const int outside = cv::countNonZero(ref & ~grown);
    const int boundary = cv::countNonZero(ref & ~gl);
    SCOPED_TRACE("trial " + std::to_string(trial) + ": mask " + std::to_string(cv::countNonZero(gl)) + " px, CPU " +
                 std::to_string(cv::countNonZero(ref)) + " px, common " + std::to_string(static_cast<int>(inter)));
    EXPECT_GT(uni, 2000);
    EXPECT_GE(iou, 0.98);
    EXPECT_EQ(outside, 0);
    EXPECT_LE(boundary, 0.02 * cv::countNonZero(ref));
    worst_boundary = std::max(worst_boundary, static_cast<double>(boundary) / cv::countNonZero(ref));
  }
  std::cout << "mask vs CPU silhouette: worst IoU " << worst_iou
            << ", CPU pixels outside the mask (all within 1 px): at most " << 100.0 * worst_boundary
            << "% of the silhouette\n";
}

// Every mask pixel that disagrees with the independent silhouette at its centre lies within the
// frame's reported bound (Frame::mask_edge_px) of the silhouette's edge, at mask scales 1, 2 and 3,
// for lenses from strong barrel to pincushion, volumes small and far to large and near. The
// silhouette is filled at 7x, so it is itself exact to about 0.1 px: 0.15 px is allowed for it.
TEST(RenderMask, EdgesLieWithinTheReportedBound) {
  std::mt19937_64 rng(57);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int k = kccd::testing::kSilhouetteScale;
  std::array<double, 4> worst{}, bound_max{}, bound_min{1e9, 1e9, 1e9, 1e9};
  int disagreeing = 0;
  for (int trial = 0; trial < 8; ++trial) {
    Camera c = randomCamera(rng, true, 240, 180);
    if (trial % 4 == 0) c.distortion = {-0.28, 0.09, 0.001, -0.001, -0.012};  // strong barrel
    if (trial % 4 == 1) c.distortion = {0.12, 0.02, 0.0, 0.0, 0.0};           // pincushion
    std::vector<Vec3> pts;
    const int n = 1 + trial % 3;
    for (int i = 0; i < n; ++i) pts.push_back(Vec3(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng)));
    const double radius = trial % 2 ? 0.05 + 0.05 * std::abs(u(rng)) : 0.25 + 0.1 * std::abs(u(rng));
    const cv::Mat fine = cpuSilhouetteFine(c, pts, radius);
    cv::Mat to_inside, to_outside;  // fine-pixel distances to the nearest inside / outside fine pixel
    cv::distanceTransform(fine == 0, to_inside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    cv::distanceTransform(fine != 0, to_outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    const Volume v{pts, radius, SafetyStatus::Clear, ""};
    for (const int scale : {1, 2, 3}) {
      Renderer r(c, RenderOptions{.mask_supersample = static_cast<double>(scale)});
      const Frame f = r.render(std::span<const Volume>(&v, 1), Style{}, false, true);
      ASSERT_TRUE(std::isfinite(f.mask_edge_px));
      double far = 0.0;
      for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; ++x) {
          const bool labelled = f.mask.at<uchar>(y, x) != 0;
          const int fy = y * k + k / 2, fx = x * k + k / 2;
          if (labelled == (fine.at<uchar>(fy, fx) != 0)) continue;
          ++disagreeing;
          far = std::max(far, static_cast<double>((labelled ? to_inside : to_outside).at<float>(fy, fx)) / k);
        }
      SCOPED_TRACE("trial " + std::to_string(trial) + ", mask scale " + std::to_string(scale));
      EXPECT_LE(far, f.mask_edge_px + 0.15);
      EXPECT_GT(cv::countNonZero(f.mask), 150);
      worst[scale] = std::max(worst[scale], far);
      bound_max[scale] = std::max(bound_max[scale], f.mask_edge_px);
      bound_min[scale] = std::min(bound_min[scale], f.mask_edge_px);
    }
  }
  EXPECT_GT(disagreeing, 0);  // the bound is exercised, not vacuous
  for (const int scale : {1, 2, 3})
    std::cout << "mask scale " << scale << ": reported bound " << bound_min[scale] << ".." << bound_max[scale]
              << " px, farthest disagreeing pixel " << worst[scale] << " px from the silhouette's edge\n";
  // Finer masks are tighter, and scale 3 meets half a pixel on these lenses.
  EXPECT_LT(bound_max[3], bound_max[1]);
  EXPECT_LE(bound_max[3], 0.5);
}

TEST(RenderMask, NearestBodyWinsAndLabelsAreIndexPlusOne) {
  const Camera c = lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), 160, 120, 150, {0, 0, 0, 0, 0});
  Renderer r(c);
  const std::vector<Vec3> far = {Vec3(-0.3, 0, 0)}, near = {Vec3(0.3, 0.1, 0)};
  // The far one first in the list, so drawing order alone would let it win.
  const Volume v[] = {{far, 0.25, SafetyStatus::Clear, "far"}, {near, 0.15, SafetyStatus::Colliding, "near"}};
  const Frame f = r.render(v, Style{.legend = false}, true, true);
  const cv::Point centre_near(static_cast<int>(std::lround(r.projection().project(near[0]).x())),
                              static_cast<int>(std::lround(r.projection().project(near[0]).y())));
  EXPECT_EQ(f.mask.at<uchar>(centre_near), 2);
  EXPECT_EQ(f.mask.at<uchar>(0, 0), 0);
  EXPECT_GT(f.pixels[0], 0);
  EXPECT_GT(f.pixels[1], 0);
  EXPECT_EQ(f.pixels[0] + f.pixels[1], cv::countNonZero(f.mask));
  // Straight alpha: the fill of the near body alone shows its colour at the fill opacity.
  const cv::Point far_only(static_cast<int>(std::lround(r.projection().project(far[0]).x())) - 10,
                           static_cast<int>(std::lround(r.projection().project(far[0]).y())));
  ASSERT_EQ(f.mask.at<uchar>(far_only), 1);
  const cv::Vec4b px = f.bgra.at<cv::Vec4b>(far_only);
  EXPECT_NEAR(px[3], 0.35 * 255, 2);
  const cv::Scalar green = statusColour(SafetyStatus::Clear);
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(px[ch], green[ch], 3) << ch;
  EXPECT_EQ(f.bgra.at<cv::Vec4b>(c.height - 1, c.width - 1)[3], 0);
}

// The labels come out of the colour pass (overlay look), or from a pass of their own (mask alone,
// shaded look, multisampling): the same masks either way, in any order of frames.
TEST(RenderMask, SameLabelsFromTheColourPassAndAlone) {
  const Camera c = lookAt(Vec3(1.5, -1.0, 1.0), Vec3(0, 0, 0), 200, 150, 180, {-0.1, 0.01, 0, 0, 0});
  const std::vector<Vec3> a = {Vec3(-0.2, 0, 0), Vec3(0.2, 0.1, 0)}, b = {Vec3(0.1, 0.1, 0.1)},
                          d = {Vec3(0, -0.3, 0.2)};
  const Volume v[] = {{a, 0.15, SafetyStatus::Clear, "a"},
                      {b, 0.2, SafetyStatus::Colliding, "b"},
                      {d, 0.1, SafetyStatus::WithinMargin, "d"}};
  Renderer plain(c);
  Renderer msaa(c, RenderOptions{.msaa_samples = 4});
  const Frame together = plain.render(v, Style{}, true, true);
  const Frame alone = plain.render(v, Style{}, false, true);
  const Frame shaded = plain.render(v, Style{.shaded = true}, true, true);
  const Frame again = plain.render(v, Style{}, true, true);
  const Frame mask_first = msaa.render(v, Style{}, false, true);
  const Frame multisampled = msaa.render(v, Style{}, true, true);
  EXPECT_GT(together.pixels[0], 100);
  EXPECT_GT(together.pixels[1], 100);
  EXPECT_GT(together.pixels[2], 100);
  for (const Frame* f : {&alone, &shaded, &again, &mask_first, &multisampled}) {
    EXPECT_EQ(cv::countNonZero(f->mask != together.mask), 0);
    EXPECT_EQ(f->pixels, together.pixels);
  }
  // The colour layer does not depend on whether a mask is drawn with it, nor on a mask drawn before.
  const Frame colour_only = plain.render(v, Style{}, true, false);
  EXPECT_EQ(cv::norm(colour_only.bgra, together.bgra, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(multisampled.bgra, msaa.render(v, Style{}, true, false).bgra, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(multisampled.bgra.reshape(1) > 0), 1000);
}

// A volume right next to the camera (outside the view) pulls the near plane in to a fraction of
// a millimetre; the labels of two nearly coincident capsules 3 m away must not change (the label
// pass's reversed float depth resolves ~1e-7 of the distance whatever the near plane; a
// conventional depth buffer would resolve only ~1 mm there and mix the two labels up).
TEST(RenderMask, LabelsDoNotDependOnTheNearPlane) {
  const Camera c = lookAt(Vec3(3, 0, 0), Vec3(0, 0, 0), 320, 240, 300, {0, 0, 0, 0, 0});
  const std::vector<Vec3> a = {Vec3(0, -0.5, 0), Vec3(0, 0.5, 0)};
  const std::vector<Vec3> b = {Vec3(0.0002, -0.5, 0.002), Vec3(0.0002, 0.5, -0.002)};  // crossing a at 0.2 mm
  const std::vector<Vec3> close = {Vec3(3 - 0.0005, 0.0025, 0)};                       // 0.5 mm in front, 2.5 mm aside
  const Volume pair[] = {{a, 0.1, SafetyStatus::Clear, "a"}, {b, 0.1, SafetyStatus::Colliding, "b"}};
  const Volume with_close[] = {pair[0], pair[1], {close, 0.001, SafetyStatus::Clear, "close"}};
  Renderer r(c);
  const Frame plain = r.render(pair, Style{}, false, true);
  const Frame near = r.render(with_close, Style{}, false, true);
  EXPECT_LT(near.near, 1e-3);  // the close volume did pull the near plane in
  EXPECT_EQ(near.pixels[2], 0);
  EXPECT_GT(plain.pixels[0], 500);
  EXPECT_GT(plain.pixels[1], 500);
  EXPECT_EQ(cv::countNonZero(plain.mask != near.mask), 0);
}

// The mask's distortion warp (done on the GPU) is the nearest-pixel remap of the pinhole labels:
// the same labels drawn through the undistorted pinhole camera and remapped on the CPU with
// OpenCV's nearest-pixel map give the same mask, pixel for pixel, at both mask scales.
TEST(RenderMask, WarpIsTheNearestPixelRemapOfThePinholeLabels) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    const Camera c = randomCamera(rng, true, 300, 200);
    std::vector<std::vector<Vec3>> cores(4);
    std::vector<Volume> v;
    for (std::size_t i = 0; i < cores.size(); ++i) {
      cores[i] = {Vec3(0.5 * u(rng), 0.5 * u(rng), 0.5 * u(rng)), Vec3(0.5 * u(rng), 0.5 * u(rng), 0.5 * u(rng))};
      v.push_back(Volume{cores[i], 0.05 + 0.1 * std::abs(u(rng)), SafetyStatus::Clear, ""});
    }
    for (const double scale : {1.0, 2.0}) {
      // The finest tessellation for both (the level otherwise follows the output camera's focal length).
      const RenderOptions options{.mask_supersample = scale, .tolerance_px = 0.0};
      Renderer distorted(c, options);
      const Projection& mp = distorted.maskProjection();
      Camera pinhole = c;  // the pinhole image as a camera of its own: drawn without a warp
      const Pinhole& ph = mp.pinhole();
      pinhole.width = ph.width;
      pinhole.height = ph.height;
      pinhole.camera_matrix = cv::Matx33d(ph.fx, 0, ph.cx, 0, ph.fy, ph.cy, 0, 0, 1);
      pinhole.distortion = {0, 0, 0, 0, 0};
      Renderer plain(pinhole, RenderOptions{.tolerance_px = 0.0});
      const Frame f = distorted.render(v, Style{}, false, true);
      const Frame p = plain.render(v, Style{}, false, true);
      ASSERT_EQ(f.near, p.near);
      cv::Mat map, unused, expected;
      cv::convertMaps(mp.mapX(), mp.mapY(), map, unused, CV_16SC2, true);
      cv::remap(p.mask, expected, map, cv::Mat(), cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar::all(0));
      SCOPED_TRACE("trial " + std::to_string(trial) + ", mask scale " + std::to_string(scale));
      EXPECT_GT(cv::countNonZero(expected), 500);
      EXPECT_EQ(cv::countNonZero(f.mask != expected), 0);
    }
  }
}

// Appearance surfaces (Volume::surface): a triangle mesh drawn like the volume it bounds, both
// sides, with the mask label it is given (0 hides what is behind it without a label).
TEST(RenderMask, SurfacesDrawBothSidesWithTheirOwnLabels) {
  const Camera c = lookAt(Vec3(2, 0.5, 0.8), Vec3(0, 0, 0), 240, 180, 220, {-0.05, 0, 0, 0, 0});
  std::vector<Vec3> corners, soup;
  for (int i = 0; i < 8; ++i) corners.emplace_back(i & 1 ? 0.2 : -0.2, i & 2 ? 0.2 : -0.2, i & 4 ? 0.2 : -0.2);
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces)
    soup.insert(soup.end(), {corners[f[0]], corners[f[1]], corners[f[2]], corners[f[0]], corners[f[2]], corners[f[3]]});
  const auto box = std::make_shared<const Mesh>(surfaceMesh(soup));
  EXPECT_EQ(box->vertices.size(), 24u);  // each corner once per face: the creases stay sharp
  EXPECT_EQ(box->triangles.size(), 12u);
  Renderer r(c);
  Volume surface;
  surface.surface = box;
  surface.mask_label = 7;
  const Frame fs = r.render(std::span<const Volume>(&surface, 1), Style{.legend = false, .shaded = true}, true, true);
  const Volume ssch{corners, 0.0, SafetyStatus::Clear, ""};
  const Frame fv = r.render(std::span<const Volume>(&ssch, 1), Style{.shaded = true}, true, true);
  const cv::Mat a = fs.mask > 0, b = fv.mask > 0;
  EXPECT_EQ(cv::countNonZero(fs.mask == 7), cv::countNonZero(a));
  EXPECT_EQ(fs.pixels[0], cv::countNonZero(a));
  EXPECT_GT(fs.pixels[0], 2000);
  // The SSCH of the same corners is drawn 1 mm thicker: the same silhouette within a pixel.
  EXPECT_GE(static_cast<double>(cv::countNonZero(a & b)) / cv::countNonZero(a | b), 0.97);
  EXPECT_EQ(fs.visibility[0], Visibility::Drawn);
  // Shaded and opaque where it is drawn (inside its anti-aliased edge).
  cv::Mat alpha, inside;
  cv::extractChannel(fs.bgra, alpha, 3);
  cv::erode(a, inside, cv::Mat::ones(3, 3, CV_8U));
  EXPECT_GT(cv::countNonZero(inside), 1500);
  EXPECT_EQ(cv::countNonZero((alpha == 255) & inside), cv::countNonZero(inside));

  // One triangle turned away from the camera is drawn all the same.
  std::vector<Vec3> back = {Vec3(0, -0.3, -0.3), Vec3(0, -0.3, 0.3), Vec3(0, 0.3, 0)};
  std::vector<Vec3> front = {back[0], back[2], back[1]};
  for (const auto* tri : {&back, &front}) {
    Volume t;
    t.surface = std::make_shared<const Mesh>(surfaceMesh(*tri));
    const Frame f = r.render(std::span<const Volume>(&t, 1), Style{.shaded = true}, true, true);
    EXPECT_GT(f.pixels[0], 500);
  }
  // In the tinted look the colour layer is the same with the mask drawn in the same pass or not.
  const Frame tinted = r.render(std::span<const Volume>(&surface, 1), Style{}, true, true);
  const Frame tinted_alone = r.render(std::span<const Volume>(&surface, 1), Style{}, true, false);
  EXPECT_EQ(cv::norm(tinted.bgra, tinted_alone.bgra, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(tinted.mask == 7), 2000);
  // Label 0 in front hides the volume behind it.
  Volume wall;
  wall.surface = std::make_shared<const Mesh>(surfaceMesh(std::vector<Vec3>{
      Vec3(1, -1, -1), Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(1, 1, 1), Vec3(1, -1, 1)}));
  wall.mask_label = 0;
  const Volume both[] = {ssch, wall};
  const Frame hidden = r.render(both, Style{.shaded = true}, false, true);
  EXPECT_EQ(hidden.pixels[0], 0);
  EXPECT_LT(cv::countNonZero(hidden.mask), cv::countNonZero(b) / 10);
}

TEST(RenderMask, DegenerateVolumesAreVisible) {
  const Camera c = lookAt(Vec3(1.5, -1.0, 1.0), Vec3(0, 0, 0), 160, 120, 150, {-0.1, 0.01, 0, 0, 0});
  Renderer r(c);
  const std::vector<Vec3> square = {Vec3(-0.3, -0.3, 0), Vec3(0.3, -0.3, 0), Vec3(0.3, 0.3, 0), Vec3(-0.3, 0.3, 0)};
  const std::vector<Vec3> segment = {Vec3(-0.4, 0.4, 0.2), Vec3(0.4, 0.4, 0.2)};
  const std::vector<Vec3> point = {Vec3(0, 0, 0.5)};
  const Volume v[] = {{square, 0.0, SafetyStatus::Clear, ""},
                      {segment, 0.0, SafetyStatus::Clear, ""},
                      {point, 0.05, SafetyStatus::Clear, ""}};
  const Frame f = r.render(v, Style{}, true, true);
  EXPECT_GT(f.pixels[0], 500);  // a flat square seen at an angle
  EXPECT_GT(f.pixels[2], 20);   // a ball
  EXPECT_GT(f.pixels[1], 0);    // a radius-0 segment, drawn 1 mm thick
  EXPECT_GT(cv::countNonZero(f.mask), 500);
}

TEST(RenderMask, VolumesThatCannotBeDrawnAreReported) {
  // Camera at x = 2 looking along -x: camera z = -world x, camera x = world -y (right).
  const Camera c = lookAt(Vec3(2, 0, 0), Vec3(0, 0, 0), 160, 120, 150, {0, 0, 0, 0, 0});
  Renderer r(c);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Vec3> behind = {Vec3(5, 0, 0)}, far = {Vec3(-2e7, 0, 0)}, bad = {Vec3(nan, 0, 0)},
                          distant = {Vec3(-500, 0, 0)}, off_axis = {Vec3(1.9999, -1e5, 0)};
  const Volume v[] = {{behind, 0.5, SafetyStatus::Clear, "behind"},
                      {far, 1e3, SafetyStatus::Clear, "far"},
                      {bad, 0.1, SafetyStatus::Clear, "bad"},
                      {distant, 30, SafetyStatus::Clear, "distant"},
                      {off_axis, 0.01, SafetyStatus::Clear, "off axis"}};
  const Frame f = r.render(v, Style{.labels = true}, true, true);
  EXPECT_EQ(f.visibility[0], Visibility::BehindCamera);
  EXPECT_EQ(f.visibility[1], Visibility::BeyondFar);
  EXPECT_EQ(f.visibility[2], Visibility::NotFinite);
  EXPECT_EQ(f.visibility[3], Visibility::Drawn);
  EXPECT_EQ(f.visibility[4], Visibility::Drawn);  // its label (centre at ~1e11 px) is skipped
  EXPECT_EQ(f.pixels[0] + f.pixels[1] + f.pixels[2], 0);
  EXPECT_GT(f.pixels[3], 50);  // 500 m away, beyond the default far plane (100 m): still drawn
  EXPECT_GT(f.far, 500.0);
  // 1 cm from the camera (closer than the default near plane, 5 cm): a ball of 2 cm radius
  // seen from 1 cm covers the whole view, not clipped away by the near plane.
  const std::vector<Vec3> close = {Vec3(1.97, 0, 0)};
  const Volume u[] = {{close, 0.02, SafetyStatus::Clear, "close"}};
  const Frame e = r.render(u, Style{}, true, true);
  EXPECT_EQ(e.visibility[0], Visibility::Drawn);
  EXPECT_LT(e.near, 0.01);
  EXPECT_EQ(e.pixels[0], c.width * c.height);
  EXPECT_STREQ(toString(Visibility::BeyondFar), "beyond far plane");

  // A volume containing the camera fills the view in the mask and tints the colour layer.
  const std::vector<Vec3> room = {Vec3(0, 0, 0)}, ball = {Vec3(0, 0, 0)};
  const Volume w[] = {{ball, 0.3, SafetyStatus::Clear, "ball"}, {room, 5.0, SafetyStatus::Colliding, "room"}};
  const Frame g = r.render(w, Style{.legend = false}, true, true);
  EXPECT_EQ(g.visibility[1], Visibility::FillsView);
  EXPECT_EQ(g.pixels[1], c.width * c.height);
  EXPECT_EQ(cv::countNonZero(g.mask == 2), c.width * c.height);
  EXPECT_NEAR(g.bgra.at<cv::Vec4b>(0, 0)[3], 0.35 * 255, 2);
  EXPECT_GT(g.bgra.at<cv::Vec4b>(c.height / 2, c.width / 2)[3],
            g.bgra.at<cv::Vec4b>(0, 0)[3]);  // the ball shows through
}

TEST(RenderContext, ReportsItsRenderer) {
  const auto ctx = GlContext::make();
  EXPECT_FALSE(ctx->renderer().empty());
  std::cout << "renderer: " << ctx->renderer() << "\n";
  const char* chosen = std::getenv("KCCD_GL");
  // Unset: EGL when this build has it (OSMesa only when EGL gives no context; not on CI machines).
  const GlBackend expected = chosen != nullptr && std::string(chosen) == "osmesa" ? GlBackend::OsMesa
                             : chosen == nullptr && !compiledIn(GlBackend::Egl)   ? GlBackend::OsMesa
                                                                                  : GlBackend::Egl;
  EXPECT_EQ(ctx->backend(), expected) << toString(ctx->backend());
  EXPECT_NE(ctx->renderer().find(expected == GlBackend::Egl ? "EGL" : "OSMesa"), std::string::npos);
}

// GlPreparation loads the driver on a thread of its own; contexts made at once on other threads,
// while it may still be loading, wait for it and work, as does one made after it ended.
TEST(RenderContext, ContextsMadeWhileTheDriverIsPreparedWork) {
  std::vector<std::string> renderers(3);
  {
    const GlPreparation preparation;
    std::vector<std::thread> threads;
    for (std::size_t i = 0; i < renderers.size(); ++i)
      threads.emplace_back([&renderers, i] {
        const auto ctx = GlContext::make();
        renderers[i] = ctx->renderer();
      });
    for (std::thread& t : threads) t.join();
  }
  { const GlPreparation again; }
  const std::string alone = GlContext::make()->renderer();
  ASSERT_FALSE(alone.empty());
  for (const std::string& r : renderers) EXPECT_EQ(r, alone);
}

TEST(RenderContext, UnknownOrMissingBackendIsAOneLineError) {
  const char* saved = std::getenv("KCCD_GL");
  const std::string restore = saved == nullptr ? "" : saved;
  ::setenv("KCCD_GL", "vulkan", 1);
  try {
    (void)GlContext::make();
    ADD_FAILURE() << "KCCD_GL=vulkan accepted";
  } catch (const GlContextError& e) {
    EXPECT_EQ(std::string(e.what()), "KCCD_GL=vulkan: unknown GL back end (use egl or osmesa)");
  }
  if (saved == nullptr)
    ::unsetenv("KCCD_GL");
  else
    ::setenv("KCCD_GL", restore.c_str(), 1);
  for (const GlBackend b : {GlBackend::Egl, GlBackend::OsMesa}) {
    if (compiledIn(b)) {
      EXPECT_EQ(GlContext::make(b)->backend(), b);
    } else {
      try {
        (void)GlContext::make(b);
        ADD_FAILURE() << toString(b) << " made without being compiled in";
      } catch (const GlContextError& e) {
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
      }
    }
  }
}

}  // namespace
