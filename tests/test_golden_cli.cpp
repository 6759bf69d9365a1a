// `kccd golden` as an integrator's CI runs it, on a fixture manifest of 2 cameras x 3 states, one
// box and one recorded frame: update then run passes, a second update is byte-identical, reports
// and JUnit are written; each real change fails naming the case, the output and the likely cause
// (the camera's cx + 1 px, the thin post moved 1 px across and along, a body removed, the safety
// margin, a re-encoded video, a URDF edit re-imported); run never writes goldens; update --only
// failed touches only the failing case; approve gives the bytes update gives; a bad manifest is one
// line with its place; `supersample` draws finer masks, their edge bound in the sidecar.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "kccd/calib/camera.hpp"
#include "support/cameras.hpp"
#include "support/files.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::testing::Outcome;
const std::string kData = KCCD_DATA_DIR;
const std::string kCli = KCCD_CLI;

std::string readText(const fs::path& p) { return kccd::testing::readText(p.string()); }

void writeText(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

// Every file under `dir` with its bytes.
std::map<std::string, std::string> tree(const fs::path& dir) {
  std::map<std::string, std::string> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = readText(e.path());
  return out;
}

// Where two trees differ, readably: files only in one, and the differing files (a sidecar's JSON
// in full, an image by its size), so that a failure says which output and which field changed.
std::string treeDiff(const std::map<std::string, std::string>& got, const std::map<std::string, std::string>& want) {
  std::ostringstream out;
  for (const auto& [name, bytes] : want)
    if (!got.count(name)) out << "\n  missing: " << name;
  for (const auto& [name, bytes] : got) {
    const auto it = want.find(name);
    if (it == want.end()) {
      out << "\n  extra: " << name;
    } else if (it->second != bytes) {
      out << "\n  differs: " << name;
      if (name.ends_with(".json"))
        out << "\n    got:  " << bytes << "\n    want: " << it->second;
      else
        out << " (" << bytes.size() << " bytes, want " << it->second.size() << ")";
    }
  }
  return out.str();
}

// Whether the tree under `dir` is `want`, byte for byte; if not, where it differs.
::testing::AssertionResult sameTree(const fs::path& dir, const std::map<std::string, std::string>& want) {
  const auto got = tree(dir);
  if (got == want) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << dir.string() << " differs:" << treeDiff(got, want);
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

class GoldenCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_golden_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "rec");
    model_ = readText(kData + "/demo_arm.yaml");
    writeText(dir_ / "robot.yaml", model_);
    // Two small cameras looking at the arm and the post from the front and from the side.
    front_ = kccd::testing::lookAt({2.5, 0.0, 0.8}, {0.3, 0.0, 0.4}, 320, 240, 300, {-0.05, 0.01, 0, 0, 0});
    side_ = kccd::testing::lookAt({0.6, -2.4, 1.0}, {0.4, 0.0, 0.4}, 320, 240, 280, {});
    kccd::calib::saveCamera(front_, (dir_ / "front.yaml").string());
    kccd::calib::saveCamera(side_, (dir_ / "side.yaml").string());
    writeVideo(cv::VideoWriter::fourcc('F', 'F', 'V', '1'), "rec/rec.mkv");
    std::ostringstream log;
    log << "time,shoulder_yaw,shoulder_pitch,elbow\n";
    for (int i = 0; i <= 40; ++i) log << i * 0.025 << "," << 0.1 * i / 40.0 << ",0.4," << 0.6 + 0.2 * i / 40.0 << "\n";
    writeText(dir_ / "rec/rec.csv", log.str());
    writeText(dir_ / "golden.yaml", R"(kccd_golden: 1
goldens: goldens/
defaults: {model: robot.yaml, camera: front.yaml, outputs: [mask, colour]}
cases:
  - {id: home, state: [0, 0.5, 1.2]}
  - {id: reach, state: [0.3, 0.4, 0.6]}
  - {id: folded, state: [-0.4, -0.2, 2.0]}
  - {id: home-side, camera: side.yaml, state: [0, 0.5, 1.2]}
  - {id: reach-side, camera: side.yaml, state: [0.3, 0.4, 0.6]}
  - {id: folded-side, camera: side.yaml, state: [-0.4, -0.2, 2.0]}
  - id: reach-swept
    lower: [0.2, 0.35, 0.5]
    upper: [0.4, 0.45, 0.7]
  - id: rec-f5
    video: rec/rec.mkv
    frame: 5
    states: rec/rec.csv
    time_offset: 0.1
    outputs: [overlay, mask]
    compare: {overlay: {max_diff_px: 30}}
)");
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // A 10 fps recording of a grey room, 8 frames; below 100, each frame is passed through JPEG at
  // that quality first (a lossy transcode).
  void writeVideo(int fourcc, const std::string& name, int jpeg_quality = 100) {
    cv::VideoWriter w((dir_ / name).string(), fourcc, 10.0, cv::Size(320, 240));
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 8; ++i) {
      cv::Mat f(240, 320, CV_8UC3, cv::Scalar(70, 80, 90));
      cv::rectangle(f, cv::Rect(20 + 5 * i, 150, 60, 40), cv::Scalar(30, 120, 200), cv::FILLED);
      cv::GaussianBlur(f, f, cv::Size(5, 5), 1.5);
      if (jpeg_quality < 100) {
        std::vector<unsigned char> jpeg;
        cv::imencode(".jpg", f, jpeg, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
        f = cv::imdecode(jpeg, cv::IMREAD_COLOR);
      }
      w.write(f);
    }
  }

  Outcome golden(const std::string& args) { return kccd::testing::runProgram(kCli + " golden " + args); }
  std::string manifest() const { return (dir_ / "golden.yaml").string(); }
  std::string out() const { return (dir_ / "out").string(); }

  fs::path dir_;
  std::string model_;
  kccd::calib::Camera front_, side_;
};

TEST_F(GoldenCli, UpdateThenRunPassesAndASecondUpdateIsByteIdentical) {
  const Outcome up = golden("update " + manifest() + " -q");
  ASSERT_EQ(up.code, 0) << up.out << up.err;
  EXPECT_NE(up.out.find("8 of 8 case(s) written"), std::string::npos) << up.out;
  const auto goldens = tree(dir_ / "goldens");
  EXPECT_EQ(goldens.size(), 8u * 3) << "2 images and golden.json per case (rec-f5: overlay and mask)";
  ASSERT_TRUE(goldens.count("home/mask.png") && goldens.count("home/colour.png") &&
              goldens.count("rec-f5/overlay.png"));
  const nlohmann::json side = nlohmann::json::parse(goldens.at("rec-f5/golden.json"));
  EXPECT_EQ(side["outputs"]["mask"]["labels"]["4"], "shoulder");
  EXPECT_EQ(side["inputs"]["video"]["frame"], 5);
  EXPECT_EQ(side["inputs"]["video_frame"]["sha256"].get<std::string>().size(), 64u);
  EXPECT_FALSE(side["renderer"].get<std::string>().empty());

  const Outcome run = golden("run " + manifest() + " --out " + out() + " -q");
  EXPECT_EQ(run.code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("8 case(s): 8 passed, 0 failed, 0 missing"), std::string::npos) << run.out;
  const auto reports = tree(out());
  EXPECT_EQ(reports.size(), 4u) << "a passing run writes its reports and no images";
  for (const char* f : {"results.json", "junit.xml", "summary.md", "report.html"}) EXPECT_TRUE(reports.count(f)) << f;
  EXPECT_NE(reports.at("junit.xml").find("tests=\"16\" failures=\"0\""), std::string::npos) << reports.at("junit.xml");
  EXPECT_TRUE(sameTree(dir_ / "goldens", goldens)) << "run never writes goldens";

  ASSERT_EQ(golden("update " + manifest() + " --only all -q").code, 0);
  EXPECT_TRUE(sameTree(dir_ / "goldens", goldens)) << "the same pixels give the same bytes";
}

TEST_F(GoldenCli, RealChangesFailNamingCaseOutputAndCause) {
  ASSERT_EQ(golden("update " + manifest() + " -q").code, 0);
  const auto goldens = tree(dir_ / "goldens");

  // The camera's principal point moved by 1 px.
  kccd::calib::Camera moved = front_;
  moved.camera_matrix(0, 2) += 1.0;
  kccd::calib::saveCamera(moved, (dir_ / "front.yaml").string());
  Outcome o = golden("run " + manifest() + " --out " + out() + " -q");
  EXPECT_EQ(o.code, 1) << o.out << o.err;
  EXPECT_NE(o.out.find("home: mask failed: largest cluster of changed pixels"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("likely cause: the camera changed (front.yaml)"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("3 passed, 5 failed"), std::string::npos) << "the side camera's cases still pass: " << o.out;
  EXPECT_TRUE(sameTree(dir_ / "goldens", goldens)) << "run never writes goldens";
  EXPECT_TRUE(fs::exists(dir_ / "out/home/mask.diff.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out/home-side")) << "no images for passing cases";
  const nlohmann::json results = nlohmann::json::parse(readText(dir_ / "out/results.json"));
  EXPECT_EQ(results["cases"][0]["outputs"][0]["tolerance"]["from"], "built-in");
  kccd::calib::saveCamera(front_, (dir_ / "front.yaml").string());

  // The thin post (5 cm wide, 0.8 m tall, about 1.9 m from the front camera: 1 px is 6.3 mm there)
  // moved by one pixel across and, separately, along itself.
  const double px = 1.9 / 300.0;
  std::vector<nlohmann::json> true_changes;  // the metrics of the smallest true changes
  for (const auto& [from, to, what] :
       {std::tuple{std::string("[[0.6, 0, 0], [0.6, 0, 0.8]]"),
                   "[[0.6, " + std::to_string(px) + ", 0], [0.6, " + std::to_string(px) + ", 0.8]]", "across"},
        std::tuple{std::string("[[0.6, 0, 0], [0.6, 0, 0.8]]"),
                   "[[0.6, 0, " + std::to_string(1.2 * px) + "], [0.6, 0, " + std::to_string(0.8 + 1.2 * px) + "]]",
                   "along"}}) {
    writeText(dir_ / "robot.yaml", replaced(model_, from, to));
    o = golden("run " + manifest() + " --case home --out " + out() + " -q");
    EXPECT_EQ(o.code, 1) << what << ": " << o.out;
    EXPECT_NE(o.out.find("home: mask failed"), std::string::npos) << what << ": " << o.out;
    EXPECT_NE(o.out.find("likely cause: the model changed (robot.yaml)"), std::string::npos) << what << ": " << o.out;
    const nlohmann::json m =
        nlohmann::json::parse(readText(dir_ / "out/results.json"))["cases"][0]["outputs"][0]["metrics"];
    std::printf(
        "post moved 1 px %s: mask largest cluster %d px, worst centroid shift %.3f px, worst area change %.2f x "
        "allowed\n",
        what, m["largest_cluster_px"].get<int>(), m["worst_centroid_shift_px"].get<double>(),
        m["worst_area_change_ratio"].get<double>());
    true_changes.push_back(m);
  }
  // Each true change breaks a rule (cluster 4 px, centroid 0.25 px): by 2.75x along, 28x across
  // when measured; GoldensCrossTheGlBackEnds keeps the back ends' differences 3x inside the rules.
  for (const nlohmann::json& m : true_changes)
    EXPECT_TRUE(m["largest_cluster_px"].get<int>() > 4 || m["worst_centroid_shift_px"].get<double>() > 0.25)
        << m.dump();

  // A body removed: the set of bodies differs before any pixel is compared.
  writeText(dir_ / "robot.yaml",
            replaced(model_,
                     "  - name: post                  # a 5 cm pole standing 0.6 m in front of the robot\n"
                     "    frame: world\n    points: [[0.6, 0, 0], [0.6, 0, 0.8]]\n    radius: 0.025\n",
                     ""));
  o = golden("run " + manifest() + " --case home --out " + out() + " -q");
  EXPECT_EQ(o.code, 1);
  EXPECT_NE(o.out.find("home: mask failed: bodies: missing 'post'"), std::string::npos) << o.out;

  // The safety margin: the same volumes, other colours (the pole within the margin of the gripper).
  writeText(dir_ / "robot.yaml", replaced(model_, "safety_margin: 0.02", "safety_margin: 0.6"));
  o = golden("run " + manifest() + " --case reach --out " + out() + " -q");
  EXPECT_EQ(o.code, 1) << o.out;
  EXPECT_NE(o.out.find("colour failed"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("mask failed"), std::string::npos) << "the mask does not change: " << o.out;
  writeText(dir_ / "robot.yaml", model_);

  // The recording re-encoded through a lossy codec (every frame through JPEG at quality 5): the
  // frame's pixels changed, which is an input change, not a render failure.
  writeVideo(cv::VideoWriter::fourcc('F', 'F', 'V', '1'), "rec/rec.mkv", 5);
  o = golden("run " + manifest() + " --case rec-f5 --out " + out() + " -q");
  EXPECT_EQ(o.code, 1) << o.out;
  EXPECT_NE(o.out.find("likely cause: the video frame's pixels changed (rec/rec.mkv"), std::string::npos) << o.out;
}

TEST_F(GoldenCli, UpdateOnlyFailedAndApproveGiveTheBytesOfUpdate) {
  ASSERT_EQ(golden("update " + manifest() + " -q").code, 0);
  const auto before = tree(dir_ / "goldens");
  // Every later step on the back end the first one used: golden.json names the renderer, and a
  // step that fell back from EGL to OSMesa (EGL failing under load) would write another name, and
  // the trees would differ for that alone. Pinned, such a step fails saying why.
  const std::string renderer = nlohmann::json::parse(before.at("reach/golden.json")).at("renderer");
  const std::string gl = renderer.find("OSMesa") != std::string::npos ? "osmesa" : "egl";
  const auto golden = [&](const std::string& args) {
    return kccd::testing::runProgram("KCCD_GL=" + gl + " " + kCli + " golden " + args);
  };
  writeText(dir_ / "robot.yaml", replaced(model_, "radius: 0.045", "radius: 0.05"));  // the forearm, seen by every case
  // The failing run's actual images become the goldens...
  ASSERT_EQ(golden("run " + manifest() + " --case reach* --out " + out() + " -q").code, 1);
  const Outcome ap = golden("approve " + manifest() + " --from " + out() + " -q");
  ASSERT_EQ(ap.code, 0) << ap.out << ap.err;
  EXPECT_NE(ap.out.find("3 case(s)"), std::string::npos) << ap.out;
  const auto approved = tree(dir_ / "goldens");
  // ... exactly the bytes update writes.
  fs::remove_all(dir_ / "goldens");
  for (const auto& [name, bytes] : before) {
    fs::create_directories((dir_ / "goldens" / name).parent_path());
    writeText(dir_ / "goldens" / name, bytes);
  }
  const Outcome up = golden("update " + manifest() + " --case reach* --only failed -q");
  ASSERT_EQ(up.code, 0) << up.err;
  EXPECT_NE(up.out.find("3 of 3 case(s) written"), std::string::npos) << up.out;
  EXPECT_TRUE(sameTree(dir_ / "goldens", approved));
  for (const auto& [name, bytes] : before) {
    if (name.rfind("reach", 0) != 0) {
      EXPECT_EQ(approved.at(name), bytes) << name << ": not selected, untouched";
    }
  }
  // A tampered artifact is refused before anything is written.
  writeText(dir_ / "out/reach/mask.actual.png", "not the image");
  const Outcome bad = golden("approve " + manifest() + " --from " + out());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("its SHA-256 is not the one the run recorded"), std::string::npos) << bad.err;
  EXPECT_TRUE(sameTree(dir_ / "goldens", approved));
}

TEST_F(GoldenCli, MistakesAreOneLineWithThePlace) {
  struct Case {
    std::string manifest, expected;
  };
  const Case cases[] = {
      {"kccd_golden: 2\ncases: []\n", ":1:14: kccd_golden: expected 1"},
      {"kccd_golden: 1\ndefaults: {model: robot.yaml, camera: front.yaml}\ncases:\n  - {id: a, state: [0, 0, 0]}\n  - "
       "{id: a, state: [0, 0, 0]}\n",
       ":5:10: cases[1].id: 'a' is given twice"},
      {"kccd_golden: 1\ndefaults: {model: robot.yaml, camera: front.yaml}\ncases:\n  - {id: a, state: [0, 0]}\n",
       "case 'a'.state: 2 values, model 'demo_arm' has 3"},
      {"kccd_golden: 1\ndefaults: {model: robot.yaml, camera: front.yaml}\ncases:\n  - {id: a, state: [0, 0, 0], "
       "outputs: [mask, depth]}\n",
       ":4:47: case 'a'.outputs[1]: expected mask, colour or overlay, got 'depth'"},
      {"kccd_golden: 1\ndefaults: {model: robot.yaml, camera: front.yaml}\ncases:\n  - {id: a, state: [0, 0, 0], "
       "outputs: [overlay]}\n",
       "case 'a'.outputs: overlay needs a recorded frame"},
      {"kccd_golden: 1\ndefaults: {model: nothing.yaml, camera: front.yaml}\ncases:\n  - {id: a, state: [0, 0, 0]}\n",
       "nothing.yaml"},
      {"kccd_golden: 1\ndefaults: {model: robot.yaml, camera: front.yaml}\ncases:\n  - {id: ../x, state: [0, 0, 0]}\n",
       "is not a folder name"},
      {"kccd_golden: 1\ndefaults: {model: robot.yaml, camera: front.yaml, supersample: 5}\ncases:\n  - {id: a, state: "
       "[0, 0, 0]}\n",
       ":2:64: defaults.supersample: must be in 1..4"},
  };
  for (const Case& c : cases) {
    writeText(dir_ / "bad.yaml", c.manifest);
    const Outcome o = golden("run " + (dir_ / "bad.yaml").string() + " --out " + out());
    EXPECT_EQ(o.code, 2) << c.manifest << o.err;
    EXPECT_NE(o.err.find(c.expected), std::string::npos) << c.manifest << "\n" << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_FALSE(fs::exists(out())) << "nothing rendered, nothing written";
  }
  EXPECT_EQ(golden("run " + manifest() + " --case nothing*").code, 2);
  EXPECT_EQ(golden("update " + manifest() + " --only some").code, 2);
}

// The integrator's own flow for a URDF robot: the model imported from the URDF, goldens made; the
// same URDF imported again is no change (the import is deterministic and masks are matched by body
// name); a 5 mm change of one link's collision cylinder, re-imported, fails naming the model.
TEST_F(GoldenCli, AUrdfEditReimportedFails) {
  const fs::path urdf = dir_ / "urdf";
  fs::copy(fs::path(KCCD_TEST_DATA_DIR) / "urdf", urdf, fs::copy_options::recursive);
  const std::string original = readText(urdf / "two_link.urdf");
  auto import = [&] {
    const Outcome o = kccd::testing::runProgram(
        kCli + " import " + (urdf / "two_link.urdf").string() + " --srdf " + (urdf / "two_link.srdf").string() +
        " --package-path kccd_test=" + urdf.string() + " -k 4 -q -o " + (dir_ / "cell.yaml").string());
    ASSERT_EQ(o.code, 0) << o.err;
  };
  import();
  kccd::calib::saveCamera(
      kccd::testing::lookAt({1.4, -1.1, 0.7}, {0.05, 0.0, 0.3}, 320, 240, 320, {-0.06, 0.01, 0, 0, 0}),
      (dir_ / "cell_cam.yaml").string());
  writeText(dir_ / "cell_golden.yaml", R"(kccd_golden: 1
goldens: cell_goldens/
defaults: {model: cell.yaml, camera: cell_cam.yaml, outputs: [mask, colour]}
cases:
  - {id: home, state: [0, 0.05, 0]}
  - {id: turned, state: [0.8, 0.12, 1.0]}
)");
  const std::string m = (dir_ / "cell_golden.yaml").string();
  ASSERT_EQ(golden("update " + m + " -q").code, 0);
  const auto goldens = tree(dir_ / "cell_goldens");
  import();
  Outcome o = golden("run " + m + " --out " + out() + " -q");
  EXPECT_EQ(o.code, 0) << "the same URDF imported again: " << o.out;

  writeText(urdf / "two_link.urdf", replaced(original, R"(<cylinder radius="0.05" length="0.5"/>)",
                                             R"(<cylinder radius="0.055" length="0.5"/>)"));
  import();
  o = golden("run " + m + " --out " + out() + " -q");
  EXPECT_EQ(o.code, 1) << o.out;
  EXPECT_NE(o.out.find("home: mask failed"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("turned: mask failed"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("likely cause: the model changed (cell.yaml)"), std::string::npos) << o.out;
  EXPECT_TRUE(sameTree(dir_ / "cell_goldens", goldens));
}

// `supersample` draws the case's images finer: the sidecar records it and the mask's edge bound
// (render::Frame::mask_edge_px), which at 3 is under half a pixel where at 1 it is about one; the
// two masks differ only along the edges.
TEST_F(GoldenCli, SupersampleDrawsFinerMasks) {
  writeText(dir_ / "fine.yaml", R"(kccd_golden: 1
defaults: {model: robot.yaml, camera: front.yaml, outputs: [mask]}
cases:
  - {id: plain, state: [0.3, 0.4, 0.6]}
  - {id: fine, state: [0.3, 0.4, 0.6], supersample: 3}
)");
  const std::string m = (dir_ / "fine.yaml").string();
  ASSERT_EQ(golden("update " + m + " -q").code, 0);
  EXPECT_EQ(golden("run " + m + " --out " + out() + " -q").code, 0);
  const nlohmann::json plain = nlohmann::json::parse(readText(dir_ / "goldens/plain/golden.json"));
  const nlohmann::json fine = nlohmann::json::parse(readText(dir_ / "goldens/fine/golden.json"));
  EXPECT_EQ(plain["options"]["supersample"], 1.0);
  EXPECT_EQ(fine["options"]["supersample"], 3.0);
  const double edge_plain = plain["outputs"]["mask"]["edge_px"], edge_fine = fine["outputs"]["mask"]["edge_px"];
  std::printf("mask edge bound: %.3f px at supersample 1, %.3f px at 3\n", edge_plain, edge_fine);
  EXPECT_GT(edge_plain, 0.7);  // the front camera distorts: the nearest pinhole sample alone is up to 0.71 px
  EXPECT_LE(edge_fine, 0.5);
  const cv::Mat a = cv::imread((dir_ / "goldens/plain/mask.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat b = cv::imread((dir_ / "goldens/fine/mask.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(a.size(), cv::Size(320, 240));
  ASSERT_EQ(b.size(), a.size());
  cv::Mat edges;  // pixels next to a label change in the finer mask
  cv::Mat grown, shrunk;
  cv::dilate(b, grown, cv::Mat::ones(3, 3, CV_8U));
  cv::erode(b, shrunk, cv::Mat::ones(3, 3, CV_8U));
  edges = grown != shrunk;
  const int differing = cv::countNonZero(a != b);
  EXPECT_GT(differing, 0);
  EXPECT_EQ(cv::countNonZero((a != b) & ~edges), 0) << "the masks differ only along edges";
}

TEST_F(GoldenCli, ListShowsMissingAndUnusedGoldens) {
  ASSERT_EQ(golden("update " + manifest() + " --case home -q").code, 0);
  fs::create_directories(dir_ / "goldens/retired-case");
  const Outcome o = golden("list " + manifest());
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_NE(o.out.find("home\tstate\tmask,colour\tgoldens present"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("rec-f5\tframe\toverlay,mask\tmissing: overlay,mask"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("unused golden: "), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("8 case(s), 7 with missing goldens, 1 unused golden folder(s)"), std::string::npos) << o.out;
  const Outcome run = golden("run " + manifest() + " --out " + out() + " -q");
  EXPECT_EQ(run.code, 1) << "missing goldens fail the run";
  EXPECT_NE(run.out.find("1 passed, 0 failed, 7 missing"), std::string::npos) << run.out;
}

}  // namespace

namespace {

// Goldens made with one GL back end pass under the other (software OSMesa and EGL): the differences
// between back ends, measured, stay at least 3 times below every rule's limit.
TEST_F(GoldenCli, GoldensCrossTheGlBackEnds) {
  for (const auto& [make, check] : {std::pair{"osmesa", "egl"}, std::pair{"egl", "osmesa"}}) {
    fs::remove_all(dir_ / "goldens");
    const Outcome up =
        kccd::testing::runProgram("KCCD_GL=" + std::string(make) + " " + kCli + " golden update " + manifest() + " -q");
    ASSERT_EQ(up.code, 0) << make << ": " << up.err;
    const Outcome run = kccd::testing::runProgram("KCCD_GL=" + std::string(check) + " " + kCli + " golden run " +
                                                  manifest() + " --out " + out() + " -q");
    EXPECT_EQ(run.code, 0) << make << " goldens under " << check << ": " << run.out;
    const nlohmann::json results = nlohmann::json::parse(readText(dir_ / "out/results.json"));
    for (const nlohmann::json& c : results["cases"])
      for (const nlohmann::json& o : c["outputs"]) {
        const nlohmann::json& m = o["metrics"];
        std::printf(
            "%s goldens under %s: %s %s: changed %d px, largest cluster %d px, centroid %.3f px, area %.2f x allowed\n",
            make, check, c["id"].get<std::string>().c_str(), o["output"].get<std::string>().c_str(),
            m["changed_px"].get<int>(), m["largest_cluster_px"].get<int>(), m["worst_centroid_shift_px"].get<double>(),
            m["worst_area_change_ratio"].get<double>());
        EXPECT_LE(3 * m["largest_cluster_px"].get<int>(), 4);
        EXPECT_LE(3 * m["worst_centroid_shift_px"].get<double>(), 0.25);
        EXPECT_LE(3 * m["worst_area_change_ratio"].get<double>(), 1.0);
      }
  }
}

}  // namespace
