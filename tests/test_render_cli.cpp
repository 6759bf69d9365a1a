// End-to-end: `kccd render` as scripts use it (files written, JSON summary, exit codes, errors).
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/render/camera.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;

using kccd::testing::Outcome;

Outcome runKccd(const std::string& args) { return kccd::testing::runProgram(std::string(KCCD_CLI) + " " + args); }

const std::string kData = KCCD_DATA_DIR;
const std::string kDemo = kData + "/demo_arm.yaml";

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("kccd_render_cli_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    // A small version of the sample camera keeps the runs short (the distortion map is per pixel).
    kccd::render::Camera c = kccd::render::loadCamera(kData + "/demo_camera.yaml");
    c.width = 320;
    c.height = 180;
    c.camera_matrix(0, 0) /= 4;
    c.camera_matrix(1, 1) /= 4;
    c.camera_matrix(0, 2) = (c.camera_matrix(0, 2) + 0.5) / 4 - 0.5;
    c.camera_matrix(1, 2) = (c.camera_matrix(1, 2) + 0.5) / 4 - 0.5;
    camera_ = (dir_ / "camera.yaml").string();
    kccd::render::saveCamera(c, camera_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string out(const std::string& name) const { return (dir_ / name).string(); }
  std::string base() const { return "render " + kDemo + " --camera " + camera_; }
  fs::path dir_;
  std::string camera_;
};

TEST_F(RenderCli, WritesRgbaAndMask) {
  const Outcome r = runKccd(base() + " --state 0.3,0.4,0.6 -o " + out("a.png") + " --labels");
  ASSERT_EQ(r.code, 0) << r.err;
  const cv::Mat rgba = cv::imread(out("a.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(rgba.type(), CV_8UC4);
  EXPECT_EQ(rgba.cols, 320);
  EXPECT_EQ(rgba.rows, 180);
  std::vector<cv::Mat> ch;
  cv::split(rgba, ch);
  EXPECT_GT(cv::countNonZero(ch[3]), 1000);
  EXPECT_LT(cv::countNonZero(ch[3]), 320 * 180);

  const Outcome m = runKccd(base() + " --state 0.3,0.4,0.6 -o " + out("m.png") + " --mask --json");
  ASSERT_EQ(m.code, 0) << m.err;
  const cv::Mat mask = cv::imread(out("m.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(mask.type(), CV_8UC1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(mask, &lo, &hi);
  EXPECT_EQ(lo, 0);
  EXPECT_LE(hi, 7);  // 7 bodies: labels 1..7
  const auto j = nlohmann::json::parse(m.out);
  EXPECT_EQ(j["kind"], "mask");
  EXPECT_EQ(j["volumes"], "static");
  EXPECT_EQ(j["status"], "ok");
  EXPECT_FALSE(j["renderer"].get<std::string>().empty());
  ASSERT_EQ(j["bodies"].size(), 7u);
  int total = 0;
  for (const auto& b : j["bodies"]) {
    const int label = b["label"];
    EXPECT_EQ(cv::countNonZero(mask == label), b["pixels"].get<int>()) << b["name"];
    total += b["pixels"].get<int>();
    EXPECT_TRUE(b["status"] == "clear" || b["status"] == "within_margin" || b["status"] == "colliding");
  }
  EXPECT_EQ(total, cv::countNonZero(mask));
}

TEST_F(RenderCli, SweptVolumesCoverTheStaticOnes) {
  ASSERT_EQ(runKccd(base() + " --state 0,0,0 -o " + out("s.png") + " --mask").code, 0);
  const Outcome r = runKccd(base() + " --lower -0.5,0,0 --upper 0.5,0,0 -o " + out("w.png") + " --mask --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["volumes"], "swept");
  const cv::Mat s = cv::imread(out("s.png"), cv::IMREAD_UNCHANGED), w = cv::imread(out("w.png"), cv::IMREAD_UNCHANGED);
  // Every pixel covered at the box's middle state is covered by the swept volumes.
  EXPECT_EQ(cv::countNonZero((s > 0) & (w == 0)), 0);
  EXPECT_GT(cv::countNonZero(w > 0), cv::countNonZero(s > 0));
}

TEST_F(RenderCli, BadInputExitsTwoWithOneLine) {
  const std::string o = " -o " + out("bad.png");
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"render " + kDemo + " --camera /nonexistent/cam.yaml --state 0,0,0" + o, "/nonexistent/cam.yaml"},
      {base() + " --state 0,0" + o, "--state has 2 values"},
      {base() + " --state 0,nan,0" + o, "not finite"},
      {base() + " --state 0,x,0" + o, "--state"},
      {base() + o, "--state"},
      {base() + " --state 0,0,0 --lower 0,0,0 --upper 0,0,0" + o, "not both"},
      {base() + " --state 0,0,0 -o " + out("nodir/x.png"), "does not exist"},
      {base() + " --state 0,0,0 -o " + out("x.jpg"), ".png"},
      {"render /nonexistent/model.yaml --camera " + camera_ + " --state 0,0,0" + o, "/nonexistent/model.yaml"},
  };
  for (const Case& c : cases) {
    const Outcome r = runKccd(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  // A camera file with a bad field names the file and the field.
  std::ofstream(out("bad_cam.yaml")) << "%YAML:1.0\n---\nimage_width: 320\nimage_height: 0\n";
  const Outcome r = runKccd("render " + kDemo + " --camera " + out("bad_cam.yaml") + " --state 0,0,0" + o);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("bad_cam.yaml: image_height"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out("bad.png")));
  // No partial or temporary files are left behind.
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(RenderCli, UnsafeStatusExitsThreeAndStillWrites) {
  // A joint with `sweep: exact` given an interval is an unsafe status (fail safe).
  const std::string model = out("exact.yaml");
  std::ofstream(model) << "kccd: 1\nname: exact\nsafety_margin: 0.01\njoints:\n"
                          "  - {name: j, parent: world, type: revolute, axis: [0, 0, 1], sweep: exact}\n"
                          "bodies:\n  - {name: base, frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
                          "  - {name: arm, frame: j, points: [[0.5, 0, 0.3]], radius: 0.05}\n";
  const Outcome r = runKccd("render " + model + " --camera " + camera_ + " --lower 0 --upper 0.1 -o " + out("u.png") + " --json");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("unsafe"), std::string::npos);
  EXPECT_TRUE(fs::exists(out("u.png")));
  EXPECT_EQ(runKccd("render " + model + " --camera " + camera_ + " --state 0.1 -o " + out("v.png")).code, 0);
}

}  // namespace
