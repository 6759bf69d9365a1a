// End-to-end: `kccd render` as scripts use it (files written, JSON summary, exit codes, errors).
#include <gtest/gtest.h>

#include <algorithm>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/render/projection.hpp"
#include "support/cameras.hpp"
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
    kccd::calib::Camera c = kccd::calib::loadCamera(kData + "/demo_camera.yaml");
    c = kccd::testing::quarterSized(c);
    camera_ = (dir_ / "camera.yaml").string();
    kccd::calib::saveCamera(c, camera_);
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

// Without EGL (glvnd finds no EGL vendor here) the command falls back to OSMesa and says so in one
// warning line naming EGL's failure; with EGL it says nothing. KCCD_GL=egl makes the same an error.
TEST_F(RenderCli, AFallBackToOsMesaIsSaid) {
  const std::string args = base() + " --state 0.3,0.4,0.6 -o ";
  const Outcome egl = runKccd(args + out("egl.png"));
  ASSERT_EQ(egl.code, 0) << egl.err;
  EXPECT_EQ(egl.err, "");
  const std::string no_egl = "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent ";
  const Outcome fallback = kccd::testing::runProgram(no_egl + KCCD_CLI + " " + args + out("osmesa.png"));
  ASSERT_EQ(fallback.code, 0) << fallback.err;
  EXPECT_NE(fallback.out.find("/ OSMesa"), std::string::npos) << fallback.out;
  EXPECT_EQ(fallback.err.rfind("kccd: warning: no EGL context (EGL: ", 0), 0u) << fallback.err;
  EXPECT_NE(fallback.err.find("rendered with OSMesa"), std::string::npos) << fallback.err;
  EXPECT_EQ(std::count(fallback.err.begin(), fallback.err.end(), '\n'), 1) << fallback.err;
  const Outcome pinned = kccd::testing::runProgram(no_egl + "KCCD_GL=egl " + KCCD_CLI + " " + args + out("pinned.png"));
  EXPECT_NE(pinned.code, 0);
  EXPECT_NE(pinned.err.find("EGL"), std::string::npos) << pinned.err;
  EXPECT_FALSE(fs::exists(out("pinned.png")));
}

// OSMesa (and the LLVM behind it) is loaded only by a program that renders with it: the loader's
// own record of the files it opened (LD_DEBUG=files) names libOSMesa under KCCD_GL=osmesa, never
// under EGL, and both draw the same volumes.
TEST_F(RenderCli, OsMesaIsLoadedOnlyWhenItRenders) {
  const std::string args = base() + " --state 0.3,0.4,0.6 -o ";
  auto opened = [](const std::string& err) { return err.find("file=libOSMesa.so") != std::string::npos; };
  const Outcome egl =
      kccd::testing::runProgram("LD_DEBUG=files KCCD_GL=egl " + std::string(KCCD_CLI) + " " + args + out("egl.png"));
  ASSERT_EQ(egl.code, 0) << egl.err;
  EXPECT_NE(egl.err.find("file=libEGL.so"), std::string::npos) << "no loader record in the output";
  EXPECT_FALSE(opened(egl.err));
  const Outcome osmesa = kccd::testing::runProgram("LD_DEBUG=files KCCD_GL=osmesa " + std::string(KCCD_CLI) + " " +
                                                   args + out("osmesa.png"));
  ASSERT_EQ(osmesa.code, 0) << osmesa.err;
  EXPECT_TRUE(opened(osmesa.err));
  EXPECT_NE(osmesa.out.find("/ OSMesa"), std::string::npos) << osmesa.out;
  const cv::Mat a = cv::imread(out("egl.png"), cv::IMREAD_UNCHANGED),
                b = cv::imread(out("osmesa.png"), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(cv::countNonZero(a.reshape(1) > 0), 0);
  // The two back ends are both llvmpipe here: the same pixels but for rounding along edges.
  EXPECT_LT(cv::countNonZero(a.reshape(1) != b.reshape(1)), a.total() / 100);
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
  EXPECT_NE(r.err.find("bad_cam.yaml:4:15: image_height: 0 is not in"), std::string::npos)
      << r.err;  // the value's place
  EXPECT_FALSE(fs::exists(out("bad.png")));
  // No partial or temporary files are left behind.
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST_F(RenderCli, CameraFileErrorsExitTwoWithOneLine) {
  const std::string o = " --state 0,0,0 -o " + out("bad.png");
  std::ifstream in(camera_);
  const std::string ok((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string dup = ok;
  dup.insert(dup.find("image_height"), "image_width: 640\n");
  std::string height = ok;
  height.replace(height.find("image_height: 180"), 17, "image_height: 20000");
  fs::create_directories(out("dir.yaml"));
  ASSERT_EQ(::mkfifo(out("fifo.yaml").c_str(), 0600), 0);
  const struct {
    std::string name, text, expect;
  } cases[] = {
      {"dup.yaml", dup, ":4:1: image_width: duplicate key"},
      {"trail.yaml", ok + "---\nimage_width: 640\n",
       ":" + std::to_string(std::count(ok.begin(), ok.end(), '\n') + 1) + ":1: document: a second YAML document"},
      {"empty.yaml", "", ": file: empty"},
      {"noheader.yaml", ok.substr(ok.find('\n') + 1), ":1: header"},
      {"list.yaml", "%YAML:1.0\n---\n- 1\n", ":3:1: document: the top level must be a mapping"},
      {"binary.yaml",
       std::string("\x7f"
                   "ELF\x02\x01\x01\0\0\0",
                   10),
       ":1: file: control byte"},
      {"truncated.yaml", ok.substr(0, ok.find("data:") + 12), ":"},
      {"height.yaml", height,
       ":" +
           std::to_string(std::count(height.begin(),
                                     height.begin() + static_cast<long>(height.find("image_height: 20000")), '\n') +
                          1) +
           ":15: image_height: 20000 is not in 1..8192"},
      {"dir.yaml", "", ": a folder, not a camera file"},
      {"fifo.yaml", "", ": not a regular file (a device, FIFO or socket)"},
  };
  for (const auto& c : cases) {
    if (c.name != "dir.yaml" && c.name != "fifo.yaml") std::ofstream(out(c.name), std::ios::binary) << c.text;
    const Outcome r = runKccd("render " + kDemo + " --camera " + out(c.name) + o);
    EXPECT_EQ(r.code, 2) << c.name << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("kccd: " + out(c.name) + c.expect, 0), 0u) << c.name << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.name << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(out("bad.png")));
}

TEST_F(RenderCli, VolumesThatCannotBeDrawnAreReported) {
  const std::string model = out("slide.yaml");
  std::ofstream(model) << "kccd: 1\nname: slide\nsafety_margin: 0.01\njoints:\n"
                          "  - {name: s, parent: world, type: prismatic, axis: [1, 0, 0]}\n"
                          "bodies:\n  - {name: base, frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
                          "  - {name: carriage, frame: s, points: [[0, 0, 0.5], [0.1, 0, 0.5]], radius: 0.05}\n"
                          "  - {name: room, frame: s, points: [[0, 0, 0]], radius: 50}\n";
  auto notDrawn = [](const nlohmann::json& j) {
    std::map<std::string, std::string> m;
    for (const auto& e : j["not_drawn"]) m[e["body"]] = e["reason"];
    return m;
  };
  // Far along the prismatic joint: behind the camera (static) or reaching beyond the far plane (swept).
  Outcome r = runKccd("render " + model + " --camera " + camera_ + " --state 1e100 -o " + out("a.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(notDrawn(j)["carriage"], "behind the camera");
  EXPECT_EQ(notDrawn(j)["room"], "behind the camera");
  r = runKccd("render " + model + " --camera " + camera_ + " --lower 100 --upper 1e100 -o " + out("b.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(notDrawn(j)["carriage"], "beyond far plane");
  // The text output says so too, and with --labels nothing overflows.
  r = runKccd("render " + model + " --camera " + camera_ + " --state 1e100 --labels -o " + out("c.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("carriage: clear, 0 px (not drawn: behind the camera)"), std::string::npos) << r.out;
  // At the origin the 50 m room contains the camera: it fills the view.
  r = runKccd("render " + model + " --camera " + camera_ + " --state 0 --mask -o " + out("d.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["fills_view"], nlohmann::json::array({"room"}));
  EXPECT_EQ(j["bodies"][2]["pixels"], 320 * 180);
  // Overflow to infinity: an unsafe status (3) with one line naming it, never exit 1.
  r = runKccd("render " + model + " --camera " + camera_ + " --state 1e308 -o " + out("e.png") + " --json");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("unsafe"), std::string::npos) << r.err;
  r = runKccd("render " + model + " --camera " + camera_ + " --lower 0 --upper 1e300 -o " + out("f.png"));
  EXPECT_EQ(r.code, 3) << r.err;
}

TEST_F(RenderCli, UnsafeStatusExitsThreeAndStillWrites) {
  // A joint with `sweep: exact` given an interval is an unsafe status (fail safe).
  const std::string model = out("exact.yaml");
  std::ofstream(model) << "kccd: 1\nname: exact\nsafety_margin: 0.01\njoints:\n"
                          "  - {name: j, parent: world, type: revolute, axis: [0, 0, 1], sweep: exact}\n"
                          "bodies:\n  - {name: base, frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
                          "  - {name: arm, frame: j, points: [[0.5, 0, 0.3]], radius: 0.05}\n";
  const Outcome r =
      runKccd("render " + model + " --camera " + camera_ + " --lower 0 --upper 0.1 -o " + out("u.png") + " --json");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("unsafe"), std::string::npos);
  EXPECT_TRUE(fs::exists(out("u.png")));
  EXPECT_EQ(runKccd("render " + model + " --camera " + camera_ + " --state 0.1 -o " + out("v.png")).code, 0);
}

}  // namespace
