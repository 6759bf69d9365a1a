// Calibration on synthetic images: the tag scene renderer (support/tag_scene.hpp) against OpenCV's
// lens model and the detector's corners, then the whole pipeline detectTags -> tagCorrespondences
// -> solvePose on rendered frames of random cameras.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <apriltag/apriltag.h>
#include <apriltag/common/image_u8.h>
#include <apriltag/tag36h11.h>
#include <opencv2/calib3d.hpp>

#include "kccd/calib/pose.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "support/cameras.hpp"
#include "support/sanitized.hpp"
#include "support/tag_scene.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;
using kccd::testing::projectTagCorners;
using kccd::testing::renderTagScene;
using kccd::testing::rotationErrorDeg;
using kccd::testing::TagSceneOptions;

constexpr double kPi = 3.14159265358979323846;

// A camera at the world origin looking along +z (world = camera frame).
Camera frontCamera(int w, int h, double f, double cx, double cy, std::vector<double> dist = {0, 0, 0, 0, 0}) {
  Camera c;
  c.width = w;
  c.height = h;
  c.camera_matrix = cv::Matx33d(f, 0, cx, 0, f, cy, 0, 0, 1);
  c.distortion = std::move(dist);
  return c;
}

// A tag facing that camera at (x, y, z), turned by `turn` radians in its plane from upright (tag
// x along image x, tag y up the image).
Tag frontTag(int id, double size, double x, double y, double z, double turn = 0.0) {
  Tag t;
  t.id = id;
  t.size = size;
  t.xyz = Vec3(x, y, z);
  t.rpy = Vec3(kPi, 0, turn);
  return t;
}

// ---------------------------------------------------------------------------------------------
// The renderer

TEST(TagScene, LensModelMatchesOpenCV) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::vector<std::vector<double>> lenses = {
      {-0.2, 0.05, 0.001, -0.002},
      {-0.25, 0.08, 0.002, 0.001, -0.02},
      {0.1, -0.03, -0.001, 0.002, 0.01, 0.05, -0.01, 0.004},
      {-0.1, 0.02, 0.001, 0.001, 0.0, 0.01, 0.0, 0.0, 0.002, -0.001, 0.001, 0.0005},
      {-0.1, 0.02, 0.001, 0.001, 0.0, 0.01, 0.0, 0.0, 0.002, -0.001, 0.001, 0.0005, 0.02, -0.03},
  };
  for (const auto& d : lenses) {
    const Camera c = frontCamera(640, 480, 500, 321.3, 238.9, d);
    for (int i = 0; i < 50; ++i) {
      const cv::Point3d p(0.6 * u(rng), 0.45 * u(rng), 1.0);
      std::vector<cv::Point2d> ref;
      cv::projectPoints(std::vector<cv::Point3d>{p}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), c.camera_matrix,
                        c.distortion, ref);
      const cv::Point2d mine = kccd::testing::distortNormalised(c, cv::Point2d(p.x, p.y));
      EXPECT_LT(cv::norm(mine - ref[0]), 1e-9) << d.size() << " coefficients at " << p;
    }
  }
}

// Pixel centres are at integers: a black square edge on the boundary between two pixels leaves
// both pixels uniform.
TEST(TagScene, PixelCentresAtIntegers) {
  // f = 1000 px, tag 1 m away, size 0.16 m -> the black square is 160 px, a cell 20 px. Its left
  // edge at x = cx - 80: with cx = 319.5 the edge lies at 239.5, between pixels 239 and 240.
  const Camera c = frontCamera(640, 480, 1000, 319.5, 239.5);
  TagLayout layout;
  layout.tags.push_back(frontTag(0, 0.16, 0.0, 0.0, 1.0));
  TagSceneOptions o;
  o.white = 250;
  o.black = 10;
  o.background = 128;
  const cv::Mat img = renderTagScene(c, layout, o);
  ASSERT_EQ(img.type(), CV_8UC1);
  ASSERT_EQ(img.size(), cv::Size(640, 480));
  // Row 239 crosses the square's middle; the white border cell is pixels 220..239, the black
  // border 240..259; the bitmap's outer edge at 219.5 has the background left of it.
  EXPECT_EQ(img.at<uchar>(239, 219), 128);
  EXPECT_EQ(img.at<uchar>(239, 220), 250);
  EXPECT_EQ(img.at<uchar>(239, 239), 250);
  EXPECT_EQ(img.at<uchar>(239, 240), 10);
  EXPECT_EQ(img.at<uchar>(239, 259), 10);
  // Half a pixel to the right: the edge pixels are half covered.
  const Camera shifted = frontCamera(640, 480, 1000, 320.0, 239.5);
  const cv::Mat half = renderTagScene(shifted, layout, o);
  EXPECT_EQ(half.at<uchar>(239, 239), 250);
  EXPECT_EQ(half.at<uchar>(239, 240), 130);  // (250 + 10) / 2
  EXPECT_EQ(half.at<uchar>(239, 241), 10);
  EXPECT_EQ(half.at<uchar>(239, 220), 189);  // (128 + 250) / 2, rounded
}

// Through a strongly distorted lens, every cell centre of tilted tags, projected by
// cv::projectPoints, lands in a pixel of that cell's grey (the renderer inverts the lens itself).
TEST(TagScene, CellCentresLandWhereOpenCVProjectsThem) {
  const Camera c = frontCamera(960, 540, 700, 481.7, 268.2, {-0.25, 0.08, 0.001, -0.0015, -0.01});
  TagLayout layout;
  layout.tags.push_back(frontTag(7, 0.30, -0.55, -0.25, 1.3, 0.4));
  layout.tags.push_back(frontTag(77, 0.25, 0.55, 0.2, 1.2, -0.2));
  layout.tags.push_back(frontTag(377, 0.35, 0.0, 0.0, 1.6, 1.0));
  layout.tags[0].rpy = Vec3(kPi + 0.5, 0.3, 0.4);  // tilted 30 deg, turned
  layout.tags[1].rpy = Vec3(kPi - 0.4, -0.4, -0.2);
  TagSceneOptions o;
  o.white = 240;
  o.black = 20;
  o.background = 128;
  const cv::Mat img = renderTagScene(c, layout, o);
  apriltag_family_t* family = tag36h11_create();
  int checked = 0;
  for (const Tag& tag : layout.tags) {
    image_u8_t* bitmap = apriltag_to_image(family, static_cast<uint32_t>(tag.id));
    const double cell = tag.size / family->width_at_border;
    const Pose pose = tag.pose();
    for (int row = 0; row < bitmap->height; ++row)
      for (int col = 0; col < bitmap->width; ++col) {
        // Bitmap row 0 is the top of the printed tag (tag +y), column 0 its left (tag -x).
        const Vec3 p =
            pose * Vec3((col + 0.5 - 0.5 * bitmap->width) * cell, (0.5 * bitmap->height - row - 0.5) * cell, 0.0);
        std::vector<cv::Point2d> projected;
        cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, c.rvec, c.tvec, c.camera_matrix,
                          c.distortion, projected);
        const cv::Point2d q = projected[0];
        const int u = static_cast<int>(std::lround(q.x)), v = static_cast<int>(std::lround(q.y));
        ASSERT_TRUE(u >= 1 && v >= 1 && u < c.width - 1 && v < c.height - 1) << "tag " << tag.id << " out of view";
        const int expected = bitmap->buf[row * bitmap->stride + col] >= 128 ? 240 : 20;
        EXPECT_EQ(img.at<uchar>(v, u), expected) << "tag " << tag.id << " cell (" << row << ", " << col << ") at " << q;
        ++checked;
      }
    image_u8_destroy(bitmap);
  }
  tag36h11_destroy(family);
  EXPECT_EQ(checked, 300);
}

// Detected corners of fronto-parallel tags (random sub-pixel positions, turned in their plane)
// land on the projected layout corners: RMS within 0.1 px and no mean offset, so a half-pixel
// convention error fails. Not every corner within 0.1 px: AprilTag's edge refinement (3.3) takes
// the nearest pixel at quarter-pixel steps across the edge, which leaves single corners up to
// ~0.25 px off on turned tags and ~0.4 px on upright ones (along a pixel axis every sample of an
// edge has the same sub-pixel phase: RMS 0.15 px and a -0.06 px mean, against 0.05 px turned).
TEST(TagScene, DetectedCornersMatchProjection) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto turn = [&] { return (u(rng) < 0.5 ? -1.0 : 1.0) * (0.25 + 1.05 * u(rng)); };  // 14..75 deg
  double worst = 0, sum_x = 0, sum_y = 0, sum_sq = 0;
  int corners = 0;
  for (int frame = 0; frame < 8; ++frame) {
    const Camera c = frontCamera(800, 600, 900.0 + 100 * u(rng), 399.5 + u(rng), 299.5 + u(rng));
    TagLayout layout;
    layout.tags.push_back(
        frontTag(1 + frame, 0.10 + 0.06 * u(rng), -0.25 + 0.05 * u(rng), -0.15 + 0.05 * u(rng), 1.2, turn()));
    layout.tags.push_back(
        frontTag(100 + frame, 0.08 + 0.04 * u(rng), 0.2 + 0.05 * u(rng), 0.1 + 0.05 * u(rng), 1.0, turn()));
    layout.tags.push_back(frontTag(300 + frame, 0.15 + 0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng), 1.5, turn()));
    TagSceneOptions o;
    o.seed = static_cast<std::uint64_t>(frame + 1);
    o.blur_sigma = frame % 2 ? 0.8 : 0.0;
    o.noise_sigma = frame % 4 == 3 ? 2.0 : 0.0;
    const cv::Mat img = renderTagScene(c, layout, o);
    const std::vector<TagDetection> found = detectTags(img);
    ASSERT_EQ(found.size(), layout.tags.size()) << "frame " << frame;
    const auto truth = projectTagCorners(c, layout);
    for (const TagDetection& d : found) {
      std::size_t t = 0;
      while (t < layout.tags.size() && layout.tags[t].id != d.id) ++t;
      ASSERT_LT(t, layout.tags.size()) << "unexpected tag " << d.id;
      for (std::size_t k = 0; k < 4; ++k) {
        const cv::Point2d e = d.corners[k] - truth[t][k];
        worst = std::max(worst, cv::norm(e));
        sum_x += e.x, sum_y += e.y, sum_sq += e.dot(e), ++corners;
        EXPECT_LT(cv::norm(e), 0.3) << "frame " << frame << " tag " << d.id << " corner " << k << ": detected "
                                    << d.corners[k] << ", projected " << truth[t][k];
      }
    }
  }
  const double rms = std::sqrt(sum_sq / corners), offset = std::hypot(sum_x, sum_y) / corners;
  std::printf("fronto-parallel tags: %d corners, RMS error %.4f px, largest %.4f px, mean offset (%.4f, %.4f) px\n",
              corners, rms, worst, sum_x / corners, sum_y / corners);
  RecordProperty("fronto_parallel_corner_rms_px", std::to_string(rms));
  RecordProperty("fronto_parallel_worst_corner_px", std::to_string(worst));
  EXPECT_LT(rms, 0.1);
  EXPECT_LT(offset, 0.02);
}

TEST(TagScene, RejectsBadInput) {
  const Camera c = frontCamera(64, 48, 50, 32, 24);
  TagLayout layout;
  layout.tags.push_back(frontTag(587, 0.1, 0, 0, 1));
  EXPECT_THROW(renderTagScene(c, layout), std::invalid_argument);
  layout.tags[0].id = 5;
  TagSceneOptions o;
  o.supersample = 0;
  EXPECT_THROW(renderTagScene(c, layout, o), std::invalid_argument);
  Camera bad = c;
  bad.width = 0;
  EXPECT_THROW(renderTagScene(bad, layout), CameraError);
}

// ---------------------------------------------------------------------------------------------
// The pose of random cameras from rendered frames

cv::Vec3d cameraCentre(const Camera& c) {
  cv::Matx33d r;
  cv::Rodrigues(c.rvec, r);
  return -(r.t() * c.tvec);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}

// URDF rpy of a rotation matrix (R = Rz(yaw) Ry(pitch) Rx(roll)).
Vec3 rpyOf(const Eigen::Matrix3d& r) {
  const Vec3 ypr = r.eulerAngles(2, 1, 0);
  return Vec3(ypr[2], ypr[1], ypr[0]);
}

// 6-10 tags of 0.08-0.2 m on a floor (z = 0, facing up) and two walls (x = 0 facing +x, y = 0
// facing +y), turned in their plane, a third of them tilted 15-35 deg out of it on a wedge.
TagLayout randomLayout(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int count = 6 + static_cast<int>(u(rng) * 5);
  // Plane frames: tag z along the plane normal, tag y "up" within the plane.
  const Eigen::Matrix3d floor = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d wall_x, wall_y;
  wall_x.col(0) = Vec3(0, 1, 0), wall_x.col(1) = Vec3(0, 0, 1), wall_x.col(2) = Vec3(1, 0, 0);
  wall_y.col(0) = Vec3(-1, 0, 0), wall_y.col(1) = Vec3(0, 0, 1), wall_y.col(2) = Vec3(0, 1, 0);
  TagLayout layout;
  std::vector<std::pair<int, Vec3>> placed;  // plane, centre
  std::vector<double> sizes;
  for (int k = 0; k < count; ++k) {
    const int plane = k % 3;
    Tag t;
    t.id = static_cast<int>(u(rng) * 500) + k;  // distinct: k < 10 and ids spread
    for (const Tag& other : layout.tags)
      if (other.id == t.id) t.id += 37;
    t.size = 0.08 + 0.12 * u(rng);
    for (int attempt = 0;; ++attempt) {
      const double a = 0.22 + 0.76 * u(rng), b = 0.22 + 0.66 * u(rng);
      const Vec3 c = plane == 0 ? Vec3(a, 0.22 + 0.76 * u(rng), 0.0) : plane == 1 ? Vec3(0.0, a, b) : Vec3(a, 0.0, b);
      bool clear = true;
      for (std::size_t q = 0; q < placed.size(); ++q)
        if (placed[q].first == plane && (placed[q].second - c).norm() < 0.9 * (t.size + sizes[q]) + 0.03) clear = false;
      if (clear || attempt > 200) {
        t.xyz = c;
        break;
      }
    }
    const Eigen::Matrix3d base = plane == 0 ? floor : plane == 1 ? wall_x : wall_y;
    Eigen::Matrix3d r = base * Eigen::AngleAxisd(2 * kPi * u(rng), Vec3::UnitZ()).toRotationMatrix();
    if (u(rng) < 1.0 / 3.0) {
      // On a wedge: tilted about an in-plane axis, lifted off the plane by its half-size.
      const double tilt = (15.0 + 20.0 * u(rng)) * kPi / 180.0;
      r = r * Eigen::AngleAxisd(tilt, Vec3::UnitX()).toRotationMatrix();
      t.xyz += base.col(2) * (0.5 * t.size * std::sin(tilt) + 0.01);
    }
    t.rpy = rpyOf(r);
    layout.tags.push_back(t);
    placed.emplace_back(plane, t.xyz);
    sizes.push_back(t.size);
  }
  return layout;
}

struct RandomView {
  Camera camera;
  TagLayout layout;
};

// A random camera 1.5-4 m from the scene looking at it (every tag in view, facing the camera at
// less than 70 deg), fx 600-1400, mild distortion.
RandomView randomView(std::mt19937_64& rng, int width, int height) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RandomView v;
  v.layout = randomLayout(rng);
  for (;;) {
    Camera c;
    c.width = width;
    c.height = height;
    const double fx = 600.0 + 800.0 * u(rng), fy = fx * (1.0 + 0.01 * (u(rng) - 0.5));
    const double cx = (width - 1) / 2.0 + 0.03 * width * (u(rng) - 0.5),
                 cy = (height - 1) / 2.0 + 0.03 * height * (u(rng) - 0.5);
    c.camera_matrix = cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1);
    c.distortion = {-0.25 + 0.35 * u(rng), 0.1 * (u(rng) - 0.5), 0.002 * (u(rng) - 0.5), 0.002 * (u(rng) - 0.5),
                    0.02 * (u(rng) - 0.5)};
    const double azimuth = (25.0 + 40.0 * u(rng)) * kPi / 180.0, elevation = (20.0 + 35.0 * u(rng)) * kPi / 180.0;
    const double distance = 1.5 + 2.5 * u(rng);
    const Vec3 target(0.45 + 0.2 * (u(rng) - 0.5), 0.45 + 0.2 * (u(rng) - 0.5), 0.3 + 0.2 * (u(rng) - 0.5));
    const Vec3 eye = target + distance * Vec3(std::cos(elevation) * std::cos(azimuth),
                                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    c = kccd::testing::placedAt(c, eye, target, 0.35 * (u(rng) - 0.5));
    try {
      c.validate("random camera");
    } catch (const CameraError&) {
      continue;
    }
    bool ok = true;
    for (const Tag& tag : v.layout.tags) {
      const Pose p = tag.pose();
      const Vec3 to_eye = (eye - p.translation()).normalized();
      if (p.linear().col(2).dot(to_eye) < std::cos(70.0 * kPi / 180.0)) ok = false;
    }
    const auto corners = projectTagCorners(c, v.layout);
    for (std::size_t k = 0; k < corners.size() && ok; ++k)
      for (const cv::Point2d& q : corners[k])
        if (!(q.x > 20 && q.y > 20 && q.x < width - 21 && q.y < height - 21)) ok = false;
    if (!ok) continue;
    v.camera = c;
    return v;
  }
}

// The whole pipeline on frames of 100 random cameras (30 under the sanitizers): detectTags -> tagCorrespondences ->
// solvePose. Blur 0.5-1.0 px, noise 2 grey levels, background texture and clutter.
TEST(CalibImages, PoseOfRandomCamerasFromRenderedFrames) {
  constexpr int kCameras = kccd::testing::casesFor(100, 30);  // 30 under the sanitizers
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> rot, pos, rms, rot_ratio, pos_ratio;  // errors, and errors over the reported sigmas
  int honest_rot = 0, honest_pos = 0, solved = 0, tags_placed = 0, tags_found = 0;
  double render_s = 0, detect_s = 0, solve_s = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kCameras; ++i) {
    const RandomView view = randomView(rng, 1280, 720);
    TagSceneOptions o;
    o.blur_sigma = 0.5 + 0.5 * u(rng);
    o.noise_sigma = 2.0;
    o.texture = true;
    o.seed = static_cast<std::uint64_t>(1000 + i);
    const auto t0 = std::chrono::steady_clock::now();
    const cv::Mat frame = renderTagScene(view.camera, view.layout, o);
    const auto t1 = std::chrono::steady_clock::now();
    const std::vector<TagDetection> found = detectTags(frame);
    const auto t2 = std::chrono::steady_clock::now();
    render_s += std::chrono::duration<double>(t1 - t0).count();
    detect_s += std::chrono::duration<double>(t2 - t1).count();
    const TagCorrespondences corr = tagCorrespondences(found, view.layout, "camera " + std::to_string(i));
    EXPECT_TRUE(corr.unknown_ids.empty()) << "camera " << i << ": a tag that is not in the layout";
    tags_placed += static_cast<int>(view.layout.tags.size());
    tags_found += static_cast<int>(corr.points.size() / 4);
    Camera intrinsics = view.camera;
    intrinsics.rvec = cv::Vec3d(0, 0, 0);
    intrinsics.tvec = cv::Vec3d(0, 0, 0);
    const auto t3 = std::chrono::steady_clock::now();
    const PoseResult r = solvePose(intrinsics, corr.points);
    solve_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t3).count();
    if (r.status != PoseStatus::Solved) {
      ADD_FAILURE() << "camera " << i << " (" << found.size() << " of " << view.layout.tags.size()
                    << " tags found): " << r.message;
      continue;
    }
    ++solved;
    const double e_rot = rotationErrorDeg(r.camera.rvec, view.camera.rvec);
    const double e_pos = cv::norm(cameraCentre(r.camera) - cameraCentre(view.camera));
    rot.push_back(e_rot);
    pos.push_back(e_pos);
    rms.push_back(*r.camera.reprojection_rms_px);
    rot_ratio.push_back(e_rot / *r.camera.rotation_sigma_deg);
    pos_ratio.push_back(e_pos / *r.camera.position_sigma_m);
    honest_rot += e_rot <= 3.0 * *r.camera.rotation_sigma_deg;
    honest_pos += e_pos <= 3.0 * *r.camera.position_sigma_m;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rot50 = percentile(rot, 0.5), rot90 = percentile(rot, 0.9);
  const double pos50 = percentile(pos, 0.5), pos90 = percentile(pos, 0.9);
  const double honest_r = solved ? static_cast<double>(honest_rot) / solved : 0.0;
  const double honest_p = solved ? static_cast<double>(honest_pos) / solved : 0.0;
  std::printf(
      "%d cameras (1280x720), %d solved, %d of %d tags found: rotation error median %.4f deg, p90 %.4f deg; "
      "position error median %.3f mm, p90 %.3f mm; RMS median %.3f px; true error within 3 sigma: rotation %.0f%%, "
      "position %.0f%% (error / sigma median %.2f and %.2f, largest %.2f and %.2f); %.1f s (rendering %.1f s, "
      "detection %.1f s, solving %.1f s)\n",
      kCameras, solved, tags_found, tags_placed, rot50, rot90, 1000 * pos50, 1000 * pos90, percentile(rms, 0.5),
      100 * honest_r, 100 * honest_p, percentile(rot_ratio, 0.5), percentile(pos_ratio, 0.5),
      percentile(rot_ratio, 1.0), percentile(pos_ratio, 1.0), seconds, render_s, detect_s, solve_s);
  RecordProperty("cameras", kCameras);
  RecordProperty("solved", solved);
  RecordProperty("rotation_error_median_deg", std::to_string(rot50));
  RecordProperty("rotation_error_p90_deg", std::to_string(rot90));
  RecordProperty("position_error_median_mm", std::to_string(1000 * pos50));
  RecordProperty("position_error_p90_mm", std::to_string(1000 * pos90));
  RecordProperty("rotation_within_3_sigma", std::to_string(honest_r));
  RecordProperty("position_within_3_sigma", std::to_string(honest_p));
  EXPECT_EQ(solved, kCameras);
  if (!kccd::testing::kSanitized) {  // the medians' limits are for the full 100 cameras (Release run)
    EXPECT_LE(rot50, 0.02);
    EXPECT_LE(pos50, 0.001);
  }
  EXPECT_GE(honest_r, 0.9);
  EXPECT_GE(honest_p, 0.9);
}

}  // namespace
