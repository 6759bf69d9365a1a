// Calibration through kccd::overlay's library calls, without the command line: the correspondences
// gathered from a rendered frame of tags, labels and a model (gatherCorrespondences), frames of a
// recording by index, the solve with its figures, its check image and report, and the labelling
// candidates of a frame as data (tags, strong corners, projected model points) with the sheet and
// the labels template drawn from them.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/image_file.hpp"
#include "kccd/calib/labels.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/overlay/calibration/calib_check.hpp"
#include "kccd/overlay/calibration/calib_drawing.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_report.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"
#include "kccd/overlay/calibration/model_points.hpp"
#include "kccd/overlay/labelling/labelling_candidates.hpp"
#include "kccd/overlay/recording/video_source.hpp"
#include "support/tag_scene.hpp"

namespace {

namespace fs = std::filesystem;
using namespace kccd;
using namespace kccd::overlay;
using calib::Camera;
using calib::Tag;
using calib::TagLayout;

const std::string kData = KCCD_DATA_DIR;
const std::vector<double> kState{0.3, 0.4, 0.6};
constexpr int kUnknownId = 99;

cv::Point2d project(const Camera& c, const cv::Point3d& p) {
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{p}, c.rvec, c.tvec, c.camera_matrix, c.distortion, out);
  return out[0];
}

// A tag of edge `size` centred at `at`, facing the point `eye`.
Tag facing(int id, double size, const Vec3& at, const Vec3& eye) {
  const Vec3 z = (eye - at).normalized();
  const Vec3 x = Vec3::UnitZ().cross(z).normalized();
  Eigen::Matrix3d r;
  r.col(0) = x, r.col(1) = z.cross(x), r.col(2) = z;
  const Vec3 ypr = r.eulerAngles(2, 1, 0);  // R = Rz(yaw) Ry(pitch) Rx(roll)
  Tag t;
  t.id = id;
  t.size = size;
  t.xyz = at;
  t.rpy = Vec3(ypr[2], ypr[1], ypr[0]);
  return t;
}

// The demo camera looking at the demo arm, three tags of a layout around the arm facing it and a
// fourth tag the layout does not have, drawn once for every test.
class CalibLibrary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    camera_ = new Camera(calib::loadCamera(kData + "/demo_camera.yaml"));
    model_ = new Model(loadModel(kData + "/demo_arm.yaml"));
    const cv::Vec3d c = calib::cameraCentre(*camera_);
    const Vec3 eye(c[0], c[1], c[2]);
    layout_ = new TagLayout;
    layout_->tags = {facing(3, 0.2, Vec3(0.3, -0.7, 0.2), eye), facing(17, 0.22, Vec3(1.2, 0.6, 0.3), eye),
                     facing(42, 0.2, Vec3(0.2, 0.3, 0.7), eye)};
    TagLayout scene = *layout_;
    scene.tags.push_back(facing(kUnknownId, 0.18, Vec3(0.8, -0.2, 0.25), eye));
    frame_ = new cv::Mat(calib::renderTagSceneBgr(*camera_, scene));
  }
  static void TearDownTestSuite() {
    delete camera_;
    delete model_;
    delete layout_;
    delete frame_;
  }
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kccd_calib_gather_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // The inputs of one frame: the rendered picture, the layout, the model at kState.
  static GatherInputs tagInputs() {
    GatherInputs in;
    in.camera = intrinsicsOf(*camera_);
    in.camera_name = "demo_camera.yaml";
    in.tags = *layout_;
    in.model = model_;
    in.frames.push_back({.image = "frame", .bgr = *frame_, .labels = {}, .state = kState});
    return in;
  }

  static Camera* camera_;
  static Model* model_;
  static TagLayout* layout_;
  static cv::Mat* frame_;
  fs::path dir_;
};

Camera* CalibLibrary::camera_ = nullptr;
Model* CalibLibrary::model_ = nullptr;
TagLayout* CalibLibrary::layout_ = nullptr;
cv::Mat* CalibLibrary::frame_ = nullptr;

// Every corner of the layout's tags is a point at its world corner, seen within a pixel of where
// the camera projects it; the tag the layout lacks is reported, not used.
TEST_F(CalibLibrary, TagCornersAreSeenWhereTheCameraProjectsThem) {
  const Gathered g = gatherCorrespondences(tagInputs());
  ASSERT_EQ(g.frames.size(), 1u);
  ASSERT_EQ(g.points.size(), 12u);
  ASSERT_EQ(g.sources.size(), 12u);
  EXPECT_EQ(g.frames[0].tag_points, 12);
  EXPECT_EQ(g.frames[0].label_points, 0);
  EXPECT_EQ(g.frames[0].state, kState);
  EXPECT_EQ(g.frames[0].unknown_ids, std::vector<int>{kUnknownId});
  EXPECT_EQ(g.unknown_tag_ids, std::vector<int>{kUnknownId});
  for (const Tag& tag : layout_->tags) {
    const auto corners = tag.corners();
    for (std::size_t k = 0; k < 4; ++k) {
      const std::string name = "tag" + std::to_string(tag.id) + ".c" + std::to_string(k);
      const auto it = std::find_if(g.points.begin(), g.points.end(),
                                   [&](const calib::Correspondence& c) { return c.name == name; });
      ASSERT_NE(it, g.points.end()) << name;
      const std::size_t i = static_cast<std::size_t>(it - g.points.begin());
      EXPECT_EQ(it->world, corners[k]) << name;
      EXPECT_LT(cv::norm(it->pixel - project(*camera_, corners[k])), 1.0) << name << " seen at " << it->pixel;
      EXPECT_TRUE(g.sources[i].tag);
      EXPECT_EQ(g.sources[i].frame, 0u);
      EXPECT_EQ(g.sources[i].label, k == 0 ? "tag" + std::to_string(tag.id) : "") << name;
    }
  }
}

// Labels: world labels at their points, body labels placed by the model at the frame's state or at
// their own; with several frames every name says its frame.
TEST_F(CalibLibrary, LabelsAreGatheredAtTheirWorldPoints) {
  GatherInputs in = tagInputs();
  const std::vector<double> own{-0.2, 0.9, -0.4};
  const calib::Labels labels = calib::parseLabels(
      "labels:\n"
      "  - {name: w, pixel: [100, 200], world: [0.1, 0.2, 0.3]}\n"
      "  - {name: g, pixel: [300, 400], body: gripper, point: [0.34, -0.04, 0]}\n"
      "  - {name: h, pixel: [500, 600], body: forearm, point: [0.32, 0, 0], state: [-0.2, 0.9, -0.4]}\n",
      "labels.yaml");
  in.frames.push_back({.image = "", .bgr = {}, .labels = labels, .state = std::vector<double>{0.1, -0.5, 1.0}});
  const Gathered g = gatherCorrespondences(in);
  ASSERT_EQ(g.frames.size(), 2u);
  ASSERT_EQ(g.points.size(), 15u);
  EXPECT_EQ(g.frames[1].image, "");
  EXPECT_TRUE(g.frames[1].bgr.empty());
  EXPECT_EQ(g.frames[1].tag_points, 0);
  EXPECT_EQ(g.frames[1].label_points, 3);
  for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(g.points[i].name.rfind("f1/tag", 0), 0u) << g.points[i].name;
  EXPECT_EQ(g.sources[0].label.rfind("f1/tag", 0), 0u);
  // Independent forward kinematics of the two body points.
  auto placed = [&](const std::string& body, const Vec3& p, const std::vector<double>& state) {
    std::vector<Pose> poses(model_->joints.size());
    EXPECT_TRUE(framePoses(*model_, state, poses));
    int frame = 0;
    for (const Body& b : model_->bodies) frame = b.name == body ? b.frame : frame;
    const Vec3 w = framePose(poses, frame) * p;
    return cv::Point3d(w.x(), w.y(), w.z());
  };
  const calib::Correspondence& w = g.points[12];
  const calib::Correspondence& gr = g.points[13];
  const calib::Correspondence& h = g.points[14];
  EXPECT_EQ(w.name, "f2/w");
  EXPECT_EQ(w.pixel, cv::Point2d(100, 200));
  EXPECT_EQ(w.world, cv::Point3d(0.1, 0.2, 0.3));
  EXPECT_EQ(gr.name, "f2/g");
  EXPECT_LT(cv::norm(gr.world - placed("gripper", Vec3(0.34, -0.04, 0), {0.1, -0.5, 1.0})), 1e-12);
  EXPECT_EQ(h.name, "f2/h");
  EXPECT_LT(cv::norm(h.world - placed("forearm", Vec3(0.32, 0, 0), own)), 1e-12);
  for (std::size_t i = 12; i < 15; ++i) {
    EXPECT_FALSE(g.sources[i].tag);
    EXPECT_EQ(g.sources[i].frame, 1u);
    EXPECT_EQ(g.sources[i].label, g.points[i].name);
  }
}

// Inputs that do not fit together are one line naming the place.
TEST_F(CalibLibrary, InputsThatDoNotFitAreOneLineErrors) {
  auto errorOf = [](const GatherInputs& in) -> std::string {
    try {
      (void)gatherCorrespondences(in);
      return "";
    } catch (const CalibInputError& e) {
      return e.what();
    }
  };
  GatherInputs small = tagInputs();
  small.frames[0].bgr = cv::Mat(100, 200, CV_8UC3, cv::Scalar(128, 128, 128));
  EXPECT_EQ(errorOf(small), "frame: the image is 200x100 but the camera demo_camera.yaml is 1280x720");
  GatherInputs state = tagInputs();
  state.frames[0].state = std::vector<double>{0.1, 0.2};
  EXPECT_NE(errorOf(state).find("the state has 2 values but model 'demo_arm' has 3"), std::string::npos)
      << errorOf(state);

  const calib::Labels body =
      calib::parseLabels("labels:\n  - {name: g, pixel: [1, 2], body: gripper, point: [0, 0, 0]}\n", "b.yaml");
  GatherInputs no_model;
  no_model.camera = intrinsicsOf(*camera_);
  no_model.frames.push_back({.image = "", .bgr = {}, .labels = body, .state = kState});
  EXPECT_EQ(errorOf(no_model), "b.yaml:2:5: g: a body label needs a model (the model places its body)");
  GatherInputs no_state = no_model;
  no_state.model = model_;
  no_state.frames[0].state.reset();
  EXPECT_NE(errorOf(no_state).find("b.yaml:2:5: g: a body label needs a state"), std::string::npos)
      << errorOf(no_state);
  no_state.frames[0].state = kState;
  EXPECT_EQ(errorOf(no_state), "");
  // An image file that is not there: the image reader's error, naming it.
  GatherInputs missing = tagInputs();
  missing.frames[0] = {.image = path("missing.png"), .bgr = {}, .labels = {}, .state = {}};
  EXPECT_THROW((void)gatherCorrespondences(missing), calib::ImageError);
}

// Frames of a recording by index, in the order asked for; past its end, one line naming it.
TEST_F(CalibLibrary, FramesOfARecordingByIndex) {
  auto picture = [](int i) {
    cv::Mat m(48, 64, CV_8UC3, cv::Scalar(30 * i, 90, 200 - 30 * i));
    cv::rectangle(m, cv::Rect(5 * i, 10, 8, 8), cv::Scalar(255, 255, 255), cv::FILLED);
    return m;
  };
  for (int i = 0; i < 5; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", i);
    ASSERT_TRUE(cv::imwrite(path(name), picture(i)));
  }
  const RecordingFrames r = readRecordingFrames(path("frame_%06d.png"), {3, 0, 3});
  ASSERT_EQ(r.frames.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_EQ(r.frames[k].type(), CV_8UC3);
    EXPECT_EQ(cv::norm(r.frames[k], picture(k == 1 ? 0 : 3), cv::NORM_INF), 0.0) << k;
  }
  try {
    (void)readRecordingFrames(path("frame_%06d.png"), {1, 7}, "--video seq");
    ADD_FAILURE() << "frame 7 of 5 was read";
  } catch (const VideoError& e) {
    EXPECT_EQ(std::string(e.what()), "--video seq: frame 7: the recording has only 5 readable frames");
  }
  EXPECT_THROW((void)readRecordingFrames(path("none.mkv"), {0}), VideoError);
}

// The solve from the gathered tag corners finds the camera the frame was drawn with; its figures,
// check image and report say so.
TEST_F(CalibLibrary, SolveCheckImageAndReport) {
  const Gathered g = gatherCorrespondences(tagInputs());
  const CalibSolution s = solveCalibration(intrinsicsOf(*camera_), g, {}, model_, camera_);
  ASSERT_TRUE(s.solved()) << s.pose.message;
  ASSERT_TRUE(s.truth_error.has_value());
  EXPECT_LT(s.truth_error->rotation_deg, 0.2);
  EXPECT_LT(s.truth_error->position_m, 0.01);
  EXPECT_EQ(s.truth_error->rotation_deg, calib::poseDifference(s.pose.camera, *camera_).rotation_deg);
  ASSERT_TRUE(s.volume_sigma_px.has_value());
  EXPECT_GT(*s.volume_sigma_px, 0.0);
  EXPECT_LT(*s.volume_sigma_px, 5.0);
  EXPECT_EQ(s.pose.residuals.size(), g.points.size());
  // Without a model or a known camera: no such figures.
  const CalibSolution bare = solveCalibration(intrinsicsOf(*camera_), g, {});
  EXPECT_FALSE(bare.volume_sigma_px || bare.truth_error);

  // The check image: the frame's size, the volumes drawn, the headline band darkened.
  const CheckImage check = checkImage(g, s, 0, model_, {.magnify = 20.0, .camera_name = "demo_camera.yaml"});
  ASSERT_EQ(check.bgr.size(), frame_->size());
  ASSERT_EQ(check.bgr.type(), CV_8UC3);
  EXPECT_FALSE(check.renderer.empty());
  const cv::Rect band(0, frame_->rows - 20, frame_->cols, 20);
  EXPECT_LT(cv::mean(check.bgr(band))[0], 0.5 * cv::mean((*frame_)(band))[0]);
  const CheckImage plain = checkImage(g, s, 0, nullptr, {});
  EXPECT_TRUE(plain.renderer.empty());
  EXPECT_GT(cv::norm(check.bgr, plain.bgr, cv::NORM_L1), 0.0);  // the volumes
  EXPECT_THROW((void)checkImage(g, s, 1, nullptr, {}), std::invalid_argument);
  CalibSolution unsolved = s;
  unsolved.pose.status = calib::PoseStatus::TooFewInliers;
  EXPECT_THROW((void)checkImage(g, unsolved, 0, nullptr, {}), std::invalid_argument);

  const nlohmann::json j = calibReport(g, s, {.camera = "cam.yaml", .check = "", .renderer = check.renderer});
  EXPECT_EQ(j["status"], "solved");
  EXPECT_EQ(j["points"], 12);
  EXPECT_EQ(j["output"], "cam.yaml");
  EXPECT_EQ(j["unknown_tag_ids"], nlohmann::json::array({kUnknownId}));
  ASSERT_EQ(j["residuals"].size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(j["residuals"][i]["name"], g.points[i].name);
  EXPECT_EQ(j["frames"][0]["tag_points"], 12);
  EXPECT_EQ(j["truth_error"]["position_m"].get<double>(), s.truth_error->position_m);
  EXPECT_EQ(j["volume_sigma_px"].get<double>(), *s.volume_sigma_px);
  EXPECT_FALSE(j.contains("check"));
  const nlohmann::json failed = calibReport(g, unsolved, {});
  EXPECT_FALSE(failed.contains("rvec"));
}

// The model's core points: named body.k, placed by forward kinematics; none for a state that
// cannot place them.
TEST_F(CalibLibrary, ModelPointsArePlacedByForwardKinematics) {
  const std::vector<ModelPoint> points = modelPoints(*model_, kState);
  std::size_t count = 0;
  for (const Body& b : model_->bodies) count += b.points.size();
  ASSERT_EQ(points.size(), count);
  std::vector<Pose> poses(model_->joints.size());
  ASSERT_TRUE(framePoses(*model_, kState, poses));
  for (const ModelPoint& p : points) {
    const Body& b = model_->bodies[static_cast<std::size_t>(p.body)];
    EXPECT_EQ(p.name, b.name + "." + std::to_string(p.point));
    const Vec3 w = framePose(poses, b.frame) * b.points[static_cast<std::size_t>(p.point)];
    EXPECT_EQ(p.world, cv::Point3d(w.x(), w.y(), w.z())) << p.name;
  }
  EXPECT_EQ(worldPoints(points).size(), count);
  EXPECT_TRUE(modelPoints(*model_, std::vector<double>{0.1}).empty());
}

// The candidates of a frame as data: every tag with its corners (placed or not), the corners of
// drawn squares, and the model's points exactly where the camera projects them; the sheet and the
// labels template are drawn from them.
TEST_F(CalibLibrary, LabellingCandidatesAsData) {
  cv::Mat frame = frame_->clone();
  const std::vector<cv::Point> squares{{60, 60}, {1150, 40}, {40, 640}};
  for (const cv::Point& p : squares) cv::rectangle(frame, p, p + cv::Point(50, 50), cv::Scalar(20, 20, 20), cv::FILLED);
  CandidateInputs in;
  in.image = "frame.png";
  in.tags = *layout_;
  in.camera = *camera_;
  in.camera_name = "demo_camera.yaml";
  in.model = model_;
  in.state = kState;
  const LabellingCandidates c = labellingCandidates(frame, in);

  // Tags: the layout's three placed, the other not; corners within a pixel of their projection.
  ASSERT_EQ(c.tags.size(), 4u);
  EXPECT_TRUE(c.layout);
  TagLayout all = *layout_;
  all.tags.push_back(facing(kUnknownId, 0.18, Vec3(0.8, -0.2, 0.25), Vec3(2.0, -1.5, 1.3)));
  for (const TagCandidate& t : c.tags) {
    EXPECT_EQ(t.placed, t.id != kUnknownId) << t.id;
    const Tag* tag = all.find(t.id);
    ASSERT_NE(tag, nullptr) << t.id;
    const auto corners = tag->corners();
    for (std::size_t k = 0; k < 4; ++k) EXPECT_LT(cv::norm(t.corners[k] - project(*camera_, corners[k])), 1.0) << t.id;
  }
  // Strong corners: each square's four, at its pixel edges (p - 0.5 and p + 50.5), named p1, p2, ...
  int found = 0;
  for (const cv::Point& p : squares)
    for (const cv::Point2d& q : {cv::Point2d(p.x - 0.5, p.y - 0.5), cv::Point2d(p.x + 50.5, p.y - 0.5),
                                 cv::Point2d(p.x - 0.5, p.y + 50.5), cv::Point2d(p.x + 50.5, p.y + 50.5)})
      for (const CornerCandidate& k : c.corners) found += cv::norm(k.pixel - q) < 0.25;
  EXPECT_EQ(found, 12);
  for (std::size_t i = 0; i < c.corners.size(); ++i) EXPECT_EQ(c.corners[i].name, "p" + std::to_string(i + 1));
  EXPECT_LE(c.corners.size(), 40u);
  // Model points: every core point in view, where the camera projects the point placed at the state.
  EXPECT_EQ(c.state, kState);
  std::size_t in_view = 0;
  for (const ModelPoint& p : modelPoints(*model_, kState)) {
    const cv::Point2d q = project(*camera_, p.world);
    in_view += q.x >= -0.5 && q.y >= -0.5 && q.x < frame.cols - 0.5 && q.y < frame.rows - 0.5;
  }
  EXPECT_EQ(c.model_points.size(), in_view);
  EXPECT_GE(c.model_points.size(), 10u);
  for (const ModelPointCandidate& p : c.model_points) {
    EXPECT_EQ(p.pixel, project(*camera_, p.world)) << p.name;
    const Body* b = nullptr;
    for (const Body& body : model_->bodies) b = body.name == p.body ? &body : b;
    ASSERT_NE(b, nullptr) << p.name;
    EXPECT_EQ(p.body_point, b->points[static_cast<std::size_t>(p.point)]);
    EXPECT_EQ(p.world_fixed, b->frame == kWorld) << p.name;
    if (p.world_fixed) {
      EXPECT_EQ(p.world, cv::Point3d(p.body_point.x(), p.body_point.y(), p.body_point.z())) << p.name;
    }
  }

  // The sheet: drawn from the data (differs from the frame); the template: one commented line per
  // strong corner, per corner of the tag the layout lacks, per model point.
  const cv::Mat sheet = drawSheet(frame, c);
  ASSERT_EQ(sheet.size(), frame.size());
  EXPECT_GT(cv::norm(sheet, frame, cv::NORM_L1), 0.0);
  const std::string t = labelsTemplate(c, "frame.png", "sheet.png");
  EXPECT_EQ(t.rfind("# Labels for frame.png (made by kccd calib sheet; see the sheet image sheet.png).\n", 0), 0u) << t;
  EXPECT_EQ(static_cast<std::size_t>(std::count(t.begin(), t.end(), '\n')),
            4 + c.corners.size() + 4 + c.model_points.size())
      << t;
  EXPECT_NE(t.find("name: tag99.c3"), std::string::npos) << t;
  EXPECT_EQ(t.find("name: tag3.c0"), std::string::npos) << t;
  EXPECT_NE(t.find("body: gripper, point: [0.34, -0.04, 0], state: [0.3, 0.4, 0.6]"), std::string::npos) << t;
  EXPECT_NE(t.find("world: [0.45, -0.4, 0.1]"), std::string::npos) << t;

  // Without a camera, the model cannot be projected; a state of the wrong size is refused.
  CandidateInputs no_camera = in;
  no_camera.camera.reset();
  EXPECT_THROW((void)labellingCandidates(frame, no_camera), CalibInputError);
  CandidateInputs bad_state = in;
  bad_state.state = {0.1};
  EXPECT_THROW((void)labellingCandidates(frame, bad_state), CalibInputError);
  // Tags and corners alone, no layout: nothing is placed.
  const LabellingCandidates bare = labellingCandidates(frame, CandidateInputs{.image = "frame.png"});
  EXPECT_EQ(bare.tags.size(), 4u);
  EXPECT_FALSE(bare.layout);
  for (const TagCandidate& tag : bare.tags) EXPECT_FALSE(tag.placed);
  EXPECT_TRUE(bare.model_points.empty());
}

}  // namespace

namespace {

// A camera fixed to joint frame `frame` with pose `mount_to_camera`, as a world camera at state `q`.
calib::Camera worldCameraAt(const Model& m, calib::Camera c, int frame, const Pose& mount_to_camera,
                            const std::vector<double>& q) {
  std::vector<Pose> poses(m.joints.size());
  EXPECT_TRUE(framePoses(m, q, poses));
  const Pose world_to_camera = mount_to_camera * framePose(poses, frame).inverse();
  cv::Matx33d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = world_to_camera.linear()(i, j);
  cv::Rodrigues(r, c.rvec);
  c.tvec = cv::Vec3d(world_to_camera.translation().x(), world_to_camera.translation().y(),
                     world_to_camera.translation().z());
  return c;
}

}  // namespace

// A camera on the robot solved from world points seen at several states (inMountFrame): the mount
// -> camera pose it was made with, to float precision; a frame without a state is refused.
TEST(CalibMount, ACameraOnTheRobotIsSolvedInItsFrame) {
  const Model m = loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const int frame = m.jointIndex("shoulder_pitch");
  calib::Camera intrinsics = calib::loadCamera(std::string(KCCD_DATA_DIR) + "/demo_camera.yaml");
  // The true mount -> camera pose: 0.4 m out along the arm's x, looking back at the world's origin area.
  const calib::Camera looking = intrinsics;  // the sample camera's view of the world at the zero state
  std::vector<Pose> zero(m.joints.size());
  ASSERT_TRUE(framePoses(m, std::vector<double>(3, 0.0), zero));
  const Pose mount_to_camera = looking.worldToCamera() * framePose(zero, frame);
  Gathered g;
  const std::vector<std::vector<double>> states = {{0.0, 0.0, 0.0}, {0.15, -0.1, 0.3}, {-0.2, 0.12, 0.5}};
  for (std::size_t f = 0; f < states.size(); ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "f%zu", f);
    g.frames.push_back(GatheredFrame{.image = name, .state = states[f]});
    const calib::Camera at = worldCameraAt(m, intrinsics, frame, mount_to_camera, states[f]);
    for (int i = 0; i < 12; ++i) {  // points on the floor and the wall in front of the robot
      const cv::Point3d w(0.3 + 0.1 * (i % 4), -0.3 + 0.2 * (i / 4), i % 2 == 0 ? 0.0 : 0.4);
      std::vector<cv::Point2d> px;
      cv::projectPoints(std::vector<cv::Point3d>{w}, at.rvec, at.tvec, at.camera_matrix, at.distortion, px);
      std::snprintf(name, sizeof name, "f%zu/p%d", f, i);
      g.points.push_back({name, px[0], w});
      g.sources.push_back({.frame = f});
    }
  }
  const Gathered mounted = inMountFrame(g, m, frame, "--camera-frame shoulder_pitch");
  const calib::PoseResult r = calib::solvePose(intrinsicsOf(intrinsics), mounted.points);
  ASSERT_EQ(r.status, calib::PoseStatus::Solved) << r.message;
  const Pose solved = r.camera.worldToCamera();
  EXPECT_LT((solved.translation() - mount_to_camera.translation()).norm(), 1e-6);
  EXPECT_LT((solved.linear() - mount_to_camera.linear()).norm(), 1e-6);
  // The world camera of one state does not explain the others' points: the mount frame is what fits.
  const calib::PoseResult wrong = calib::solvePose(intrinsicsOf(intrinsics), g.points);
  EXPECT_TRUE(wrong.status != calib::PoseStatus::Solved || wrong.rejected.size() > 6);
  Gathered stateless = g;
  stateless.frames[1].state.clear();
  try {
    inMountFrame(stateless, m, frame, "--camera-frame shoulder_pitch");
    ADD_FAILURE() << "a frame without a state was placed";
  } catch (const CalibInputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--camera-frame shoulder_pitch: frame 2 (f1) has no state", 0), 0u)
        << e.what();
  }
}
