// End-to-end: `kccd calib intrinsics` as scripts use it (images in, camera file out, JSON summary,
// exit codes, one-line errors, nothing written on failure).
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/intrinsics.hpp"
#include "support/files.hpp"
#include "support/run_program.hpp"
#include "support/tag_scene.hpp"

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
    // A PNG cut in the middle: libpng's own message, and nothing else on stderr.
    const std::string bytes = kccd::testing::readText(a);
    std::ofstream(path("cut.png"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    // A PNG whose header says it is wider than its data (IHDR's CRC made right): OpenCV's
    // decoder printed "libpng error: Not enough image data" before kccd's line.
    std::string wide = bytes;
    wide[19] = static_cast<char>(wide[19] + 1);
    const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(wide.data() + 12), 17);
    for (int k = 0; k < 4; ++k) wide[29 + k] = static_cast<char>((crc >> (24 - 8 * k)) & 0xff);
    std::ofstream(path("wide.png"), std::ios::binary) << wide;
  }
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--image " + a + " " + b + " " + small + kGrid, small + ": image: 160x120 differs from " + a},
      {"--image " + a + " " + path("missing.png") + kGrid,
       path("missing.png") + ": image: cannot open the image (no such file)"},
      {"--image " + a + " " + path("text.png") + kGrid, path("text.png") + ": image: not an image"},
      {"--image " + a + " " + path("cut.png") + kGrid, path("cut.png") + ": image: a damaged PNG ("},
      {"--image " + a + " " + path("wide.png") + kGrid, path("wide.png") + ": image: a damaged PNG ("},
      {"--image " + a + " " + dir_.string() + kGrid, dir_.string() + ": image: a folder, not an image"},
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
  const Outcome r =
      runKccd("calib intrinsics --image " + a + " " + b + " --image " + c + kGrid + " -o " + out + " --json");
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

// ---------------------------------------------------------------------------------------------
// Images of a grid board rendered through a known distorted camera (tests/support/tag_scene).

// 640 x 480, visible barrel distortion.
Camera trueCamera() {
  Camera c;
  c.width = 640;
  c.height = 480;
  c.camera_matrix = cv::Matx33d(560.0, 0.0, 324.5, 0.0, 556.0, 236.0, 0.0, 0.0, 1.0);
  c.distortion = {-0.24, 0.09, 0.0006, -0.0004, -0.02};
  return c;
}

// The camera's pose for a view of `board`: the board centre at `at` in the camera, facing it,
// tilted by `tilt_deg` about the in-plane axis at `axis_deg`, rolled by `roll_deg`.
Camera viewOf(const Board& board, double tilt_deg, double axis_deg, double roll_deg, cv::Vec3d at) {
  Camera c = trueCamera();
  const cv::Matx33d flip(1, 0, 0, 0, -1, 0, 0, 0, -1);
  cv::Matx33d roll, tilt;
  cv::Rodrigues(cv::Vec3d(0, 0, roll_deg * kPi / 180), roll);
  const double a = axis_deg * kPi / 180;
  cv::Rodrigues(cv::Vec3d(std::cos(a), std::sin(a), 0) * (tilt_deg * kPi / 180), tilt);
  const cv::Matx33d r = tilt * flip * roll;
  cv::Vec3d centre(0, 0, 0);
  for (const Tag& t : board.layout.tags) centre += cv::Vec3d(t.xyz.x(), t.xyz.y(), t.xyz.z());
  centre /= static_cast<double>(board.layout.tags.size());
  cv::Rodrigues(r, c.rvec);
  c.tvec = at - r * centre;
  return c;
}

TEST_F(IntrinsicsCli, RecoversTheCameraFromRenderedImagesOfAGridBoard) {
  const Board board = Board::grid(TagGrid{.cols = 6, .rows = 4, .tag_size = 0.04, .spacing = 0.012});
  kccd::testing::TagSceneOptions scene;
  scene.blur_sigma = 0.6;
  scene.noise_sigma = 2.0;
  // Eight views: tilted 25-40 deg about different axes, the board in the centre and towards the corners.
  const struct {
    double tilt, axis, roll, x, y, z;
  } poses[] = {{30, 0, 5, 0.0, 0.0, 0.42},     {35, 90, -8, 0.06, -0.04, 0.45}, {30, 45, 12, -0.08, 0.06, 0.46},
               {40, 135, -4, 0.09, 0.07, 0.5}, {25, 200, 6, -0.1, -0.06, 0.48}, {35, 270, -10, 0.0, 0.08, 0.44},
               {30, 315, 3, 0.1, -0.07, 0.5},  {38, 160, 15, -0.09, 0.02, 0.47}};
  std::string images;
  int n = 0;
  for (const auto& p : poses) {
    scene.seed = static_cast<std::uint64_t>(++n);
    const cv::Mat image =
        kccd::testing::renderTagScene(viewOf(board, p.tilt, p.axis, p.roll, {p.x, p.y, p.z}), board.layout, scene);
    const std::string name = path("view" + std::to_string(n) + ".png");
    ASSERT_TRUE(cv::imwrite(name, image));
    images += " " + name;
  }
  const std::string out = path("camera.yaml");
  const Outcome r = runKccd("calib intrinsics --image" + images + kGrid + " -o " + out + " --json");
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "solved");
  EXPECT_EQ(j["output"], out);
  EXPECT_EQ(j["views"].size(), 8u);
  EXPECT_EQ(j["used"].size(), 8u);
  EXPECT_TRUE(j["rejected"].empty());
  EXPECT_LT(j["rms_px"].get<double>(), 0.5);
  EXPECT_EQ(j["std_dev"]["distortion"].size(), 5u);
  for (const auto& v : j["views"]) {
    EXPECT_GE(v["tags"].get<int>(), 12) << v["image"];
    EXPECT_GT(v["tilt_deg"].get<double>(), 20.0) << v["image"];
  }

  const Camera c = loadCamera(out);
  const Camera t = trueCamera();
  const cv::Matx33d& k = c.camera_matrix;
  std::ostringstream summary;
  summary << "fx " << k(0, 0) << " (" << 100 * (k(0, 0) / 560.0 - 1) << " %), fy " << k(1, 1) << " ("
          << 100 * (k(1, 1) / 556.0 - 1) << " %), cx " << k(0, 2) - 324.5 << " px, cy " << k(1, 2) - 236.0 << " px, k1 "
          << c.distortion[0] - t.distortion[0] << ", rms " << j["rms_px"] << " px";
  std::printf("recovered from rendered images: %s\n", summary.str().c_str());
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_NEAR(k(0, 0), 560.0, 0.005 * 560.0) << summary.str();
  EXPECT_NEAR(k(1, 1), 556.0, 0.005 * 556.0) << summary.str();
  EXPECT_NEAR(k(0, 2), 324.5, 2.0) << summary.str();
  EXPECT_NEAR(k(1, 2), 236.0, 2.0) << summary.str();
  ASSERT_EQ(c.distortion.size(), 5u);
  EXPECT_NEAR(c.distortion[0], t.distortion[0], 0.02) << summary.str();
  EXPECT_EQ(c.rvec, cv::Vec3d(0, 0, 0));
  EXPECT_EQ(c.tvec, cv::Vec3d(0, 0, 0));
  ASSERT_TRUE(c.reprojection_rms_px.has_value());
  EXPECT_NEAR(*c.reprojection_rms_px, j["rms_px"].get<double>(), 1e-9);
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("avg_reprojection_error:"), std::string::npos) << text;
  EXPECT_NE(text.find("nr_of_frames: 8"), std::string::npos) << text;

  // The file is the --intrinsics of a pose solve: the first view's pose from its tags (the grid as a layout file).
  {
    std::ofstream layout(path("grid.yaml"));
    layout << "tags:\n";
    for (const Tag& t : board.layout.tags)
      layout << "  - {id: " << t.id << ", size: " << t.size << ", xyz: [" << t.xyz.x() << ", " << t.xyz.y()
             << ", 0], rpy: [0, 0, 0]}\n";
  }
  const Outcome pose = runKccd("calib --intrinsics " + out + " --image " + path("view1.png") + " --tags " +
                               path("grid.yaml") + " -o " + path("posed.yaml") + " -q");
  ASSERT_EQ(pose.code, 0) << pose.err;
  const Camera posed = loadCamera(path("posed.yaml"));
  const Camera truth1 =
      viewOf(board, poses[0].tilt, poses[0].axis, poses[0].roll, {poses[0].x, poses[0].y, poses[0].z});
  cv::Matx33d r_posed, r_truth;
  cv::Rodrigues(posed.rvec, r_posed);
  cv::Rodrigues(truth1.rvec, r_truth);
  const double angle =
      cv::norm(cv::Mat(r_posed.t() * r_truth) - cv::Mat(cv::Matx33d::eye()));  // ~ rotation angle (rad) * sqrt(2)
  EXPECT_LT(angle, 0.01) << posed.rvec << " vs " << truth1.rvec;
  EXPECT_LT(cv::norm(posed.tvec - truth1.tvec), 0.003) << posed.tvec << " vs " << truth1.tvec;

  // The same images with --fix-k3 and in text form: k3 stays 0, the summary names the file.
  const Outcome fixed = runKccd("calib intrinsics -q --fix-k3 --image" + images + kGrid + " -o " + path("fixed.yaml"));
  ASSERT_EQ(fixed.code, 0) << fixed.err;
  EXPECT_NE(fixed.out.find("wrote " + path("fixed.yaml")), std::string::npos) << fixed.out;
  EXPECT_EQ(loadCamera(path("fixed.yaml")).distortion[4], 0.0);

  // An image of another size among them: bad input, naming it; nothing written.
  cv::imwrite(path("other.png"), cv::Mat(240, 320, CV_8UC1, cv::Scalar(128)));
  const Outcome mixed =
      runKccd("calib intrinsics --image" + images + " " + path("other.png") + kGrid + " -o " + path("mixed.yaml"));
  EXPECT_EQ(mixed.code, 2);
  EXPECT_NE(mixed.err.find(path("other.png") + ": image: 320x240 differs"), std::string::npos) << mixed.err;
  EXPECT_FALSE(fs::exists(path("mixed.yaml")));

  // The board described with the wrong first id: no board tags, and the message says which ids were seen.
  const Outcome wrong = runKccd("calib intrinsics -q --image" + images + kGrid + " --first-id 100 -o " +
                                path("wrong.yaml"));  // -q: no progress line on a slow machine
  EXPECT_EQ(wrong.code, 4);
  EXPECT_NE(wrong.err.find("too few views"), std::string::npos) << wrong.err;
  EXPECT_NE(wrong.err.find("the images show tags 0, 1, 2"), std::string::npos) << wrong.err;
  EXPECT_NE(wrong.err.find("--first-id"), std::string::npos) << wrong.err;
  EXPECT_EQ(std::count(wrong.err.begin(), wrong.err.end(), '\n'), 1) << wrong.err;
  EXPECT_FALSE(fs::exists(path("wrong.yaml")));
}

TEST_F(IntrinsicsCli, FaceOnImagesAreNotSolvable) {
  const Board board = Board::grid(TagGrid{.cols = 6, .rows = 4, .tag_size = 0.04, .spacing = 0.012});
  std::string images;
  const double shifts[][2] = {{0, 0}, {0.05, 0.03}, {-0.05, -0.03}, {0.04, -0.04}};
  for (int i = 0; i < 4; ++i) {
    const cv::Mat image = kccd::testing::renderTagScene(
        viewOf(board, 2.0, 90.0 * i, 0, {shifts[i][0], shifts[i][1], 0.45}), board.layout);
    const std::string name = path("flat" + std::to_string(i) + ".png");
    ASSERT_TRUE(cv::imwrite(name, image));
    images += " " + name;
  }
  const Outcome r = runKccd("calib intrinsics --image" + images + kGrid + " -o " + path("camera.yaml"));
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_NE(r.err.find("kccd: intrinsics fronto-parallel: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tilt the board"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("camera.yaml")));
}

}  // namespace
