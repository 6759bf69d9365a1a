// The camera pose refined to robot masks (kccd::calib::refineToMasks) on synthetic frames whose
// true camera and masks are known: the masks are drawn by tests/support/silhouette.hpp, an
// independent rasteriser sharing no code with calib's silhouette. Starts 10 deg / 10 cm off, and
// masks damaged as segmentation leaves them. A mask eroded or dilated all round by 3 px reads as a
// thinner or thicker robot, which a pose can only answer with distance: those bounds are loose
// (measured 1.2 deg / 84 mm and 0.5 deg / 44 mm for links 20-40 px wide here).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/silhouette.hpp"
#include "kccd/model.hpp"
#include "support/cameras.hpp"
#include "support/sanitized.hpp"
#include "support/silhouette.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;
using kccd::testing::cameraCentre;
using kccd::testing::perturbed;
using kccd::testing::rotationErrorDeg;

const std::string kData = KCCD_DATA_DIR;
const std::vector<int> kRobot = {0, 3, 4, 5, 6};  // demo_arm: pedestal, shoulder, upper arm, forearm, gripper

// The true mask of the robot's bodies at `state`, by the independent rasteriser.
cv::Mat trueMask(const Model& model, const Camera& cam, const std::vector<double>& state) {
  cv::Mat mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  for (const PlacedVolume& v : placeVolumes(model, state, kRobot))
    mask |= kccd::testing::cpuSilhouette(cam, v.points, v.radius);
  return mask * 255;
}

struct Scene {
  Model model = loadModel(kData + "/demo_arm.yaml");
  Camera truth;
  std::vector<std::vector<double>> states;
  std::vector<cv::Mat> masks;
  Scene(int frames, std::uint64_t seed) {
    truth = kccd::testing::lookAt(Vec3(1.25, -0.95, 0.9), Vec3(0.2, 0.0, 0.35), 640, 360, 520.0,
                                  {-0.08, 0.03, 0.0005, -0.0003, 0.0});
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int f = 0; f < frames; ++f) {
      states.push_back({1.2 * u(rng), 0.6 * u(rng), 1.0 * u(rng)});
      masks.push_back(trueMask(model, truth, states.back()));
    }
  }
  std::vector<MaskFrame> frames(const std::vector<cv::Mat>& with) const {
    std::vector<MaskFrame> out;
    for (std::size_t f = 0; f < states.size(); ++f) out.push_back({with[f], placeVolumes(model, states[f], kRobot)});
    return out;
  }
};

TEST(MaskRefine, ConvergesFromTenDegreesAndTenCentimetres) {
  const Scene scene(6, 1);
  std::mt19937_64 rng(2);
  const int starts = kccd::testing::casesFor(6, 2);
  for (int s = 0; s < starts; ++s) {
    const Camera start = perturbed(scene.truth, 10.0, 0.10, rng);
    const RefineResult r = refineToMasks(start, scene.frames(scene.masks));
    ASSERT_TRUE(r.improved) << r.message;
    const double rot = rotationErrorDeg(r.camera.rvec, scene.truth.rvec);
    const double pos = cv::norm(cameraCentre(r.camera) - cameraCentre(scene.truth));
    EXPECT_LT(rot, 0.1) << r.message;
    EXPECT_LT(pos, 0.003) << r.message;
    for (const FrameAgreement& a : r.frames) EXPECT_GT(a.iou_after, 0.97);
    std::printf("start %d: %.3f deg, %.2f mm from the truth (sigma %.3f deg, %.2f mm), %d iterations\n", s, rot,
                pos * 1e3, *r.camera.rotation_sigma_deg, *r.camera.position_sigma_m * 1e3, r.iterations);
  }
}

TEST(MaskRefine, DamagedMasksStillConverge) {
  const Scene scene(6, 3);
  std::mt19937_64 rng(4);
  const cv::Mat k3 = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7));
  const struct {
    const char* name;
    std::function<cv::Mat(const cv::Mat&, std::size_t)> damage;
    double max_deg, max_m;
  } cases[] = {
      {"eroded 3 px",
       [&](const cv::Mat& m, std::size_t) {
         cv::Mat o;
         cv::erode(m, o, k3);
         return o;
       },
       2.0, 0.15},
      {"dilated 3 px",
       [&](const cv::Mat& m, std::size_t) {
         cv::Mat o;
         cv::dilate(m, o, k3);
         return o;
       },
       2.0, 0.15},
      {"holes",
       [&](const cv::Mat& m, std::size_t f) {
         cv::Mat o = m.clone();
         std::mt19937 r(static_cast<unsigned>(f));
         std::vector<cv::Point> in;
         cv::findNonZero(m, in);
         for (int k = 0; k < 8 && !in.empty(); ++k) cv::circle(o, in[r() % in.size()], 4, cv::Scalar(0), cv::FILLED);
         return o;
       },
       0.2, 0.005},
      {"a blob beside the robot",
       [&](const cv::Mat& m, std::size_t) {
         cv::Mat o = m.clone();
         cv::circle(o, cv::Point(40, 300), 25, cv::Scalar(255), cv::FILLED);
         return o;
       },
       0.2, 0.005},
      {"an occluding box",
       [&](const cv::Mat& m, std::size_t f) {
         cv::Mat o = m.clone();
         cv::Rect box;
         std::vector<cv::Point> in;
         cv::findNonZero(m, in);
         const cv::Rect bb = cv::boundingRect(in);
         box = cv::Rect(bb.x + bb.width / 3, bb.y + (f % 2 ? 0 : bb.height / 2), bb.width / 4, bb.height / 2);
         o(box & cv::Rect(0, 0, o.cols, o.rows)).setTo(0);
         return o;
       },
       0.5, 0.01},
  };
  for (const auto& c : cases) {
    std::vector<cv::Mat> damaged;
    for (std::size_t f = 0; f < scene.masks.size(); ++f) damaged.push_back(c.damage(scene.masks[f], f));
    const Camera start = perturbed(scene.truth, 10.0, 0.10, rng);
    const RefineResult r = refineToMasks(start, scene.frames(damaged));
    ASSERT_TRUE(r.improved) << c.name << ": " << r.message;
    const double rot = rotationErrorDeg(r.camera.rvec, scene.truth.rvec);
    const double pos = cv::norm(cameraCentre(r.camera) - cameraCentre(scene.truth));
    EXPECT_LT(rot, c.max_deg) << c.name;
    EXPECT_LT(pos, c.max_m) << c.name;
    std::printf("%s: %.3f deg, %.2f mm from the truth\n", c.name, rot, pos * 1e3);
  }
}

// The optimum checked by a second route: poses sampled around the refined one, each scored by
// the independent rasteriser's IoU with the true masks, do not beat it.
TEST(MaskRefine, NoNearbyPoseAgreesBetterByAnIndependentRasteriser) {
  const Scene scene(2, 5);
  std::mt19937_64 rng(6);
  const RefineResult r = refineToMasks(perturbed(scene.truth, 6.0, 0.05, rng), scene.frames(scene.masks));
  ASSERT_TRUE(r.improved) << r.message;
  auto score = [&](const Camera& c) {
    double iou = 0;
    for (std::size_t f = 0; f < scene.states.size(); ++f)
      iou += maskIou(trueMask(scene.model, c, scene.states[f]), scene.masks[f]);
    return iou / static_cast<double>(scene.states.size());
  };
  const double best = score(r.camera);
  const int samples = kccd::testing::casesFor(6, 2);
  for (int k = 0; k < samples; ++k) {
    const Camera near = perturbed(r.camera, 0.3, 0.005, rng);
    EXPECT_LE(score(near), best + 0.002) << "sample " << k;
  }
}

// Masks of other states than the frames' (a wrong clock): the start is kept, never a worse camera.
TEST(MaskRefine, MasksThatDisagreeKeepTheStart) {
  const Scene scene(4, 7), other(4, 8);
  const RefineResult r = refineToMasks(scene.truth, scene.frames(other.masks));
  EXPECT_FALSE(r.improved) << r.message;
  EXPECT_EQ(r.camera.rvec, scene.truth.rvec);
  EXPECT_EQ(r.camera.tvec, scene.truth.tvec);
  EXPECT_NE(r.message.find("the start is kept"), std::string::npos) << r.message;
}

TEST(MaskRefine, MaskFilesAreCheckedWithOneLine) {
  const std::string dir = ::testing::TempDir();
  cv::Mat good = cv::Mat::zeros(36, 64, CV_8UC1);
  good(cv::Rect(10, 10, 20, 10)).setTo(255);
  const auto write = [&](const std::string& name, const cv::Mat& m) {
    cv::imwrite(dir + "/" + name, m);
    return dir + "/" + name;
  };
  EXPECT_EQ(cv::countNonZero(readMask(write("m_good.png", good), 64, 36)), 200);
  cv::Mat colour;
  cv::cvtColor(good, colour, cv::COLOR_GRAY2BGR);
  colour.setTo(cv::Scalar(0, 0, 1), good);  // any non-zero channel is robot
  EXPECT_EQ(cv::countNonZero(readMask(write("m_colour.png", colour), 64, 36)), 200);
  const struct {
    std::string path, expect;
  } bad[] = {
      {write("m_size.png", cv::Mat::zeros(36, 63, CV_8UC1) + 1), "63x36, but the camera's images are 64x36"},
      {write("m_empty.png", cv::Mat::zeros(36, 64, CV_8UC1)), "no robot in it"},
      {write("m_full.png", cv::Mat::ones(36, 64, CV_8UC1)), "nothing but robot"},
      {dir + "/m_missing.png", "no such file"},
  };
  for (const auto& b : bad) {
    try {
      (void)readMask(b.path, 64, 36);
      ADD_FAILURE() << b.path;
    } catch (const MaskError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(b.path + ": mask: ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(b.expect), std::string::npos) << e.what();
    }
  }
}

}  // namespace
