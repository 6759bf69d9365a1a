// End-to-end: `kccd calib intrinsics` as scripts use it (images in, camera file out, JSON summary,
// exit codes, one-line errors, nothing written on failure).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/intrinsics.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;

using kccd::testing::Outcome;
using namespace kccd::calib;

Outcome runKccd(const std::string& args) { return kccd::testing::runProgram(std::string(KCCD_CLI) + " " + args); }

constexpr double kPi = 3.14159265358979323846;

class IntrinsicsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) / ("kccd_intrinsics_cli_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string blank(const std::string& name, int w, int h) const {
    cv::imwrite(path(name), cv::Mat(h, w, CV_8UC1, cv::Scalar(200)));
    return path(name);
  }
  fs::path dir_;
};

const std::string kGrid = " --grid 6x4 --tag-size 0.04 --spacing 0.012";

TEST_F(IntrinsicsCli, HelpExplainsTheBoardAndGoodViews) {
  const Outcome r = runKccd("calib intrinsics --help");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("--grid"), std::string::npos);
  EXPECT_NE(r.out.find("--board"), std::string::npos);
  EXPECT_NE(r.out.find("Good views"), std::string::npos);
  EXPECT_NE(r.out.find("tilted"), std::string::npos);
}

TEST_F(IntrinsicsCli, BadInputIsOneLineNamingTheFile) {
  const std::string a = blank("a.png", 320, 240), b = blank("b.png", 320, 240), small = blank("small.png", 160, 120);
  const std::string out = path("cam.yaml");
  {
    std::ofstream(path("text.png")) << "not an image\n";
  }
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--image " + a + " " + b + " " + small + kGrid, small + ": image: 160x120 differs from " + a},
      {"--image " + a + " " + path("missing.png") + kGrid, path("missing.png") + ": image: no such file"},
      {"--image " + a + " " + path("text.png") + kGrid, path("text.png") + ": image: not an image"},
      {"--image " + a + " " + dir_.string() + kGrid, dir_.string() + ": image: not a regular file"},
      {"--image " + a + " " + a + kGrid, a + ": image: given twice"},
      {"--image " + a + " --grid 6x4", "--grid needs --tag-size"},
      {"--image " + a + " --grid 6by4 --tag-size 0.04 --spacing 0.01", "--grid 6by4: expected COLSxROWS"},
      {"--image " + a + " --grid 1x1 --tag-size 0.04 --spacing 0.01", "at least 2 tags"},
      {"--image " + a + " --grid 30x30 --tag-size 0.04 --spacing 0.01", "beyond tag36h11"},
      {"--image " + a, "give the board"},
      {"--image " + a + " --board " + path("missing.yaml"), path("missing.yaml")},
      {"--image " + a + " --tag-size 0.04 --board x.yaml", "describe the board twice"},
  };
  for (const Case& c : cases) {
    const Outcome r = runKccd("calib intrinsics " + c.args + " -o " + out);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("kccd: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
  // A layout whose tags are not in one plane is refused, naming the file and the tag.
  {
    std::ofstream(path("bent.yaml")) << "tags:\n  - {id: 0, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n"
                                        "  - {id: 1, size: 0.1, xyz: [0.2, 0, 0.05], rpy: [0, 0, 0]}\n"
                                        "  - {id: 2, size: 0.1, xyz: [0.4, 0, 0], rpy: [0, 0, 0]}\n";
  }
  const Outcome bent = runKccd("calib intrinsics --image " + a + " --board " + path("bent.yaml") + " -o " + out);
  EXPECT_EQ(bent.code, 2) << bent.err;
  EXPECT_NE(bent.err.find(path("bent.yaml") + ": tags: tag "), std::string::npos) << bent.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(IntrinsicsCli, NoBoardInTheImagesIsNotSolvableAndWritesNothing) {
  const std::string a = blank("a.png", 320, 240), b = blank("b.png", 320, 240), c = blank("c.png", 320, 240);
  const std::string out = path("cam.yaml");
  const Outcome r = runKccd("calib intrinsics --image " + a + " " + b + " --image " + c + kGrid + " -o " + out + " --json");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_NE(r.err.find("too few views"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("add images"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out));
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "too few views");
  EXPECT_TRUE(j["output"].is_null());
  ASSERT_EQ(j["views"].size(), 3u);
  EXPECT_EQ(j["views"][0]["tags"], 0);
  EXPECT_EQ(j["rejected"].size(), 3u);
}

}  // namespace
