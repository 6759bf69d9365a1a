// The colour layer drawn, read back and warped only where the volumes and the legend are
// (RenderOptions::crop) is the whole image's layer bit for bit, and Frame::drawn holds every
// pixel it draws: random scenes through plain and distorting cameras, supersampled or not, with
// volumes partly outside the view, reaching behind the near plane or containing the camera. And
// Renderer::renderOnto (the layer blended onto a frame in the warp's pass, without making it)
// gives the composited frame bit for bit, as does Renderer::renderOntoAgain (the last layer onto
// another frame); one renderer drawing many frames never shows an earlier frame's pixels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "kccd/render/composite.hpp"
#include "kccd/render/renderer.hpp"
#include "support/cameras.hpp"
#include "support/random_shapes.hpp"

namespace {

using kccd::SafetyStatus;
using kccd::Vec3;
using kccd::calib::Camera;
using kccd::render::Frame;
using kccd::render::Renderer;
using kccd::render::RenderOptions;
using kccd::render::Style;
using kccd::render::Volume;

TEST(RenderCrop, TheCroppedLayerIsTheWholeLayerBitForBit) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  long drawn_area = 0, image_area = 0;
  for (int trial = 0; trial < 24; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const Camera c = kccd::testing::randomCamera(rng, trial % 2 == 0, 480, 320);
    const cv::Vec3d centre = kccd::testing::cameraCentre(c);
    const Vec3 eye(centre[0], centre[1], centre[2]);
    std::vector<Volume> scene;
    std::vector<std::vector<Vec3>> clouds;
    const int n = 1 + trial % 7;
    clouds.reserve(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      // Around the origin (what the random cameras look at); in some trials one volume right in
      // front of the camera (partly behind the near plane) or around it.
      Vec3 at(0.6 * u(rng), 0.6 * u(rng), 0.6 * u(rng));
      double radius = 0.01 + 0.08 * std::abs(u(rng));
      if (i == 0 && trial % 6 == 3) at = eye * 0.97;
      if (i == 0 && trial % 12 == 5) at = eye, radius = 0.3;
      const auto cloud =
          kccd::testing::randomCloud(rng, 1 + static_cast<int>(rng() % 10), at, 0.02 + 0.15 * std::abs(u(rng)));
      clouds.emplace_back(cloud.begin(), cloud.end());
      scene.push_back(Volume{clouds.back(), radius, static_cast<SafetyStatus>(i % 4), "body " + std::to_string(i)});
    }
    Style style;
    style.legend = trial % 3 != 0;
    style.labels = trial % 5 == 1;
    style.shaded = trial % 7 == 4;
    style.outline_width = trial % 4 == 2 ? 7.0 : 2.0;
    RenderOptions cropped, whole;
    cropped.supersample = whole.supersample = trial % 3 == 1 ? 2.0 : 1.0;
    cropped.mask_supersample = whole.mask_supersample = cropped.supersample;
    whole.crop = false;
    Renderer a(c, cropped), b(c, whole), onto(c, cropped);
    // Two frames each, the second of the same renderer after the first: what the first read back
    // must not show through.
    for (int frame = 0; frame < 2; ++frame) {
      if (frame == 1)
        for (Volume& v : scene) v.pose.translation() += Vec3(0.3, -0.2, 0.1);
      const Frame fa = a.render(scene, style, true, false);
      const Frame fb = b.render(scene, style, true, false);
      cv::Mat diff;
      cv::absdiff(fa.bgra, fb.bgra, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << "frame " << frame;
      // Every drawn pixel lies in a rectangle of Frame::drawn; the rectangles are disjoint.
      cv::Mat inside = cv::Mat::zeros(fa.bgra.size(), CV_8U);
      for (std::size_t i = 0; i < fa.drawn.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j) EXPECT_TRUE((fa.drawn[i] & fa.drawn[j]).empty());
        inside(fa.drawn[i] & cv::Rect(0, 0, inside.cols, inside.rows)).setTo(1);
        drawn_area += fa.drawn[i].area();
      }
      image_area += fa.bgra.total();
      cv::Mat any;
      cv::transform(fa.bgra, any, cv::Matx14f(1, 1, 1, 1));
      any.convertTo(any, CV_8U);
      cv::Mat outside;
      cv::compare(any, 0, outside, cv::CMP_GT);
      outside.setTo(0, inside);
      EXPECT_EQ(cv::countNonZero(outside), 0) << "frame " << frame;
      // Compositing only the rectangles gives the whole blend.
      cv::Mat photo(fa.bgra.size(), CV_8UC3);
      cv::randu(photo, 0, 256);
      cv::Mat all = photo.clone(), parts = photo.clone();
      kccd::render::compositeOver(all, fb.bgra);
      kccd::render::compositeOver(parts, fa.bgra, fa.drawn);
      cv::absdiff(all, parts, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << "frame " << frame;
      // Blended in the warp's pass: the same frame, the same rectangles, no layer.
      cv::Mat blended = photo.clone();
      const Frame fo = onto.renderOnto(blended, scene, style);
      EXPECT_TRUE(fo.bgra.empty());
      EXPECT_EQ(fo.drawn, fa.drawn) << "frame " << frame;
      EXPECT_EQ(fo.visibility, fa.visibility) << "frame " << frame;
      cv::absdiff(all, blended, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << "frame " << frame;
    }
  }
  // The point of it: far less than the image is handed on.
  EXPECT_LT(drawn_area, image_area / 2);
  std::cout << "drawn rectangles: " << 100.0 * static_cast<double>(drawn_area) / static_cast<double>(image_area)
            << " % of the images\n";
}

// One cropped renderer drawing a long run of frames whose looks and requests change from frame to
// frame (tinted, shaded, with a mask drawn in the same pass or alone, nothing drawn, a volume around
// the camera) and whose volumes jump across the image: each frame's layer is a fresh whole-image
// renderer's bit for bit, so what earlier frames left in the GL target (the tinted look clears only
// the cells it knows were drawn) never shows through.
TEST(RenderCrop, WhatEarlierFramesDrewNeverShowsThrough) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const bool distorted : {false, true}) {
    SCOPED_TRACE(distorted ? "distorting camera" : "plain camera");
    const Camera c = kccd::testing::randomCamera(rng, distorted, 400, 300);
    const cv::Vec3d centre = kccd::testing::cameraCentre(c);
    const Vec3 eye(centre[0], centre[1], centre[2]);
    RenderOptions cropped, whole;
    whole.crop = false;
    Renderer a(c, cropped);
    int tinted_after_other = 0;
    Style previous;
    for (int frame = 0; frame < 40; ++frame) {
      SCOPED_TRACE("frame " + std::to_string(frame));
      std::vector<std::vector<Vec3>> clouds;
      std::vector<Volume> scene;
      const int n = frame % 9 == 8 ? 0 : 1 + static_cast<int>(rng() % 6);
      clouds.reserve(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        Vec3 at(0.8 * u(rng), 0.8 * u(rng), 0.8 * u(rng));
        double radius = 0.01 + 0.1 * std::abs(u(rng));
        if (i == 0 && frame % 13 == 6) at = eye, radius = 0.3;  // around the camera: the whole view
        const auto cloud =
            kccd::testing::randomCloud(rng, 1 + static_cast<int>(rng() % 8), at, 0.02 + 0.2 * std::abs(u(rng)));
        clouds.emplace_back(cloud.begin(), cloud.end());
        scene.push_back(Volume{clouds.back(), radius, static_cast<SafetyStatus>(i % 4), "body " + std::to_string(i)});
      }
      Style style;
      style.shaded = frame % 5 == 2;
      style.legend = frame % 4 == 1;
      style.outline_width = frame % 3 == 0 ? 5.0 : 2.0;
      const bool mask = frame % 6 == 3;
      if (!style.shaded && !mask && frame > 0 && (previous.shaded || frame % 6 == 4)) ++tinted_after_other;
      previous = style;
      if (frame % 7 == 5) (void)a.render(scene, style, false, true);  // a mask alone in between
      Renderer b(c, whole);
      const Frame fa = a.render(scene, style, true, mask);
      const Frame fb = b.render(scene, style, true, mask);
      cv::Mat diff;
      cv::absdiff(fa.bgra, fb.bgra, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0);
      if (mask) {
        cv::absdiff(fa.mask, fb.mask, diff);
        EXPECT_EQ(cv::countNonZero(diff), 0);
      }
    }
    EXPECT_GT(tinted_after_other, 3);  // the looks really alternate
  }
}

// The last renderOnto()'s layer onto another picture: what renderOnto() gives there, the same
// Frame::drawn; only after a renderOnto() in that style, and never after another draw.
TEST(RenderCrop, RenderOntoAgainIsRenderOntoWithoutTheDrawing) {
  std::mt19937_64 rng(11);
  const Camera c = kccd::testing::randomCamera(rng, true, 320, 240);
  Renderer r(c), fresh(c);
  std::vector<Vec3> cloud{Vec3(0.05, 0.0, 0.0), Vec3(-0.1, 0.1, 0.05)};
  const std::vector<Volume> scene{Volume{cloud, 0.15, SafetyStatus::WithinMargin, "arm"}};
  Style style;
  cv::Mat first(240, 320, CV_8UC3), second(240, 320, CV_8UC3);
  cv::randu(first, 0, 256);
  cv::randu(second, 0, 256);
  EXPECT_FALSE(r.canRenderOntoAgain(style));
  EXPECT_THROW(r.renderOntoAgain(second, style), std::logic_error);
  const Frame drawn = r.renderOnto(first, scene, style);
  EXPECT_TRUE(r.canRenderOntoAgain(style));
  Style other = style;
  other.legend = false;
  EXPECT_FALSE(r.canRenderOntoAgain(other));
  cv::Mat again = second.clone(), expected = second.clone();
  const Frame fa = r.renderOntoAgain(again, style);
  const Frame fe = fresh.renderOnto(expected, scene, style);
  cv::Mat diff;
  cv::absdiff(again, expected, diff);
  EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0);
  EXPECT_GT(cv::countNonZero(cv::Mat(again != second).reshape(1)), 1000);  // something was drawn
  EXPECT_EQ(fa.drawn, fe.drawn);
  EXPECT_EQ(fa.visibility, drawn.visibility);
  cv::Mat grey(240, 320, CV_8UC1, cv::Scalar::all(0));
  EXPECT_THROW(r.renderOntoAgain(grey, style), std::invalid_argument);
  (void)r.render(scene, style, true, false);
  EXPECT_FALSE(r.canRenderOntoAgain(style));
  EXPECT_THROW(r.renderOntoAgain(again, style), std::logic_error);
}

TEST(RenderCrop, RenderOntoRejectsAFrameOfAnotherSizeOrType) {
  std::mt19937_64 rng(7);
  const Camera c = kccd::testing::randomCamera(rng, true, 160, 120);
  Renderer r(c);
  const std::vector<Vec3> cloud{Vec3::Zero()};
  const std::vector<Volume> scene{Volume{cloud, 0.1, SafetyStatus::Clear, "ball"}};
  cv::Mat small(119, 160, CV_8UC3, cv::Scalar::all(0)), grey(120, 160, CV_8UC1, cv::Scalar::all(0));
  EXPECT_THROW(r.renderOnto(small, scene), std::invalid_argument);
  EXPECT_THROW(r.renderOnto(grey, scene), std::invalid_argument);
}

}  // namespace
