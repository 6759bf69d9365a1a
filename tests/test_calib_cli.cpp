// End-to-end: `kccd calib` as an operator runs it (labels, body labels, several frames, the camera
// file, JSON, the check image, exit codes and one-line errors).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/model.hpp"
#include "support/cameras.hpp"
#include "support/files.hpp"
#include "support/golden.hpp"
#include "support/run_program.hpp"
#include "support/silhouette.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::testing::Outcome;
using kccd::testing::rotationErrorDeg;
const auto centre = [](const kccd::calib::Camera& c) { return kccd::testing::cameraCentre(c); };

const std::string kData = KCCD_DATA_DIR;
const std::string kDemo = kData + "/demo_arm.yaml";
const std::string kCamera = kData + "/demo_camera.yaml";

Outcome runKccd(const std::string& args) { return kccd::testing::runProgram(std::string(KCCD_CLI) + " " + args); }

// Uniform in [lo, hi) from the raw generator output: the same numbers with every standard library.
double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

cv::Point2d project(const kccd::calib::Camera& c, const cv::Point3d& p) {
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{p}, c.rvec, c.tvec, c.camera_matrix, c.distortion, out);
  return out[0];
}

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

class CalibCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("kccd_calib_cli_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    truth_ = kccd::calib::loadCamera(kCamera);
    model_ = kccd::loadModel(kDemo);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string out(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(out(name)) << text; }

  // `n` world points in the cell that the sample camera sees, with 0.5 px noise; the names listed
  // in `misclicks` are moved 40-90 px.
  std::string worldLabels(std::mt19937_64& rng, int n, const std::vector<int>& misclicks = {}) const {
    std::string t = "labels:\n";
    int made = 0;
    while (made < n) {
      const cv::Point3d p(uniform(rng, -0.6, 0.9), uniform(rng, -0.7, 0.7), uniform(rng, 0.0, 1.3));
      cv::Point2d px = project(truth_, p);
      if (px.x < 20 || px.y < 20 || px.x > truth_.width - 20 || px.y > truth_.height - 20) continue;
      px += cv::Point2d(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5));
      if (std::find(misclicks.begin(), misclicks.end(), made) != misclicks.end()) {
        const double a = uniform(rng, 0, 2 * M_PI), r = uniform(rng, 40, 90);
        px += cv::Point2d(r * std::cos(a), r * std::sin(a));
      }
      t += "  - {name: w" + std::to_string(made) + ", pixel: [" + fmt(px.x) + ", " + fmt(px.y) + "], world: [" +
           fmt(p.x) + ", " + fmt(p.y) + ", " + fmt(p.z) + "]}\n";
      ++made;
    }
    return t;
  }

  // Labels of every core point of the arm's bodies at `state` (0.3 px noise); the state written
  // into each label when `with_state`.
  std::string bodyLabels(std::mt19937_64& rng, const std::vector<double>& state, bool with_state,
                         const std::string& prefix) const {
    std::vector<kccd::Pose> poses(model_.joints.size());
    EXPECT_TRUE(kccd::framePoses(model_, state, poses));
    std::string st;
    for (double v : state) st += (st.empty() ? "" : ", ") + fmt(v);
    std::string t = "labels:\n";
    for (const kccd::Body& b : model_.bodies)
      for (std::size_t k = 0; k < b.points.size(); ++k) {
        const kccd::Vec3 w = kccd::framePose(poses, b.frame) * b.points[k];
        cv::Point2d px = project(truth_, {w.x(), w.y(), w.z()});
        px += cv::Point2d(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3));
        const kccd::Vec3& q = b.points[k];
        t += "  - {name: " + prefix + b.name + std::to_string(k) + ", pixel: [" + fmt(px.x) + ", " + fmt(px.y) +
             "], body: " + b.name + ", point: [" + fmt(q.x()) + ", " + fmt(q.y()) + ", " + fmt(q.z()) + "]" +
             (with_state ? ", state: [" + st + "]" : "") + "}\n";
      }
    return t;
  }

  // A bad invocation: the arguments after a base command line, and what its one error line says.
  struct ErrorCase {
    std::string args, expect;
  };
  // Each case exits 2 with one line saying its `expect`, and `output` is not written.
  void expectOneLineErrors(const std::string& base, const std::vector<ErrorCase>& cases,
                           const std::string& output) const {
    for (const ErrorCase& c : cases) {
      const Outcome r = runKccd(base + c.args);
      EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
      EXPECT_FALSE(fs::exists(output));
    }
  }

  fs::path dir_;
  kccd::calib::Camera truth_;
  kccd::Model model_;
};

TEST_F(CalibCli, LabelsSolveRejectMisclicksAndWriteTheCamera) {
  std::mt19937_64 rng(7);
  write("labels.yaml", worldLabels(rng, 14, {3, 9}));
  const Outcome r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("labels.yaml") + " --model " + kDemo +
                            " --state 0.3,0.4,0.6 -o " + out("cam.yaml") + " --check " + out("check.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "solved");
  EXPECT_EQ(j["rejected"], nlohmann::json::array({"w3", "w9"}));
  EXPECT_EQ(j["inliers"], 12);
  ASSERT_EQ(j["residuals"].size(), 14u);
  EXPECT_GT(j["residuals"][3]["px"].get<double>(), 30.0);
  EXPECT_FALSE(j["residuals"][3]["inlier"].get<bool>());
  EXPECT_LT(j["reprojection_rms_px"].get<double>(), 0.6);
  EXPECT_GT(j["volume_sigma_px"].get<double>(), 0.0);
  // The camera file: the sample camera's intrinsics, the true pose within its stated sigmas.
  const kccd::calib::Camera c = kccd::calib::loadCamera(out("cam.yaml"));
  EXPECT_EQ(c.width, truth_.width);
  EXPECT_EQ(c.camera_matrix, truth_.camera_matrix);
  ASSERT_TRUE(c.rotation_sigma_deg && c.position_sigma_m && c.reprojection_rms_px);
  EXPECT_DOUBLE_EQ(*c.rotation_sigma_deg, j["rotation_sigma_deg"].get<double>());
  EXPECT_LT(rotationErrorDeg(c.rvec, truth_.rvec), std::max(0.02, 4 * *c.rotation_sigma_deg));
  EXPECT_LT(cv::norm(centre(c) - centre(truth_)), std::max(0.002, 4 * *c.position_sigma_m));
  // --truth reports the same errors.
  const Outcome t = runKccd("calib --intrinsics " + kCamera + " --labels " + out("labels.yaml") + " --truth " +
                            kCamera + " -o " + out("cam2.yaml") + " --json");
  ASSERT_EQ(t.code, 0) << t.err;
  const nlohmann::json jt = nlohmann::json::parse(t.out);
  EXPECT_NEAR(jt["truth_error"]["rotation_deg"].get<double>(), rotationErrorDeg(c.rvec, truth_.rvec), 1e-9);
  EXPECT_NEAR(jt["truth_error"]["position_m"].get<double>(), cv::norm(centre(c) - centre(truth_)), 1e-9);
  // The check image: the frame size, and what it shows stays as reviewed.
  const cv::Mat check = cv::imread(out("check.png"), cv::IMREAD_COLOR);
  ASSERT_EQ(check.cols, truth_.width);
  EXPECT_TRUE(kccd::testing::compareGolden(check, "calib_check_labels", j["renderer"].get<std::string>()));
}

TEST_F(CalibCli, BodyLabelsPlacedByTheirStateOrByStateOption) {
  std::mt19937_64 rng(11);
  // State in the labels.
  write("own.yaml", bodyLabels(rng, {0.3, 0.4, 0.6}, true, ""));
  Outcome r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("own.yaml") + " --model " + kDemo + " -o " +
                      out("a.yaml") + " -q");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "");
  kccd::calib::Camera c = kccd::calib::loadCamera(out("a.yaml"));
  EXPECT_LT(rotationErrorDeg(c.rvec, truth_.rvec), 0.1);
  EXPECT_LT(cv::norm(centre(c) - centre(truth_)), 0.005);
  // State from --state; a wrong state moves the points and the solve does not agree.
  write("plain.yaml", bodyLabels(rng, {-0.4, 0.9, -0.5}, false, ""));
  r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("plain.yaml") + " --model " + kDemo +
              " --state=-0.4,0.9,-0.5 -o " + out("b.yaml"));
  ASSERT_EQ(r.code, 0) << r.err;
  c = kccd::calib::loadCamera(out("b.yaml"));
  EXPECT_LT(rotationErrorDeg(c.rvec, truth_.rvec), 0.1);
  // Without any state: one line naming the label's place.
  r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("plain.yaml") + " --model " + kDemo + " -o " +
              out("c.yaml"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(out("plain.yaml") + ":2:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("needs a state"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out("c.yaml")));
  // Without the model.
  r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("own.yaml") + " -o " + out("c.yaml"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("needs --model"), std::string::npos) << r.err;
}

TEST_F(CalibCli, SeveralFramesAddUp) {
  // Each frame alone sees the arm in one pose; together they span more of the view and depth.
  std::mt19937_64 rng(5);
  write("f1.yaml", bodyLabels(rng, {0.9, 0.2, 0.1}, false, ""));
  write("f2.yaml", bodyLabels(rng, {-0.9, 1.2, -1.0}, false, ""));
  write("f3.yaml", bodyLabels(rng, {0.0, -0.8, 1.4}, false, ""));
  auto sigma = [&](const std::string& args) {
    const Outcome r =
        runKccd("calib --intrinsics " + kCamera + " --model " + kDemo + " " + args + " --json -o " + out("x.yaml"));
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  };
  const nlohmann::json one = sigma("--labels " + out("f1.yaml") + " --state 0.9,0.2,0.1");
  const nlohmann::json all = sigma("--labels " + out("f1.yaml") + " --labels " + out("f2.yaml") + " --labels " +
                                   out("f3.yaml") + " --state 0.9,0.2,0.1 --state=-0.9,1.2,-1.0 --state 0.0,-0.8,1.4");
  ASSERT_TRUE(one.is_object() && all.is_object());
  EXPECT_LT(all["rotation_sigma_deg"].get<double>(), one["rotation_sigma_deg"].get<double>());
  EXPECT_LT(all["position_sigma_m"].get<double>(), one["position_sigma_m"].get<double>());
  ASSERT_EQ(all["frames"].size(), 3u);
  EXPECT_EQ(all["residuals"][0]["name"].get<std::string>().rfind("f1/", 0), 0u);
  EXPECT_EQ(all["residuals"].back()["name"].get<std::string>().rfind("f3/", 0), 0u);
  // A state count that matches neither one nor every frame.
  const Outcome r =
      runKccd("calib --intrinsics " + kCamera + " --model " + kDemo + " --labels " + out("f1.yaml") + " --labels " +
              out("f2.yaml") + " --labels " + out("f3.yaml") + " --state 0,0,0 --state 0,0,0 -o " + out("y.yaml"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--state: given 2 times for 3 frames"), std::string::npos) << r.err;
}

TEST_F(CalibCli, NotSolvableWritesNothingAndSaysWhatToAdd) {
  std::mt19937_64 rng(3);
  write("few.yaml", worldLabels(rng, 3));
  Outcome r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("few.yaml") + " -o " + out("cam.yaml") +
                      " --check " + out("check.png"));
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("kccd: calib: 3 points given, at least"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
  EXPECT_FALSE(fs::exists(out("cam.yaml")));
  EXPECT_FALSE(fs::exists(out("check.png")));
  // Half the points misclicked: too few agree.
  write("bad.yaml", worldLabels(rng, 8, {0, 2, 4, 6}));
  r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("bad.yaml") + " -o " + out("cam.yaml") + " --json");
  EXPECT_EQ(r.code, 4);
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "too few inliers");
  EXPECT_FALSE(j.contains("rotation_sigma_deg"));
  EXPECT_FALSE(fs::exists(out("cam.yaml")));
}

// --masks: the pose refined to robot masks, from four rough clicks (8 px off) on two frames. The
// masks are drawn by tests/support/silhouette.hpp, which shares no code with the refinement.
class CalibMasks : public CalibCli {
 protected:
  void SetUp() override {
    CalibCli::SetUp();
    cam_ = truth_;  // the sample camera at half size: 640 x 360
    cam_.width /= 2, cam_.height /= 2;
    cam_.camera_matrix(0, 0) /= 2, cam_.camera_matrix(1, 1) /= 2;
    cam_.camera_matrix(0, 2) = (cam_.camera_matrix(0, 2) + 0.5) / 2 - 0.5;
    cam_.camera_matrix(1, 2) = (cam_.camera_matrix(1, 2) + 0.5) / 2 - 0.5;
    kccd::calib::saveCamera(cam_, out("cam.yaml"));
    states_ = {{0.6, -0.3, 0.9}, {-0.5, 0.4, -0.7}};
    for (std::size_t f = 0; f < states_.size(); ++f)
      cv::imwrite(out("mask" + std::to_string(f) + ".png"), mask(states_[f]));
  }
  cv::Mat mask(const std::vector<double>& state, int scale = kccd::testing::kSilhouetteScale) const {
    std::vector<kccd::Pose> poses(model_.joints.size());
    EXPECT_TRUE(kccd::framePoses(model_, state, poses));
    cv::Mat m = cv::Mat::zeros(cam_.height, cam_.width, CV_8UC1);
    for (const int b : kRobot) {
      std::vector<kccd::Vec3> pts;
      for (const kccd::Vec3& p : model_.bodies[static_cast<std::size_t>(b)].points)
        pts.push_back(kccd::framePose(poses, model_.bodies[static_cast<std::size_t>(b)].frame) * p);
      m |= kccd::testing::cpuSilhouette(cam_, pts, model_.bodies[static_cast<std::size_t>(b)].radius, scale);
    }
    return m * 255;
  }
  // The arm's mask at `state` painted quickly: each body the convex hull of its balls' rims (the
  // circle where the rays from the camera touch each ball, 32 points) along its core at a sixth of
  // its radius, projected with the lens and filled at 4x (a pixel is in when half of it is).
  cv::Mat quickMask(const std::vector<double>& state) const {
    std::vector<kccd::Pose> poses(model_.joints.size());
    EXPECT_TRUE(kccd::framePoses(model_, state, poses));
    const kccd::Vec3 eye = [&] {
      const cv::Vec3d c = centre(cam_);
      return kccd::Vec3(c[0], c[1], c[2]);
    }();
    constexpr int kFine = 4;  // filled at 4x, then each pixel in when half of it is
    cv::Mat fine = cv::Mat::zeros(cam_.height * kFine, cam_.width * kFine, CV_8UC1);
    for (const int b : kRobot) {
      const kccd::Body& body = model_.bodies[static_cast<std::size_t>(b)];
      std::vector<kccd::Vec3> core;
      for (const kccd::Vec3& p : body.points) core.push_back(kccd::framePose(poses, body.frame) * p);
      std::vector<kccd::Vec3> centres = core;
      for (std::size_t i = 0; i < core.size(); ++i)
        for (std::size_t k = i + 1; k < core.size(); ++k) {
          const int n = static_cast<int>(std::ceil((core[k] - core[i]).norm() / (body.radius / 6)));
          for (int s = 1; s < n; ++s) centres.push_back(core[i] + (core[k] - core[i]) * (static_cast<double>(s) / n));
        }
      std::vector<cv::Point3d> rim;
      for (const kccd::Vec3& c : centres) {
        const kccd::Vec3 to_eye = eye - c;
        const double d = to_eye.norm(), r = body.radius;
        const kccd::Vec3 z = to_eye / d, x = z.unitOrthogonal(), y = z.cross(x);
        const kccd::Vec3 mid = c + z * (r * r / d);
        const double rho = r * std::sqrt(1.0 - r * r / (d * d));
        for (int a = 0; a < 32; ++a) {
          const double t = a * M_PI / 16;
          const kccd::Vec3 p = mid + rho * (std::cos(t) * x + std::sin(t) * y);
          rim.emplace_back(p.x(), p.y(), p.z());
        }
      }
      std::vector<cv::Point2d> px;
      cv::projectPoints(rim, cam_.rvec, cam_.tvec, cam_.camera_matrix, cam_.distortion, px);
      std::vector<cv::Point> fixed, hull;
      for (const cv::Point2d& p : px)
        fixed.emplace_back(static_cast<int>(std::lround((kFine * p.x + (kFine - 1) / 2.0) * 16)),
                           static_cast<int>(std::lround((kFine * p.y + (kFine - 1) / 2.0) * 16)));
      cv::convexHull(fixed, hull);
      cv::fillConvexPoly(fine, hull, cv::Scalar(255), cv::LINE_8, 4);
    }
    cv::Mat m;
    cv::resize(fine, m, m.size(), 1.0 / kFine, 1.0 / kFine, cv::INTER_AREA);
    m = m >= 128;
    return m;
  }
  // A fixed camera's recording (FFV1, rec.mkv) of the arm and its log (rec.csv): 48 frames at 8 fps,
  // the arm resting in one pose in every other frame and elsewhere in the others, on a background
  // of coloured boxes with noise; the log's clock runs kClock ahead of frame / fps.
  static constexpr double kFps = 8.0, kClock = 0.25;
  void writeRecording() const {
    std::mt19937_64 rng(12);
    cv::Mat scene(cam_.height, cam_.width, CV_8UC3, cv::Scalar(95, 105, 100));
    for (int k = 0; k < 30; ++k) {
      const cv::Point a(static_cast<int>(uniform(rng, 0, cam_.width)), static_cast<int>(uniform(rng, 0, cam_.height)));
      const cv::Scalar colour(uniform(rng, 20, 200), uniform(rng, 20, 200), uniform(rng, 20, 200));
      cv::rectangle(scene, a,
                    a + cv::Point(static_cast<int>(uniform(rng, 10, 70)), static_cast<int>(uniform(rng, 10, 50))),
                    colour, cv::FILLED);
    }
    const std::vector<double> rest = {0.3, -0.2, 0.6};
    std::string log = "time,shoulder_yaw,shoulder_pitch,elbow\n";
    cv::VideoWriter video(out("rec.mkv"), cv::VideoWriter::fourcc('F', 'F', 'V', '1'), kFps,
                          cv::Size(cam_.width, cam_.height));
    ASSERT_TRUE(video.isOpened());
    for (int f = 0; f < 48; ++f) {
      const std::vector<double> state =
          f % 2 == 0 ? rest
                     : std::vector<double>{uniform(rng, -1.2, 1.2), uniform(rng, -0.6, 0.6), uniform(rng, -1.0, 1.0)};
      log += fmt(f / kFps + kClock) + "," + fmt(state[0]) + "," + fmt(state[1]) + "," + fmt(state[2]) + "\n";
      cv::Mat picture = scene.clone();
      picture.setTo(cv::Scalar(215, 210, 205), quickMask(state));
      cv::Mat noise(picture.size(), CV_16SC3), wide;
      cv::RNG(static_cast<std::uint64_t>(f) + 1).fill(noise, cv::RNG::NORMAL, 0, 3);
      picture.convertTo(wide, CV_16SC3);
      cv::Mat(wide + noise).convertTo(picture, CV_8UC3);
      video.write(picture);
    }
    video.release();
    write("rec.csv", log);
  }
  // Two clicks on the arm in frame f, each 8 px off.
  std::string roughClicks(std::size_t f) const {
    std::vector<kccd::Pose> poses(model_.joints.size());
    EXPECT_TRUE(kccd::framePoses(model_, states_[f], poses));
    std::string t = "labels:\n";
    const std::pair<const char*, cv::Point2d> picks[] = {{f == 0 ? "forearm" : "upper_arm", {8, 0}},
                                                         {"gripper", {0, -8}}};
    for (const auto& [body, off] : picks) {
      const kccd::Body& b = model_.bodies[static_cast<std::size_t>(model_.bodyIndex(body))];
      const kccd::Vec3 w = kccd::framePose(poses, b.frame) * b.points[0];
      const cv::Point2d px = project(cam_, {w.x(), w.y(), w.z()}) + off;
      t += std::string("  - {name: ") + body + std::to_string(f) + ", pixel: [" + fmt(px.x) + ", " + fmt(px.y) +
           "], body: " + body + ", point: [" + fmt(b.points[0].x()) + ", " + fmt(b.points[0].y()) + ", " +
           fmt(b.points[0].z()) + "]}\n";
    }
    return t;
  }
  std::string frameArgs(bool labels) const {
    std::string a;
    for (std::size_t f = 0; f < states_.size(); ++f) {
      std::string st;
      for (double v : states_[f]) st += (st.empty() ? "" : ",") + fmt(v);
      a += (labels ? " --labels " + out("l" + std::to_string(f) + ".yaml") : std::string()) + " --state " + st +
           " --masks " + out("mask" + std::to_string(f) + ".png");
    }
    return a + " --model " + kDemo + " --mask-bodies pedestal,shoulder,upper_arm,forearm,gripper";
  }
  const std::vector<int> kRobot = {0, 3, 4, 5, 6};
  kccd::calib::Camera cam_;
  std::vector<std::vector<double>> states_;
};

TEST_F(CalibMasks, FourRoughClicksAndMasksGiveTheCamera) {
  for (std::size_t f = 0; f < states_.size(); ++f) write("l" + std::to_string(f) + ".yaml", roughClicks(f));
  const Outcome r = runKccd("calib --intrinsics " + out("cam.yaml") + frameArgs(true) + " -o " + out("c.yaml") +
                            " --json --check " + out("check.png"));
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["refinement"]["improved"].get<bool>()) << r.out;
  EXPECT_EQ(j["refinement"]["start"], "points");  // four clicks are too few for the gated solve
  for (const auto& fr : j["refinement"]["frames"]) EXPECT_GT(fr["iou_after"].get<double>(), 0.95) << r.out;
  const kccd::calib::Camera c = kccd::calib::loadCamera(out("c.yaml"));
  EXPECT_LT(rotationErrorDeg(c.rvec, cam_.rvec), 0.2);
  EXPECT_LT(cv::norm(centre(c) - centre(cam_)), 0.01);
  std::printf("4 clicks 8 px off + 2 masks: %.3f deg, %.2f mm from the truth\n", rotationErrorDeg(c.rvec, cam_.rvec),
              1e3 * cv::norm(centre(c) - centre(cam_)));
  // The check image draws both outlines (mask: yellow, drawn robot: magenta) on the frame.
  const cv::Mat check = cv::imread(out("check.png"));
  ASSERT_FALSE(check.empty());
  cv::Mat magenta, yellow;
  cv::inRange(check, cv::Scalar(200, 0, 200), cv::Scalar(255, 60, 255), magenta);
  cv::inRange(check, cv::Scalar(0, 170, 200), cv::Scalar(60, 255, 255), yellow);
  EXPECT_GT(cv::countNonZero(magenta), 100);
  EXPECT_GT(cv::countNonZero(yellow), 100);
}

TEST_F(CalibMasks, BadMasksAreOneLineExitTwoAndNothingWritten) {
  for (std::size_t f = 0; f < states_.size(); ++f) write("l" + std::to_string(f) + ".yaml", roughClicks(f));
  cv::imwrite(out("small.png"), cv::Mat(100, 200, CV_8UC1, cv::Scalar(255)));
  cv::imwrite(out("empty.png"), cv::Mat::zeros(cam_.height, cam_.width, CV_8UC1));
  cv::imwrite(out("full.png"), cv::Mat(cam_.height, cam_.width, CV_8UC1, cv::Scalar(7)));
  write("broken.png", "\x89PNG\r\n\x1a\nnot really");
  const std::string base = "calib --intrinsics " + out("cam.yaml") + " -o " + out("c.yaml");
  const std::string state = " --state 0,0,0";
  const std::vector<ErrorCase> cases = {
      {" --labels " + out("l0.yaml") + state + " --model " + kDemo + " --masks " + out("small.png"),
       "small.png: mask: 200x100, but the camera"},
      {" --labels " + out("l0.yaml") + state + " --model " + kDemo + " --masks " + out("empty.png"),
       "empty.png: mask: no robot in it"},
      {" --labels " + out("l0.yaml") + state + " --model " + kDemo + " --masks " + out("full.png"),
       "full.png: mask: nothing but robot"},
      {" --labels " + out("l0.yaml") + state + " --model " + kDemo + " --masks " + out("broken.png"),
       "broken.png: mask: "},
      {" --labels " + out("l0.yaml") + state + " --model " + kDemo + " --masks " + out("mask0.png") + " " +
           out("mask1.png"),
       "--masks: 2 mask(s) for 1 frame(s)"},
      {" --labels " + out("l0.yaml") + state + " --masks " + out("mask0.png"), "--masks: needs --model"},
      {" --labels " + out("l0.yaml") + state + " --model " + kDemo + " --masks " + out("mask0.png") +
           " --mask-bodies arm",
       "--mask-bodies: 'arm' is not a body"},
      {" --labels " + out("l0.yaml") + " --camera " + kCamera, "--camera: a start for --masks"},
  };
  expectOneLineErrors(base, cases, out("c.yaml"));
}

// --refine edges: no masks; the frames are pictures of the robot (each body painted by the
// independent rasteriser) on a background with boxes, from the same four rough clicks.
TEST_F(CalibMasks, FourRoughClicksAndThePicturesEdgesGiveTheCamera) {
  std::string args;
  for (std::size_t f = 0; f < states_.size(); ++f) {
    write("l" + std::to_string(f) + ".yaml", roughClicks(f));
    cv::Mat grey(cam_.height, cam_.width, CV_8UC1, cv::Scalar(90));
    cv::rectangle(grey, {40, 200}, {200, 330}, cv::Scalar(160), cv::FILLED);
    cv::rectangle(grey, {480, 40}, {600, 120}, cv::Scalar(30), cv::FILLED);
    grey.setTo(cv::Scalar(210), mask(states_[f]));
    cv::GaussianBlur(grey, grey, cv::Size(5, 5), 0.8);
    cv::Mat bgr;
    cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
    cv::imwrite(out("pic" + std::to_string(f) + ".png"), bgr);
    std::string st;
    for (double v : states_[f]) st += (st.empty() ? "" : ",") + fmt(v);
    args += " --image " + out("pic" + std::to_string(f) + ".png") + " --labels " +
            out("l" + std::to_string(f) + ".yaml") + " --state " + st;
  }
  const Outcome r = runKccd("calib --intrinsics " + out("cam.yaml") + args + " --model " + kDemo +
                            " --mask-bodies pedestal,shoulder,upper_arm,forearm,gripper --refine edges -o " +
                            out("c.yaml") + " --json --check " + out("check.png"));
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["refinement"]["improved"].get<bool>()) << r.out;
  EXPECT_EQ(j["refinement"]["source"], "edges");
  for (const auto& fr : j["refinement"]["frames"]) EXPECT_GT(fr["edge_share_after"].get<double>(), 0.8) << r.out;
  const kccd::calib::Camera c = kccd::calib::loadCamera(out("c.yaml"));
  EXPECT_LT(rotationErrorDeg(c.rvec, cam_.rvec), 0.2);
  EXPECT_LT(cv::norm(centre(c) - centre(cam_)), 0.01);
  std::printf("4 clicks 8 px off + the edges of 2 pictures: %.3f deg, %.2f mm from the truth\n",
              rotationErrorDeg(c.rvec, cam_.rvec), 1e3 * cv::norm(centre(c) - centre(cam_)));
  EXPECT_NE(kccd::testing::readText(out("c.yaml")).find("refinement: edges"), std::string::npos);
  // The check image draws the drawn robot's outline (magenta) on the frame.
  const cv::Mat check = cv::imread(out("check.png"));
  ASSERT_FALSE(check.empty());
  cv::Mat magenta;
  cv::inRange(check, cv::Scalar(200, 0, 200), cv::Scalar(255, 60, 255), magenta);
  EXPECT_GT(cv::countNonZero(magenta), 100);
}

// --masks auto: the fixture's recording (writeRecording) and a rough camera 6 degrees and 6 cm
// off, no clicks. The masks are made from the recording itself, its frames' times on the log's
// clock as the given frames' --time say.
TEST_F(CalibMasks, MasksFromTheRecordingItselfGiveTheCamera) {
  writeRecording();
  std::mt19937_64 turn(5);
  kccd::calib::saveCamera(kccd::testing::perturbed(cam_, 6.0, 0.06, turn), out("rough.yaml"));
  std::string frames;
  for (const int f : {3, 17, 31}) frames += " --frame " + std::to_string(f) + " --time " + fmt(f / kFps + kClock);
  const Outcome r = runKccd("calib --intrinsics " + out("cam.yaml") + " --video " + out("rec.mkv") + frames +
                            " --states " + out("rec.csv") + " --model " + kDemo + " --masks auto --camera " +
                            out("rough.yaml") + " -o " + out("c.yaml") + " --json --check " + out("check.png"));
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["refinement"]["improved"].get<bool>()) << r.out;
  EXPECT_NE(j["refinement"]["masks_from"].get<std::string>().find("background over 40 frames"), std::string::npos)
      << r.out;
  ASSERT_EQ(j["refinement"]["frames"].size(), 3u);
  double mean_iou = 0.0;
  for (const auto& fr : j["refinement"]["frames"]) {
    EXPECT_GT(fr["iou_after"].get<double>(), 0.85) << r.out;  // boxes of the robot's colour, its base unknown
    mean_iou += fr["iou_after"].get<double>() / 3;
  }
  EXPECT_GT(mean_iou, 0.9) << r.out;
  const kccd::calib::Camera c = kccd::calib::loadCamera(out("c.yaml"));
  const double deg = rotationErrorDeg(c.rvec, cam_.rvec), mm = 1e3 * cv::norm(centre(c) - centre(cam_));
  std::printf("masks from the recording, from 6 deg / 6 cm off: %.3f deg, %.2f mm from the truth\n", deg, mm);
  EXPECT_LT(deg, 0.15);  // measured 0.045 deg, 4.6 mm; the same frames' true masks give 0.044 deg, 4.6 mm
  EXPECT_LT(mm, 10.0);
  EXPECT_NE(kccd::testing::readText(out("c.yaml")).find("refinement_masks: \"masks from the recording"),
            std::string::npos);
  // The check image shows the mask made (yellow) and the drawn robot (magenta).
  cv::Mat yellow;
  cv::inRange(cv::imread(out("check.png")), cv::Scalar(0, 170, 200), cv::Scalar(60, 255, 255), yellow);
  EXPECT_GT(cv::countNonZero(yellow), 100);

  // What --masks auto needs, said in one line each.
  const std::string base = "calib --intrinsics " + out("cam.yaml") + " --model " + kDemo + " --camera " +
                           out("rough.yaml") + " -o " + out("d.yaml");
  const std::vector<ErrorCase> cases = {
      {" --image " + out("check.png") + " --state 0,0,0 --masks auto",
       "--masks auto: makes the masks from a recording"},
      {" --video " + out("rec.mkv") + " --frame 3 --state 0,0,0 --masks auto",
       "--masks auto: needs each frame's state"},
      {" --video " + out("rec.mkv") + " --frame 3 --states " + out("rec.csv") + " --masks auto " + out("mask0.png"),
       "give it alone"},
  };
  expectOneLineErrors(base, cases, out("d.yaml"));
}

// kccd overlay --masks auto: the same recording against its log at the true camera. At the log's
// true clock the frames agree; one frame late (the arm rests in every other frame) the mean falls;
// frames whose logged shoulder is off are named low.
TEST_F(CalibMasks, OverlayAgreementWithMasksFromTheRecording) {
  writeRecording();
  // The log with the shoulder 0.3 rad off in rows 20-29: those frames disagree with the video.
  std::string bad;
  {
    std::istringstream rows(kccd::testing::readText(out("rec.csv")));
    int row = -1;
    for (std::string line; std::getline(rows, line); ++row) {
      if (row >= 20 && row < 30) {
        const std::size_t a = line.find(','), b = line.find(',', a + 1);
        line = line.substr(0, a + 1) + fmt(std::stod(line.substr(a + 1, b - a - 1)) + 0.3) + line.substr(b);
      }
      bad += line + "\n";
    }
  }
  write("bad.csv", bad);
  const auto agreement = [&](const std::string& log, double offset) {
    const Outcome r =
        runKccd("overlay " + kDemo + " --camera " + out("cam.yaml") + " --video " + out("rec.mkv") + " --states " +
                out(log) + " --time-offset " + fmt(offset) + " --masks auto --report " + out("r.json") + " -q");
    EXPECT_EQ(r.code, 0) << r.err << r.out;
    return nlohmann::json::parse(kccd::testing::readText(out("r.json")))["mask_agreement"];
  };
  const nlohmann::json right = agreement("rec.csv", kClock), late = agreement("rec.csv", kClock + 1 / kFps),
                       offset = agreement("bad.csv", kClock);
  std::printf(
      "masks from the recording: IoU at the log's clock mean %.3f (smallest %.3f, %d low); a frame late %.3f; "
      "shoulder 0.3 rad off in 10 frames: %d low\n",
      right["mean_iou"].get<double>(), right["min_iou"].get<double>(), right["low_frames"].get<int>(),
      late["mean_iou"].get<double>(), offset["low_frames"].get<int>());
  EXPECT_GE(right["frames"].get<int>(), 40);
  EXPECT_GT(right["mean_iou"].get<double>(), 0.9);
  EXPECT_LE(right["low_frames"].get<int>(), 1) << right.dump();
  EXPECT_LT(late["mean_iou"].get<double>(), right["mean_iou"].get<double>() - 0.2);
  int named = 0;
  for (const auto& f : offset["lowest"]) named += f.get<int>() >= 20 && f.get<int>() < 30;
  EXPECT_GE(named, 7) << offset.dump();
}

TEST_F(CalibMasks, BadRefineOptionsAreOneLineExitTwo) {
  write("l0.yaml", roughClicks(0));
  const std::string base = "calib --intrinsics " + out("cam.yaml") + " -o " + out("c.yaml") + " --labels " +
                           out("l0.yaml") + " --state 0,0,0";
  const std::vector<ErrorCase> cases = {
      {" --model " + kDemo + " --refine edges --masks " + out("mask0.png"),
       "--refine edges: refines to the pictures themselves"},
      {" --refine edges", "--refine edges: needs --model"},
      {" --model " + kDemo + " --refine masks", "--refine masks: give the masks"},
      {" --model " + kDemo + " --refine lines", "--refine"},
      {" --model " + kDemo + " --refine edges", "frame 1 has no picture to find edges in"},
  };
  expectOneLineErrors(base, cases, out("c.yaml"));
}

// Masks of other states than the frames' from a rough camera alone: the masks cannot confirm any
// pose, so nothing is written and the exit is 4 with what to add.
TEST_F(CalibMasks, MasksThatCannotBeMatchedExitFourWithWhatToAdd) {
  cv::imwrite(out("wrong.png"), mask({-2.5, 1.5, 2.0}));
  kccd::calib::Camera far = cam_;
  far.tvec[0] += 0.6;  // a rough camera far off
  kccd::calib::saveCamera(far, out("rough.yaml"));
  cv::imwrite(out("frame.png"), cv::Mat(cam_.height, cam_.width, CV_8UC3, cv::Scalar(90, 90, 90)));
  const Outcome r = runKccd("calib --intrinsics " + out("cam.yaml") + " --image " + out("frame.png") + " --masks " +
                            out("wrong.png") + " --state 0.6,-0.3,0.9 --model " + kDemo + " --camera " +
                            out("rough.yaml") + " -o " + out("c.yaml"));
  EXPECT_EQ(r.code, 4) << r.err << r.out;
  EXPECT_NE(r.err.find("add labels of the robot or tags"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out("c.yaml")));
}

TEST_F(CalibCli, BadInputIsOneLineExitTwo) {
  std::mt19937_64 rng(9);
  write("l.yaml", worldLabels(rng, 8));
  const std::string l = " --labels " + out("l.yaml");
  struct Case {
    std::string args, expect;
  };
  cv::imwrite(out("small.png"), cv::Mat(100, 200, CV_8UC3, cv::Scalar(128, 128, 128)));
  write("not_image.png", "hello");
  // Cut images of the formats decoded by the suite itself and by OpenCV (whose decoders print
  // their own lines on stderr): one line of kccd's, naming the damage.
  std::vector<std::uint8_t> encoded;
  const cv::Mat picture(240, 320, CV_8UC3, cv::Scalar(40, 90, 200));
  for (const std::string ext : {".jpg", ".bmp", ".ppm", ".tif", ".webp"}) {
    cv::imencode(ext, picture, encoded);
    write("cut" + ext.substr(1) + ".png",
          std::string(encoded.begin(), encoded.begin() + static_cast<long>(encoded.size() / 2)));
  }
  const std::vector<Case> cases{
      {"--intrinsics " + kCamera + " --image " + out("cutjpg.png") + l + " -o " + out("c.yaml"),
       "image: a damaged JPEG (Premature end of JPEG file)"},
      {"--intrinsics " + kCamera + " --image " + out("cutbmp.png") + l + " -o " + out("c.yaml"),
       "image: a damaged image (Unexpected end of input stream)"},
      {"--intrinsics " + kCamera + " --image " + out("cutppm.png") + l + " -o " + out("c.yaml"),
       "image: a damaged image (Unexpected end of input stream)"},
      {"--intrinsics " + kCamera + " --image " + out("cuttif.png") + l + " -o " + out("c.yaml"),
       "image: not an image OpenCV can decode"},
      {"--intrinsics " + kCamera + " --image " + out("cutwebp.png") + l + " -o " + out("c.yaml"),
       "image: not an image OpenCV can decode"},
      {"--intrinsics " + kCamera + l, "-o CAMERA.yaml is required"},
      {l + " -o " + out("c.yaml"), "--intrinsics CAMERA.yaml is required"},
      {"--intrinsics " + kCamera + " -o " + out("c.yaml"), "give --image FRAME"},
      {"--intrinsics " + kCamera + l + " -o " + out("c.txt"), "must be a .yaml or .yml file"},
      {"--intrinsics " + kCamera + l + " -o " + out("nodir/c.yaml"), "does not exist"},
      {"--intrinsics " + kCamera + l + " -o " + out("c.yaml") + " --check " + out("c.jpg"), "must be a .png file"},
      {"--intrinsics " + out("missing.yaml") + l + " -o " + out("c.yaml"), out("missing.yaml")},
      {"--intrinsics " + kCamera + " --labels " + out("missing.yaml") + " -o " + out("c.yaml"), out("missing.yaml")},
      {"--intrinsics " + kCamera + " --image " + out("small.png") + l + " -o " + out("c.yaml"),
       "the image is 200x100 but the camera"},
      {"--intrinsics " + kCamera + " --image " + out("not_image.png") + l + " -o " + out("c.yaml"),
       "image: not an image OpenCV can decode"},
      {"--intrinsics " + kCamera + " --image " + out("small.png") + " -o " + out("c.yaml"),
       "give --tags LAYOUT, --labels LABELS and/or --masks MASK"},
      {"--intrinsics " + kCamera + l + " --tags " + kCamera + " -o " + out("c.yaml"), "--tags: needs --image"},
      {"--intrinsics " + kCamera + l + " --state 0,0,0 -o " + out("c.yaml"), "--state: needs --model"},
      {"--intrinsics " + kCamera + l + " --model " + kDemo + " --state 0,0 -o " + out("c.yaml"), "has 2 values"},
      {"--intrinsics " + kCamera + l + " --threshold nan -o " + out("c.yaml"), "--threshold"},
  };
  for (const Case& c : cases) {
    const Outcome r = runKccd("calib " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("kccd: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out("c.yaml")));
  }
}

}  // namespace

namespace {

TEST_F(CalibCli, SheetNumbersCandidatesAndWritesAFillableTemplate) {
  // A frame with a few strong corners (dark squares) where the arm stands.
  cv::Mat frame(truth_.height, truth_.width, CV_8UC3, cv::Scalar(200, 200, 200));
  const std::vector<cv::Point> squares{{200, 150}, {900, 500}, {400, 550}};
  for (const cv::Point& p : squares) cv::rectangle(frame, p, p + cv::Point(60, 60), cv::Scalar(20, 20, 20), cv::FILLED);
  cv::imwrite(out("frame.png"), frame);
  const Outcome r = runKccd("calib sheet --image " + out("frame.png") + " --model " + kDemo + " --camera " + kCamera +
                            " --state 0.3,0.4,0.6 -o " + out("sheet.png") + " --template " + out("labels.yaml"));
  ASSERT_EQ(r.code, 0) << r.err;
  const cv::Mat sheet = cv::imread(out("sheet.png"), cv::IMREAD_COLOR);
  ASSERT_EQ(sheet.size(), frame.size());
  EXPECT_GT(cv::norm(sheet, frame, cv::NORM_L1), 0.0);
  std::ifstream in(out("labels.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Every square's 4 corners are candidates, within a pixel of where they were drawn.
  // (a filled rectangle covers pixels p ... p + 60: its edges are at p - 0.5 and p + 60.5)
  int near = 0;
  for (const cv::Point& p : squares)
    for (const cv::Point2d& c : {cv::Point2d(p.x - 0.5, p.y - 0.5), cv::Point2d(p.x + 60.5, p.y - 0.5),
                                 cv::Point2d(p.x - 0.5, p.y + 60.5), cv::Point2d(p.x + 60.5, p.y + 60.5)})
      for (std::size_t at = text.find("pixel: ["); at != std::string::npos; at = text.find("pixel: [", at + 1)) {
        const double u = std::stod(text.substr(at + 8)), v = std::stod(text.substr(text.find(',', at) + 1));
        near += std::hypot(u - c.x, v - c.y) < 0.25;
      }
  EXPECT_GE(near, 12) << text;
  // The model's points: world points for fixed bodies, body points with the state for links,
  // where the camera projects them.
  EXPECT_NE(text.find("{name: table.0, pixel: [527.6"), std::string::npos) << text;
  EXPECT_NE(text.find("world: [0.45, -0.4, 0.1]"), std::string::npos) << text;
  EXPECT_NE(text.find("body: gripper, point: [0.34, -0.04, 0], state: [0.3, 0.4, 0.6]"), std::string::npos) << text;
  // Uncommented, the template with its placeholders filled in is a labels file kccd calib reads.
  std::string filled;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const bool model_point =
        line.find("name: table.") != std::string::npos || line.find("name: gripper.") != std::string::npos ||
        line.find("name: post.") != std::string::npos || line.find("name: pedestal.") != std::string::npos;
    if (model_point)
      filled += line.substr(1, line.find("  # projected") - 1) + "\n";
    else if (line.rfind("#", 0) != 0)
      filled += line + "\n";
  }
  write("filled.yaml", filled);
  const Outcome solve = runKccd("calib --intrinsics " + kCamera + " --labels " + out("filled.yaml") + " --model " +
                                kDemo + " -o " + out("cam.yaml") + " --json");
  ASSERT_EQ(solve.code, 0) << solve.err << filled;
  const kccd::calib::Camera c = kccd::calib::loadCamera(out("cam.yaml"));
  EXPECT_LT(rotationErrorDeg(c.rvec, truth_.rvec), 0.05);
  // Bad input.
  Outcome bad = runKccd("calib sheet --image " + out("frame.png") + " --model " + kDemo + " -o " + out("s.png"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--model: needs --camera"), std::string::npos) << bad.err;
  bad = runKccd("calib sheet --image " + out("frame.png") + " -o " + out("s.jpg"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_FALSE(fs::exists(out("s.png")));
}

// `calib sheet --video V --frame N`: the frame `calib --video V --frame N` reads. The sheet and
// template of frame 3 of a recording are those of the same picture given as --image (the template
// naming it V#3); frame 0, a different picture, gives a different sheet. Exactly one of --image
// and --video; bad combinations are one line, exit 2, nothing written.
TEST_F(CalibCli, SheetOfARecordingsFrame) {
  const std::vector<cv::Point> squares{{200, 150}, {900, 500}, {400, 550}};
  {
    cv::VideoWriter video(out("rec.mkv"), cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 10.0,
                          cv::Size(truth_.width, truth_.height));
    ASSERT_TRUE(video.isOpened());
    for (int f = 0; f < 5; ++f) {
      cv::Mat frame(truth_.height, truth_.width, CV_8UC3, cv::Scalar(200, 200, 200));
      for (const cv::Point& p : squares)
        cv::rectangle(frame, p + cv::Point(10 * f, 0), p + cv::Point(10 * f + 60, 60), cv::Scalar(20, 20, 20),
                      cv::FILLED);
      video.write(frame);
    }
  }
  // Frame 3 as OpenCV decodes it, as an image file.
  cv::VideoCapture cap(out("rec.mkv"));
  cv::Mat picture;
  for (int f = 0; f <= 3; ++f) ASSERT_TRUE(cap.read(picture)) << f;
  ASSERT_TRUE(cv::imwrite(out("frame3.png"), picture));
  const std::string tail = " --model " + kDemo + " --camera " + kCamera + " --state 0.3,0.4,0.6";
  const Outcome v = runKccd("calib sheet --video " + out("rec.mkv") + " --frame 3" + tail + " -o " + out("sv.png") +
                            " --template " + out("lv.yaml"));
  ASSERT_EQ(v.code, 0) << v.err;
  EXPECT_EQ(v.err, "");
  const Outcome i = runKccd("calib sheet --image " + out("frame3.png") + tail + " -o " + out("si.png") +
                            " --template " + out("li.yaml"));
  ASSERT_EQ(i.code, 0) << i.err;
  EXPECT_EQ(kccd::testing::readText(out("sv.png")), kccd::testing::readText(out("si.png")));
  const std::string lv = kccd::testing::readText(out("lv.yaml")), li = kccd::testing::readText(out("li.yaml"));
  EXPECT_EQ(lv.rfind("# Labels for " + out("rec.mkv") + "#3 (made by kccd calib sheet", 0), 0u) << lv;
  ASSERT_NE(lv.find('\n'), std::string::npos);
  EXPECT_EQ(lv.substr(lv.find('\n')), li.substr(li.find('\n')));  // the same candidates
  EXPECT_NE(lv.find("pixel: ["), std::string::npos) << lv;
  // The summary line counts what the image's does.
  const auto counts = [](const std::string& line) {
    return line.substr(line.find(':'), line.find(';') - line.find(':'));
  };
  EXPECT_EQ(counts(v.out), counts(i.out));
  EXPECT_NE(v.out.find("12 candidate points, 18 model points"), std::string::npos) << v.out;
  const Outcome first = runKccd("calib sheet --video " + out("rec.mkv") + " --frame 0 -o " + out("s0.png"));
  ASSERT_EQ(first.code, 0) << first.err;
  EXPECT_NE(kccd::testing::readText(out("s0.png")), kccd::testing::readText(out("sv.png")));
  // Bad combinations.
  const std::string video = " --video " + out("rec.mkv");
  const struct {
    std::string args, says;
  } cases[] = {
      {" --image " + out("frame3.png") + video + " --frame 3", "--image and --video: give one of them"},
      {"", "give the frame: --image FILE, or --video FILE with --frame N"},
      {video, "--video: say which frame with --frame N"},
      {" --image " + out("frame3.png") + " --frame 3", "--frame: goes with --video"},
      {video + " --frame 5", "--video " + out("rec.mkv") + ": frame 5: the recording has only 5 readable frames"},
      {video + " --frame -1", "--frame"},
      {" --video " + out("none.mkv") + " --frame 0", out("none.mkv")},
  };
  for (const auto& c : cases) {
    const Outcome r = runKccd("calib sheet" + c.args + " -o " + out("s.png") + " --template " + out("l.yaml"));
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("kccd: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out("s.png")));
    EXPECT_FALSE(fs::exists(out("l.yaml")));
  }
}

}  // namespace

namespace {

TEST_F(CalibCli, BodyLabelsPlacedByTheStateLogAtTheFrameTime) {
  // The arm moves linearly in joint space: at t = 1.25 s it is at (0.3, 0.4, 0.6), halfway between
  // the samples at 1.2 s and 1.3 s.
  std::string log = "time,shoulder_yaw,shoulder_pitch,elbow\n";
  for (int i = 0; i <= 30; ++i) {
    const double t = 0.1 * i, d = t - 1.25;
    log += fmt(t) + "," + fmt(0.3 + 0.2 * d) + "," + fmt(0.4 - 0.1 * d) + "," + fmt(0.6 + 0.3 * d) + "\n";
  }
  write("log.csv", log);
  std::mt19937_64 rng(21);
  write("labels.yaml", bodyLabels(rng, {0.3, 0.4, 0.6}, false, ""));
  const std::string base = "calib --intrinsics " + kCamera + " --labels " + out("labels.yaml") + " --model " + kDemo +
                           " --states " + out("log.csv") + " -o " + out("cam.yaml");
  Outcome r = runKccd(base + " --time 1.25");
  ASSERT_EQ(r.code, 0) << r.err;
  const kccd::calib::Camera c = kccd::calib::loadCamera(out("cam.yaml"));
  EXPECT_LT(rotationErrorDeg(c.rvec, truth_.rvec), 0.1);
  EXPECT_LT(cv::norm(centre(c) - centre(truth_)), 0.005);
  // The wrong time places the links elsewhere: the fixed bodies still agree, every gripper point
  // is rejected.
  r = runKccd(base + " --time 2.5 --json");
  const nlohmann::json wrong = nlohmann::json::parse(r.out);
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* name : {"gripper0", "gripper1", "gripper2", "gripper3"})
    EXPECT_NE(std::find(wrong["rejected"].begin(), wrong["rejected"].end(), name), wrong["rejected"].end())
        << name << r.out;
  // Outside the log, beyond --max-gap, a missing --time, a typo in a column: one line, exit 2.
  r = runKccd(base + " --time 7");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("has no sample within --max-gap"), std::string::npos) << r.err;
  r = runKccd(base);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--time"), std::string::npos) << r.err;
  write("typo.csv", "time,shoulder_yaw,shoulder_pitch,elbow,elbo\n0,0,0,0,0\n");
  r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("labels.yaml") + " --model " + kDemo + " --states " +
              out("typo.csv") + " --time 0 -o " + out("cam2.yaml"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(out("typo.csv") + ":1:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("elbo"), std::string::npos) << r.err;
  r = runKccd("calib --intrinsics " + kCamera + " --labels " + out("labels.yaml") + " --model " + kDemo + " --states " +
              out("typo.csv") + " --ignore-columns elbo --time 0 -o " + out("cam2.yaml"));
  EXPECT_NE(r.code, 2) << r.err;
}

}  // namespace

// A camera on the robot (--camera-frame): world labels seen from a camera fixed to the arm's
// shoulder at three states give the shoulder -> camera pose it was made with, and its camera file
// says frame: shoulder_pitch; `kccd render` then draws from the arm at each state.
TEST_F(CalibCli, ACameraOnTheRobotIsSolvedFromSeveralStates) {
  const int frame = model_.jointIndex("shoulder_pitch");
  std::vector<kccd::Pose> poses(model_.joints.size());
  ASSERT_TRUE(kccd::framePoses(model_, std::vector<double>(3, 0.0), poses));
  const kccd::Pose mount_to_camera = truth_.worldToCamera() * kccd::framePose(poses, frame);
  const std::vector<std::vector<double>> states = {{0.0, 0.0, 0.0}, {0.2, -0.1, 0.4}, {-0.25, 0.1, 0.8}};
  std::string labels_args, state_args;
  for (std::size_t f = 0; f < states.size(); ++f) {
    ASSERT_TRUE(kccd::framePoses(model_, states[f], poses));
    kccd::calib::Camera at = truth_;
    const kccd::Pose w2c = mount_to_camera * kccd::framePose(poses, frame).inverse();
    cv::Matx33d r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = w2c.linear()(i, j);
    cv::Rodrigues(r, at.rvec);
    at.tvec = cv::Vec3d(w2c.translation().x(), w2c.translation().y(), w2c.translation().z());
    std::ofstream labels(out("labels_" + std::to_string(f) + ".yaml"));
    labels << "labels:\n";
    for (int i = 0; i < 10; ++i) {  // corners of the table and the wall's marks
      const cv::Point3d w(0.2 + 0.15 * (i % 5), -0.3 + 0.6 * (i / 5), i % 2 == 0 ? 0.0 : 0.3);
      const cv::Point2d px = project(at, w);
      labels << "  - {name: p" << i << ", pixel: [" << fmt(px.x) << ", " << fmt(px.y) << "], world: [" << fmt(w.x)
             << ", " << fmt(w.y) << ", " << fmt(w.z) << "]}\n";
    }
    labels_args += " --labels " + out("labels_" + std::to_string(f) + ".yaml");
    state_args += " --state " + fmt(states[f][0]) + "," + fmt(states[f][1]) + "," + fmt(states[f][2]);
  }
  const Outcome r = runKccd("calib --intrinsics " + kCamera + " --model " + kDemo + " --camera-frame shoulder_pitch" +
                            labels_args + state_args + " -o " + out("wrist.yaml") + " -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const kccd::calib::Camera solved = kccd::calib::loadCamera(out("wrist.yaml"));
  EXPECT_EQ(solved.frame, "shoulder_pitch");
  const kccd::Pose got = solved.worldToCamera();
  EXPECT_LT((got.translation() - mount_to_camera.translation()).norm(), 1e-4);
  EXPECT_LT((got.linear() - mount_to_camera.linear()).norm(), 1e-4);
  // Without the states the camera cannot be placed: one line, nothing written.
  const Outcome stateless = runKccd("calib --intrinsics " + kCamera + " --model " + kDemo +
                                    " --camera-frame shoulder_pitch" + labels_args + " -o " + out("none.yaml"));
  EXPECT_EQ(stateless.code, 2);
  EXPECT_NE(stateless.err.find("has no state: a camera fixed to the robot"), std::string::npos) << stateless.err;
  EXPECT_FALSE(fs::exists(out("none.yaml")));
  const Outcome unknown = runKccd("calib --intrinsics " + kCamera + " --model " + kDemo + " --camera-frame wrist_cam" +
                                  labels_args + state_args + " -o " + out("none.yaml"));
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.err.find("--camera-frame: frame: 'wrist_cam' is neither a joint nor a body"), std::string::npos)
      << unknown.err;
  // The camera file draws from the arm: kccd render at the second state sees what the world camera did.
  const Outcome drawn =
      runKccd("render " + kDemo + " --camera " + out("wrist.yaml") + " --state 0.2,-0.1,0.4 -o " + out("wrist.png"));
  EXPECT_EQ(drawn.code, 0) << drawn.err;
}
