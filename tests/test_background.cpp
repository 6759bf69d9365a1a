// Robot masks from a fixed camera's recording (kccd::calib::estimateBackground, foregroundMask) on
// a painted recording whose background and robot are known: a textured scene, a "robot" (a bar and
// a ball) that rests in one place in most frames and moves about in the others, sensor noise.
#include <gtest/gtest.h>

#include <random>

#include <opencv2/imgproc.hpp>

#include "kccd/calib/background.hpp"
#include "kccd/calib/silhouette.hpp"

namespace {

using namespace kccd::calib;

constexpr int kW = 320, kH = 200;

struct Recording {
  cv::Mat scene;                          // the truth: the background
  std::vector<cv::Mat> pictures, robots;  // each frame and where its robot is
};

// The robot at place `t` (0: at rest): a thick bar from its base to a ball.
cv::Mat robotAt(double t) {
  cv::Mat m = cv::Mat::zeros(kH, kW, CV_8UC1);
  const cv::Point base(160, 190),
      tip(static_cast<int>(160 + 120 * std::sin(t)), static_cast<int>(190 - 150 * std::cos(t)));
  cv::line(m, base, tip, cv::Scalar(255), 14);
  cv::circle(m, tip, 16, cv::Scalar(255), cv::FILLED);
  return m;
}

Recording paint(int frames, double rest_share, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> shade(30, 180), x(0, kW - 1), y(0, kH - 1);
  Recording r;
  r.scene = cv::Mat(kH, kW, CV_8UC3, cv::Scalar(90, 110, 120));
  for (int k = 0; k < 40; ++k) {
    const cv::Point a(x(rng), y(rng));
    cv::rectangle(r.scene, a, a + cv::Point(8 + x(rng) / 8, 8 + y(rng) / 8),
                  cv::Scalar(shade(rng), shade(rng), shade(rng)), cv::FILLED);
  }
  std::uniform_real_distribution<double> place(-1.3, 1.3), unit(0.0, 1.0);
  for (int f = 0; f < frames; ++f) {
    const double t = unit(rng) < rest_share ? 0.0 : place(rng);
    cv::Mat img = r.scene.clone(), robot = robotAt(t);
    img.setTo(cv::Scalar(200, 200, 205), robot);
    cv::Mat noise(img.size(), CV_16SC3), wide;
    cv::RNG(seed * 100 + static_cast<std::uint64_t>(f)).fill(noise, cv::RNG::NORMAL, 0, 3);
    img.convertTo(wide, CV_16SC3);
    cv::Mat(wide + noise).convertTo(img, CV_8UC3);
    r.pictures.push_back(img);
    r.robots.push_back(robot);
  }
  return r;
}

cv::Mat widened(const cv::Mat& robot, int px) {
  cv::Mat out;
  cv::dilate(robot, out, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * px + 1, 2 * px + 1}));
  return out;
}

// Mean colour distance (sum over channels) to the true scene over the pixels of `where`.
double meanError(const cv::Mat& bgr, const cv::Mat& scene, const cv::Mat& where) {
  cv::Mat d;
  cv::absdiff(bgr, scene, d);
  cv::Mat sum;
  cv::transform(d, sum, cv::Matx13f(1, 1, 1));
  return cv::mean(sum, where)[0];
}

// A robot resting in one place in 60 % of the frames: a plain median holds it (a ghost), the
// estimate away from its drawing does not, and a frame's mask is the robot.
TEST(Background, ARestingRobotLeavesNoGhost) {
  const Recording r = paint(40, 0.6, 7);
  std::vector<BackgroundSample> away, plain;
  for (std::size_t f = 0; f < r.pictures.size(); ++f) {
    away.push_back({r.pictures[f], widened(r.robots[f], 6)});
    plain.push_back({r.pictures[f], cv::Mat::zeros(kH, kW, CV_8UC1)});
  }
  const Background bg = estimateBackground(away), ghosted = estimateBackground(plain);
  EXPECT_EQ(bg.samples, 40);
  const cv::Mat rest = robotAt(0.0);
  const cv::Mat rest_known = rest & bg.known;
  // The base never moves: unknown there; most of the resting place is seen in the other frames.
  EXPECT_EQ(bg.known.at<unsigned char>(185, 160), 0);
  EXPECT_GT(cv::countNonZero(rest_known), 0.7 * cv::countNonZero(rest));
  EXPECT_LT(meanError(bg.bgr, r.scene, rest_known), 12.0);
  EXPECT_GT(meanError(ghosted.bgr, r.scene, rest_known), 150.0);  // the plain median is the robot there
  EXPECT_LT(meanError(bg.bgr, r.scene, bg.known), 6.0);

  // A new frame, brighter (a camera's exposure), the robot elsewhere.
  const cv::Mat robot = robotAt(0.9);
  cv::Mat frame = r.scene * 1.2;
  frame.setTo(cv::Scalar(200, 200, 205), robot);
  const cv::Mat mask = foregroundMask({frame, widened(robot, 20)}, bg);
  const cv::Mat truth = robot & bg.known;
  EXPECT_GT(maskIou(mask, truth), 0.95);
  EXPECT_EQ(cv::countNonZero(mask & ~bg.known), 0);
  const cv::Mat plain_mask = foregroundMask({frame, widened(robot, 20)}, ghosted);
  EXPECT_LT(maskIou(plain_mask, robot), maskIou(mask, truth) - 0.1);  // the ghost is foreground too
}

// Without the gain, a brighter or darker frame would be all foreground; with it, nothing is (no
// robot in these frames; the scene's brightest shade stays below 255 at the highest gain).
TEST(Background, AGlobalGainIsNotForeground) {
  const Recording r = paint(20, 0.0, 3);
  std::vector<BackgroundSample> samples;
  for (std::size_t f = 0; f < r.pictures.size(); ++f) samples.push_back({r.pictures[f], widened(r.robots[f], 4)});
  const Background bg = estimateBackground(samples);
  for (const double gain : {0.75, 1.0, 1.25}) {
    cv::Mat frame = r.scene * gain;
    const cv::Mat mask = foregroundMask({frame, cv::Mat::zeros(kH, kW, CV_8UC1)}, bg);
    EXPECT_LT(cv::countNonZero(mask), 0.01 * kW * kH) << "gain " << gain;
  }
}

TEST(Background, FramesOfAnotherSizeAreRefused) {
  const Recording r = paint(4, 0.0, 1);
  EXPECT_THROW(estimateBackground({}), kccd::InputError);
  std::vector<BackgroundSample> samples = {{r.pictures[0], r.robots[0]},
                                           {r.pictures[1](cv::Rect(0, 0, 100, 100)).clone(), r.robots[1]}};
  EXPECT_THROW(estimateBackground(samples), kccd::InputError);
  samples[1] = {r.pictures[1], cv::Mat::zeros(10, 10, CV_8UC1)};
  EXPECT_THROW(estimateBackground(samples), kccd::InputError);
  samples.pop_back();
  const Background bg = estimateBackground(samples, 1);
  cv::Mat grey;
  cv::cvtColor(r.pictures[2], grey, cv::COLOR_BGR2GRAY);
  EXPECT_THROW(foregroundMask({grey, r.robots[2]}, bg), kccd::InputError);
}

}  // namespace
