// The calibration inputs (kccd::calib): tag layouts and their corner geometry, labels and body
// labels placed by a model; every mistake is one line naming the file, the place and the field.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <apriltag/apriltag.h>
#include <apriltag/common/image_u8.h>
#include <apriltag/tag36h11.h>

#include "kccd/calib/labels.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/model.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  return path;
}

// The message of the error `f` throws as E (fails the test if it throws nothing or another type).
template <class E, class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const E& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  }
  ADD_FAILURE() << "no error";
  return {};
}

std::string tagError(const std::string& text) {
  return errorOf<TagLayoutError>([&] { parseTagLayout(text, "layout.yaml"); });
}
std::string labelError(const std::string& text) {
  return errorOf<LabelsError>([&] { parseLabels(text, "labels.yaml"); });
}

// ---------------------------------------------------------------------------------------------
// Tag layouts

TEST(CalibTagLayout, LoadsTheNumbers) {
  const std::string path = writeTemp("kccd_layout.yaml",
                                     "tags:\n"
                                     "  - {id: 3, size: 0.16, xyz: [1.0, 0.0, 0.0], rpy: [0, 0, 0]}\n"
                                     "  - id: 586\n"
                                     "    size: 0.05\n"
                                     "    xyz: [-0.5, 2, 0.25]\n"
                                     "    rpy: [0.1, -0.2, 0.3]\n");
  const TagLayout layout = loadTagLayout(path);
  ASSERT_EQ(layout.tags.size(), 2u);
  EXPECT_EQ(layout.tags[0].id, 3);
  EXPECT_DOUBLE_EQ(layout.tags[0].size, 0.16);
  EXPECT_EQ(layout.tags[0].xyz, Vec3(1, 0, 0));
  EXPECT_EQ(layout.tags[1].id, 586);
  EXPECT_EQ(layout.tags[1].xyz, Vec3(-0.5, 2, 0.25));
  EXPECT_EQ(layout.tags[1].rpy, Vec3(0.1, -0.2, 0.3));
  ASSERT_NE(layout.find(586), nullptr);
  EXPECT_DOUBLE_EQ(layout.find(586)->size, 0.05);
  EXPECT_EQ(layout.find(4), nullptr);
}

TEST(CalibTagLayout, CornersOfAnUnrotatedTag) {
  // Identity rpy: tag x = world x, tag y = world y, z towards the viewer = world z.
  Tag t;
  t.size = 0.2;
  t.xyz = Vec3(1, 2, 3);
  const auto c = t.corners();
  const cv::Point3d expected[4] = {{0.9, 1.9, 3}, {1.1, 1.9, 3}, {1.1, 2.1, 3}, {0.9, 2.1, 3}};
  for (int i = 0; i < 4; ++i) EXPECT_LT(cv::norm(c[static_cast<std::size_t>(i)] - expected[i]), 1e-15) << i;
}

TEST(CalibTagLayout, CornersOfAWallTagFacingTheRoom) {
  // A tag on the wall x = 2 facing -x: its z (out of the tag) must be world -x. yaw pi/2 turns
  // x -> y, then roll... use the URDF convention R = Rz(yaw) Ry(pitch) Rx(roll): roll pi/2
  // (y -> z, z -> -y) then yaw -pi/2 (x -> -y, y -> x): tag x -> -y... worked out per axis below.
  Tag t;
  t.size = 1.0;
  t.xyz = Vec3(2, 0, 1);
  t.rpy = Vec3(M_PI / 2, 0, -M_PI / 2);
  const Eigen::Matrix3d R = t.pose().linear();
  // Independent composition: Rx(roll) then Rz(yaw) about the fixed axes.
  const Eigen::Matrix3d rx = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d rz = Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(R.isApprox(rz * rx, 1e-15));
  const Vec3 x = R.col(0), y = R.col(1), z = R.col(2);
  EXPECT_TRUE(x.isApprox(Vec3(0, -1, 0), 1e-12)) << x.transpose();  // seen from the room (from -x), right is -y
  EXPECT_TRUE(y.isApprox(Vec3(0, 0, 1), 1e-12)) << y.transpose();   // up
  EXPECT_TRUE(z.isApprox(Vec3(-1, 0, 0), 1e-12)) << z.transpose();  // towards the viewer in the room
  const auto c = t.corners();
  // p0 bottom-left, p1 bottom-right, p2 top-right, p3 top-left as seen from the front.
  const cv::Point3d expected[4] = {{2, 0.5, 0.5}, {2, -0.5, 0.5}, {2, -0.5, 1.5}, {2, 0.5, 1.5}};
  for (int i = 0; i < 4; ++i) EXPECT_LT(cv::norm(c[static_cast<std::size_t>(i)] - expected[i]), 1e-12) << i;
  // Counter-clockwise seen from the front: (p1 - p0) x (p2 - p1) points towards the viewer.
  const cv::Point3d n = (c[1] - c[0]).cross(c[2] - c[1]);
  EXPECT_GT(n.dot(cv::Point3d(-1, 0, 0)), 0.0);
}

TEST(CalibTagLayout, EveryMistakeIsOneLineNamingThePlaceAndField) {
  const std::string ok = "{id: 1, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}";
  struct Case {
    std::string text, expected;
  } cases[] = {
      {"tags:\n  - " + ok + "\n  - {id: 1, size: 0.2, xyz: [1, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:3:10: tags[1].id: tag 1 is listed twice (also tags[0])"},
      {"tags:\n  - {id: 587, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:10: tags[0].id: '587' is not a tag36h11 id"},
      {"tags:\n  - {id: -1, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n", "layout.yaml:2:10: tags[0].id: '-1' is not"},
      {"tags:\n  - {id: 2.5, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:10: tags[0].id: '2.5' is not"},
      {"tags:\n  - {id: x, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:10: tags[0].id: expected a number, got 'x'"},
      {"tags:\n  - {id: 1, size: 0, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:19: tags[0].size: the edge of the black square must be > 0"},
      {"tags:\n  - {id: 1, size: -0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n", "layout.yaml:2:19: tags[0].size: the edge"},
      {"tags:\n  - {id: 1, size: 101, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n", "layout.yaml:2:19: tags[0].size: the edge"},
      {"tags:\n  - {id: 1, size: .nan, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:19: tags[0].size: must be finite"},
      {"tags:\n  - {id: 1, size: 0.1, xyz: [0, 2e6, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:33: tags[0].xyz[1]: beyond the largest"},
      {"tags:\n  - {id: 1, size: 0.1, xyz: [0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:29: tags[0].xyz: expected 3 numbers, got 2"},
      {"tags:\n  - {id: 1, size: 0.1, xyz: [0, 0, 0], rpy: [0, .inf, 0]}\n",
       "layout.yaml:2:49: tags[0].rpy[1]: must be finite"},
      {"tags:\n  - {id: 1, size: 0.1, xyz: [0, 0, 0]}\n", "layout.yaml:2:5: tags[0].rpy: required field is missing"},
      {"tags:\n  - {size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n",
       "layout.yaml:2:5: tags[0].id: required field is missing"},
      {"tags:\n  - {id: 1, size: 0.1, xyz: [0, 0, 0], rpy: [0, 0, 0], colour: red}\n",
       "layout.yaml:2:56: tags[0].colour: unknown field"},
      {"tag:\n  - " + ok + "\n", "layout.yaml:1:1: layout.tag: unknown field"},
      {"tags: []\n", "layout.yaml:1:7: tags: a layout needs at least one tag"},
      {"tags: 3\n", "layout.yaml:1:7: tags: expected a list"},
      {"- " + ok + "\n", "layout.yaml:1:1: layout: expected a mapping"},
      {"tags:\n  - " + ok + "\ntags:\n  - " + ok + "\n", "layout.yaml:3:1: tags: duplicate key"},
      {"tags:\n  - " + ok + "\n---\ntags:\n  - " + ok + "\n", "layout.yaml:3:"},
      {"tags: [\n", "layout.yaml:"},
  };
  for (const Case& c : cases) {
    const std::string m = tagError(c.text);
    EXPECT_EQ(m.rfind(c.expected, 0), 0u) << "got:      " << m << "\nexpected: " << c.expected << "\nfor:\n" << c.text;
  }
}

TEST(CalibTagLayout, FilesThatAreNotRegularOrTooLarge) {
  const std::string missing = ::testing::TempDir() + "/kccd_no_such_layout.yaml";
  EXPECT_EQ(errorOf<TagLayoutError>([&] { loadTagLayout(missing); }),
            missing + ": cannot open the tag layout (no such file)");
  const std::string dir = ::testing::TempDir();
  EXPECT_EQ(errorOf<TagLayoutError>([&] { loadTagLayout(dir); }), dir + ": a folder, not a tag layout");
  const std::string fifo = ::testing::TempDir() + "/kccd_layout_fifo";
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(errorOf<TagLayoutError>([&] { loadTagLayout(fifo); }),
            fifo + ": not a regular file (a device, FIFO or socket)");
  std::filesystem::remove(fifo);
  const std::string big = writeTemp("kccd_layout_big.yaml", "# " + std::string(kMaxTagLayoutBytes, 'x') + "\n");
  EXPECT_EQ(errorOf<TagLayoutError>([&] { loadTagLayout(big); }), big + ": larger than 1 MiB");
}

// ---------------------------------------------------------------------------------------------
// Labels

const char* kModel = R"(kccd: 1
name: two_link
joints:
  - {name: base, parent: world, type: revolute, axis: [0, 0, 1], origin: {xyz: [0.5, 0, 0.2], rpy: [0, 0, 0.3]}}
  - {name: elbow, parent: base, type: revolute, axis: [0, 1, 0], origin: {xyz: [0.4, 0, 0], rpy: [0.2, 0, 0]}}
  - {name: slide, parent: elbow, type: prismatic, axis: [1, 0, 0], origin: {xyz: [0, 0, 0.1]}}
bodies:
  - {name: table, frame: world, points: [[0, 0, 0]], radius: 0.1}
  - {name: upper, frame: base, points: [[0, 0, 0], [0.4, 0, 0]], radius: 0.05}
  - {name: forearm, frame: slide, points: [[0, 0, 0], [0.3, 0, 0]], radius: 0.04}
)";

// Forward kinematics written out by hand for kModel.
Vec3 forearmPoint(const Vec3& p, double q0, double q1, double q2) {
  using A = Eigen::AngleAxisd;
  const Eigen::Matrix3d r0 = A(0.3, Vec3::UnitZ()).toRotationMatrix() * A(q0, Vec3::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d r1 = A(0.2, Vec3::UnitX()).toRotationMatrix() * A(q1, Vec3::UnitY()).toRotationMatrix();
  const Vec3 in_slide = p;
  const Vec3 in_elbow = Vec3(0, 0, 0.1) + Vec3(q2, 0, 0) + in_slide;
  const Vec3 in_base = Vec3(0.4, 0, 0) + r1 * in_elbow;
  return Vec3(0.5, 0, 0.2) + r0 * in_base;
}

TEST(CalibLabels, LoadsWorldAndBodyLabels) {
  const std::string path = writeTemp(
      "kccd_labels.yaml",
      "labels:\n"
      "  - {name: table_corner, pixel: [512.5, 301.0], world: [1.2, 0.4, 0.0]}\n"
      "  - {name: wrist, pixel: [640.0, 210.5], body: forearm, point: [0.0, 0.0, 0.3], state: [0.1, -0.4, 0.05]}\n"
      "  - name: tip\n"
      "    pixel: [-3, 1e5]\n"
      "    body: forearm\n"
      "    point: [0.3, 0, 0]\n");
  const Labels labels = loadLabels(path);
  ASSERT_EQ(labels.labels.size(), 3u);
  const Label& a = labels.labels[0];
  EXPECT_EQ(a.name, "table_corner");
  EXPECT_EQ(a.pixel, cv::Point2d(512.5, 301.0));
  ASSERT_TRUE(a.world);
  EXPECT_EQ(*a.world, cv::Point3d(1.2, 0.4, 0.0));
  EXPECT_FALSE(a.bodyFixed());
  EXPECT_EQ(a.where, path + ":2:5");
  const Label& b = labels.labels[1];
  EXPECT_TRUE(b.bodyFixed());
  EXPECT_EQ(b.body, "forearm");
  EXPECT_EQ(b.point, cv::Point3d(0, 0, 0.3));
  ASSERT_TRUE(b.state);
  EXPECT_EQ(*b.state, (std::vector<double>{0.1, -0.4, 0.05}));
  const Label& c = labels.labels[2];
  EXPECT_EQ(c.pixel, cv::Point2d(-3, 1e5));
  EXPECT_FALSE(c.state.has_value());  // from a state log later
  EXPECT_EQ(labels.find("tip"), &c);
  EXPECT_EQ(labels.find("nope"), nullptr);
}

TEST(CalibLabels, BodyLabelsMatchIndependentKinematics) {
  const Model model = parseModel(kModel, "two_link.yaml");
  ASSERT_EQ(model.stateSize(), 3);
  const Labels labels = parseLabels(
      "labels:\n"
      "  - {name: corner, pixel: [1, 2], world: [1.2, 0.4, 0.0]}\n"
      "  - {name: wrist, pixel: [3, 4], body: forearm, point: [0.3, 0.02, -0.01], state: [0.7, -0.4, 0.05]}\n"
      "  - {name: shoulder, pixel: [5, 6], body: upper, point: [0.1, 0, 0]}\n"
      "  - {name: leg, pixel: [5, 6], body: table, point: [0.1, 0.2, 0.3]}\n",
      "labels.yaml");
  EXPECT_EQ(worldPoint(model, labels.labels[0]), cv::Point3d(1.2, 0.4, 0.0));
  const cv::Point3d w = worldPoint(model, labels.labels[1]);
  const Vec3 expected = forearmPoint(Vec3(0.3, 0.02, -0.01), 0.7, -0.4, 0.05);
  EXPECT_LT((Vec3(w.x, w.y, w.z) - expected).norm(), 1e-14) << expected.transpose();
  for (const double q : {-2.0, 0.0, 1.3}) {
    const std::vector<double> state{q, 0.5 * q, 0.1 * q};
    const cv::Point3d s = worldPoint(model, labels.labels[2], state);
    const Vec3 up = Vec3(0.5, 0, 0.2) + Eigen::AngleAxisd(0.3 + q, Vec3::UnitZ()) * Vec3(0.1, 0, 0);
    EXPECT_LT((Vec3(s.x, s.y, s.z) - up).norm(), 1e-14);
  }
  const std::vector<double> zero(3, 0.0);
  EXPECT_EQ(worldPoint(model, labels.labels[3], zero), cv::Point3d(0.1, 0.2, 0.3));  // a world body
}

TEST(CalibLabels, BodyLabelsThatDoNotFitTheModel) {
  const Model model = parseModel(kModel, "two_link.yaml");
  const Labels labels = parseLabels(
      "labels:\n"
      "  - {name: wrist, pixel: [3, 4], body: hand, point: [0, 0, 0], state: [0, 0, 0]}\n"
      "  - {name: elbow, pixel: [3, 4], body: forearm, point: [0, 0, 0], state: [0, 0]}\n"
      "  - {name: tip, pixel: [3, 4], body: forearm, point: [0, 0, 0]}\n",
      "labels.yaml");
  EXPECT_EQ(errorOf<LabelsError>([&] { worldPoint(model, labels.labels[0]); }),
            "labels.yaml:2:5: label 'wrist'.body: no body 'hand' in model 'two_link'");
  EXPECT_EQ(errorOf<LabelsError>([&] { worldPoint(model, labels.labels[1]); }),
            "labels.yaml:3:5: label 'elbow'.state: 2 state values, model 'two_link' has 3");
  EXPECT_EQ(errorOf<LabelsError>([&] { worldPoint(model, labels.labels[2]); }),
            "labels.yaml:4:5: label 'tip'.state: no state given (a state log must place body 'forearm')");
  const std::vector<double> bad{0.0, NAN, 0.0};
  EXPECT_EQ(errorOf<LabelsError>([&] { worldPoint(model, labels.labels[2], bad); }),
            "labels.yaml:4:5: label 'tip'.state: a state value is not finite");
}

TEST(CalibLabels, EveryMistakeIsOneLineNamingThePlaceAndField) {
  const std::string ok = "{name: a, pixel: [1, 2], world: [0, 0, 0]}";
  struct Case {
    std::string text, expected;
  } cases[] = {
      {"labels:\n  - " + ok + "\n  - {name: a, pixel: [3, 4], world: [1, 0, 0]}\n",
       "labels.yaml:3:12: labels[1].name: label 'a' is given twice (also labels[0])"},
      {"labels:\n  - {name: a, pixel: [1, 2], world: [0, 0, 0], body: b, point: [0, 0, 0]}\n",
       "labels.yaml:2:5: label 'a': give either world or body (with point), not both"},
      {"labels:\n  - {name: a, pixel: [1, 2]}\n",
       "labels.yaml:2:5: label 'a': needs world: [x, y, z] or body: NAME with point"},
      {"labels:\n  - {name: a, pixel: [1, 2], body: b}\n",
       "labels.yaml:2:5: label 'a'.point: required field is missing"},
      {"labels:\n  - {name: a, pixel: [1, 2], world: [0, 0, 0], point: [0, 0, 0]}\n",
       "labels.yaml:2:55: label 'a'.point: point belongs to a body label"},
      {"labels:\n  - {name: a, pixel: [1, 2], world: [0, 0, 0], state: [0]}\n",
       "labels.yaml:2:55: label 'a'.state: state belongs to a body label"},
      {"labels:\n  - {name: a, pixel: [1, .nan], world: [0, 0, 0]}\n",
       "labels.yaml:2:26: label 'a'.pixel[1]: must be finite"},
      {"labels:\n  - {name: a, pixel: [1, 2e6], world: [0, 0, 0]}\n",
       "labels.yaml:2:26: label 'a'.pixel[1]: beyond the largest"},
      {"labels:\n  - {name: a, pixel: [1, 2, 3], world: [0, 0, 0]}\n",
       "labels.yaml:2:22: label 'a'.pixel: expected 2 numbers, got 3"},
      {"labels:\n  - {name: a, world: [0, 0, 0]}\n", "labels.yaml:2:5: label 'a'.pixel: required field is missing"},
      {"labels:\n  - {name: a, pixel: [1, 2], world: [0, zero, 0]}\n",
       "labels.yaml:2:41: label 'a'.world[1]: expected a number, got 'zero'"},
      {"labels:\n  - {name: a, pixel: [1, 2], world: [0, 0, -1e7]}\n",
       "labels.yaml:2:44: label 'a'.world[2]: beyond the largest"},
      {"labels:\n  - {name: a, pixel: [1, 2], body: b, point: [0, 0, 0], state: [0, .inf]}\n",
       "labels.yaml:2:68: label 'a'.state[1]: must be finite"},
      {"labels:\n  - {name: a, pixel: [1, 2], body: b, point: [0, 0, 0], state: 3}\n",
       "labels.yaml:2:64: label 'a'.state: expected a list"},
      {"labels:\n  - {name: a, pixel: [1, 2], body: [b], point: [0, 0, 0]}\n",
       "labels.yaml:2:36: label 'a'.body: expected a string"},
      {"labels:\n  - {name: '', pixel: [1, 2], world: [0, 0, 0]}\n",
       "labels.yaml:2:12: labels[0].name: must not be empty"},
      {"labels:\n  - {name: \"a\\tb\", pixel: [1, 2], world: [0, 0, 0]}\n",
       "labels.yaml:2:12: labels[0].name: contains a control character: 'a\\x09b'"},
      {"labels:\n  - {name: a\xff"
       "b, pixel: [1, 2], world: [0, 0, 0]}\n",
       "labels.yaml:2:12: labels[0].name: is not UTF-8 text: 'a\\xffb'"},
      {"labels:\n  - {pixel: [1, 2], world: [0, 0, 0]}\n",
       "labels.yaml:2:5: labels[0].name: required field is missing"},
      {"labels:\n  - {name: a, pixel: [1, 2], world: [0, 0, 0], colour: red}\n",
       "labels.yaml:2:48: labels[0].colour: unknown field"},
      {"labels: []\n", "labels.yaml:1:9: labels: at least one label is needed"},
      {"label:\n  - " + ok + "\n", "labels.yaml:1:1: file.label: unknown field"},
      {"labels:\n  - " + ok + "\nlabels:\n  - " + ok + "\n", "labels.yaml:3:1: labels: duplicate key"},
      {"labels: {\n", "labels.yaml:"},
  };
  for (const Case& c : cases) {
    const std::string m = labelError(c.text);
    EXPECT_EQ(m.rfind(c.expected, 0), 0u) << "got:      " << m << "\nexpected: " << c.expected << "\nfor:\n" << c.text;
  }
  const std::string missing = ::testing::TempDir() + "/kccd_no_such_labels.yaml";
  EXPECT_EQ(errorOf<LabelsError>([&] { loadLabels(missing); }),
            missing + ": cannot open the labels file (no such file)");
}

// ---------------------------------------------------------------------------------------------
// AprilTag detection and correspondences

// Draws tag `id` upright (as apriltag_to_image renders it), `scale` pixels a cell, its bitmap's
// top-left pixel at (x0, y0). Returns where the black square's corners lie in OpenCV's pixel
// convention, in the tag-frame order (-,-), (+,-), (+,+), (-,+) with tag y up: bottom-left,
// bottom-right, top-right, top-left as seen.
std::array<cv::Point2d, 4> drawTag(cv::Mat& image, apriltag_family_t* family, int id, int x0, int y0, int scale) {
  image_u8_t* bitmap = apriltag_to_image(family, static_cast<uint32_t>(id));
  for (int r = 0; r < bitmap->height; ++r)
    for (int c = 0; c < bitmap->width; ++c)
      image(cv::Rect(x0 + c * scale, y0 + r * scale, scale, scale)) = bitmap->buf[r * bitmap->stride + c];
  const int border = (bitmap->width - static_cast<int>(family->width_at_border)) / 2;
  const double lo_x = x0 + border * scale - 0.5, hi_x = x0 + (bitmap->width - border) * scale - 0.5;
  const double lo_y = y0 + border * scale - 0.5, hi_y = y0 + (bitmap->height - border) * scale - 0.5;
  image_u8_destroy(bitmap);
  return {cv::Point2d(lo_x, hi_y), cv::Point2d(hi_x, hi_y), cv::Point2d(hi_x, lo_y), cv::Point2d(lo_x, lo_y)};
}

TEST(CalibTagDetect, CornersLandWhereTheyWereDrawn) {
  apriltag_family_t* family = tag36h11_create();
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(255));
  const std::array<cv::Point2d, 4> drawn3 = drawTag(image, family, 3, 40, 60, 17);
  const std::array<cv::Point2d, 4> drawn42 = drawTag(image, family, 42, 300, 200, 23);
  const std::array<cv::Point2d, 4> drawn500 = drawTag(image, family, 500, 420, 20, 12);
  tag36h11_destroy(family);
  const std::vector<TagDetection> found = detectTags(image);
  ASSERT_EQ(found.size(), 3u);
  for (const TagDetection& d : found) {
    const std::array<cv::Point2d, 4>& drawn = d.id == 3 ? drawn3 : d.id == 42 ? drawn42 : drawn500;
    ASSERT_TRUE(d.id == 3 || d.id == 42 || d.id == 500) << d.id;
    EXPECT_EQ(d.hamming, 0);
    for (std::size_t k = 0; k < 4; ++k)
      EXPECT_LT(cv::norm(d.corners[k] - drawn[k]), 0.5)
          << "tag " << d.id << " corner " << k << " at " << d.corners[k] << ", drawn " << drawn[k];
  }

  const TagLayout layout = parseTagLayout(
      "tags:\n"
      "  - {id: 3, size: 0.16, xyz: [1, 0, 0], rpy: [0, 0, 0]}\n"
      "  - {id: 42, size: 0.2, xyz: [0, 1, 0], rpy: [0, 0, 1.0]}\n"
      "  - {id: 7, size: 0.2, xyz: [0, 1, 0], rpy: [0, 0, 0]}\n",
      "layout.yaml");
  const TagCorrespondences corr = tagCorrespondences(found, layout, "frame.png");
  EXPECT_EQ(corr.unknown_ids, std::vector<int>{500});
  ASSERT_EQ(corr.points.size(), 8u);
  for (const Correspondence& c : corr.points) {
    const int id = c.name.rfind("tag3.", 0) == 0 ? 3 : 42;
    const std::size_t k = static_cast<std::size_t>(c.name.back() - '0');
    ASSERT_EQ(c.name, "tag" + std::to_string(id) + ".c" + std::to_string(k));
    EXPECT_LT(cv::norm(c.pixel - (id == 3 ? drawn3 : drawn42)[k]), 0.5) << c.name;
    EXPECT_EQ(c.world, layout.find(id)->corners()[k]) << c.name;
  }

  const std::vector<TagDetection> twice{found[0], found[1], found[0]};
  EXPECT_EQ(errorOf<TagDetectionError>([&] { tagCorrespondences(twice, layout, "frame.png"); }),
            "frame.png: tags: tag " + std::to_string(found[0].id) +
                " is detected twice (each id may appear once: is it printed twice?)");
  EXPECT_THROW(detectTags(cv::Mat(10, 10, CV_8UC3)), std::invalid_argument);
}

// Images too small to hold a tag give no detections (libapriltag 3.3 reads outside images under
// 3 rows: a 130 x 1 JPEG found by fuzz_frame crashed it), at every size under the bound and in
// both directions, for noise and for stripes; the first size at the bound reaches the detector.
TEST(CalibTagDetect, ImagesTooSmallForATagHaveNone) {
  cv::RNG rng(7);
  for (int rows = 1; rows <= 2 * kMinTagPixels; ++rows)
    for (const int cols : {1, 2, 3, kMinTagPixels - 1, kMinTagPixels, 64, 130}) {
      if (rows >= kMinTagPixels && cols >= kMinTagPixels) continue;
      for (int pattern = 0; pattern < 2; ++pattern) {
        cv::Mat img(rows, cols, CV_8UC1);
        if (pattern == 0) rng.fill(img, cv::RNG::UNIFORM, 0, 256);
        for (int c = 0; pattern == 1 && c < cols; ++c) img.col(c).setTo((c / 3) % 2 ? 255 : 0);
        EXPECT_TRUE(detectTags(img).empty()) << rows << " x " << cols;
        EXPECT_TRUE(detectTags(img.t()).empty()) << cols << " x " << rows;
      }
    }
  // A real tag scaled down to the bound still goes through the detector without harm.
  cv::Mat small(kMinTagPixels, kMinTagPixels, CV_8UC1, cv::Scalar(255));
  small(cv::Rect(0, 0, kMinTagPixels / 2, kMinTagPixels / 2)).setTo(0);
  EXPECT_NO_THROW(detectTags(small));
}

}  // namespace
