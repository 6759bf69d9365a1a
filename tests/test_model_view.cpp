// The model as the camera sees it (kccd/render/model_view.hpp) and the model's visual geometry
// (kccd/render/visuals.hpp): the same images as the steps it joins (query, scene volumes,
// renderer) taken one by one, each kind of request, and visuals placed at the state.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/checker.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/render/model_view.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/render/visuals.hpp"
#include "support/cameras.hpp"
#include "support/silhouette.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;

const std::string kData = KCCD_DATA_DIR;

// The sample camera at a quarter of its size (320 x 180), as the golden images use it.
calib::Camera smallCamera() {
  calib::Camera c = calib::loadCamera(kData + "/demo_camera.yaml");
  c = kccd::testing::quarterSized(c);
  return c;
}

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

class ModelViewTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = new Model(loadModel(kData + "/demo_arm.yaml")); }
  static void TearDownTestSuite() { delete model_; }
  static Model* model_;
};
Model* ModelViewTest::model_ = nullptr;

TEST_F(ModelViewTest, StateDrawsWhatTheStepsDraw) {
  const Model& m = *model_;
  const std::vector<double> q = {0.3, 0.4, 0.6};
  ModelView view(m, smallCamera());
  ModelViewRequest request;
  request.state = q;
  request.style.labels = true;
  const ModelFrame f = view.draw(request);

  Checker checker(m);
  const QueryResult& r = checker.query(q, q, QueryOptions{.type = QueryType::Distances, .tight_volumes = true});
  Renderer renderer(smallCamera());
  const Frame expected =
      renderer.render(staticSceneVolumes(m, checker, q, bodyStatus(m, r)), Style{.labels = true}, true, true);
  ASSERT_TRUE(f.query.has_value());
  EXPECT_EQ(f.query->status, Status::Ok);
  EXPECT_EQ(f.query->min_distance, r.min_distance);
  EXPECT_EQ(f.status, bodyStatus(m, r));
  EXPECT_EQ(f.distances, bodyDistances(m, r));
  EXPECT_EQ(f.first_visual, m.bodies.size());
  EXPECT_TRUE(sameImage(f.images.bgra, expected.bgra));
  EXPECT_TRUE(sameImage(f.images.mask, expected.mask));
  EXPECT_EQ(f.images.pixels, expected.pixels);
  EXPECT_EQ(f.images.visibility, expected.visibility);
  EXPECT_GT(cv::countNonZero(f.images.mask), 1000);
}

// Neither colour nor mask asked: the query and the statuses alone (the overlay's frames outside
// --frames), the same answer as a drawn request's, and no images.
TEST_F(ModelViewTest, NoImageAskedIsTheQueryAlone) {
  const Model& m = *model_;
  const std::vector<double> lo = {0.2, 0.3, 0.5}, hi = {0.4, 0.5, 0.7};
  ModelView view(m, smallCamera());
  ModelViewRequest request;
  request.state = lo;
  request.lower = lo;
  request.upper = hi;
  const ModelFrame drawn = view.draw(request);
  request.colour = false;
  request.mask = false;
  const ModelFrame counted = view.draw(request);
  ASSERT_TRUE(drawn.query.has_value());
  ASSERT_TRUE(counted.query.has_value());
  EXPECT_EQ(counted.query->status, drawn.query->status);
  EXPECT_EQ(counted.query->min_distance, drawn.query->min_distance);
  EXPECT_EQ(counted.status, drawn.status);
  EXPECT_EQ(counted.distances, drawn.distances);
  EXPECT_TRUE(counted.images.bgra.empty());
  EXPECT_TRUE(counted.images.mask.empty());
  EXPECT_TRUE(counted.images.visibility.empty());
  EXPECT_FALSE(drawn.images.bgra.empty());
}

// A body with more points than the model's point budget is drawn as it is (its own points and
// radius), not as the checker's reduced stand-in: its mask lies within the mask's edge bound of
// an independent silhouette of its own SSCH (tests/support/silhouette.hpp). The stand-in (the
// checker's volume) is drawn too, and is visibly larger: the check can fail.
TEST(ModelViewBudget, BodyAboveThePointBudgetIsDrawnAsItIs) {
  std::mt19937_64 rng(44);
  std::normal_distribution<double> g;
  std::vector<Vec3> pts;  // 14 points of an elongated link, far more than the budget of 4
  for (int i = 0; i < 14; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    d.normalize();
    pts.push_back(Vec3(0.25 * d.x(), 0.06 * d.y(), 0.05 * d.z()));
  }
  std::ostringstream yaml;
  yaml.precision(17);
  yaml << "kccd: 1\nname: budget\nsafety_margin: 0.01\npoint_budget: 4\n"
       << "joints:\n  - {name: j, type: revolute, parent: world, axis: [0, 0, 1], origin: {xyz: [0, 0, 0.1]}}\n"
       << "bodies:\n  - {name: link, frame: j, radius: 0.01, points: [";
  for (std::size_t i = 0; i < pts.size(); ++i)
    yaml << (i ? ", " : "") << "[" << pts[i].x() << ", " << pts[i].y() << ", " << pts[i].z() << "]";
  yaml << "]}\n  - {name: post, frame: world, radius: 0.02, points: [[1, 1, 0], [1, 1, 0.3]]}\n";
  const Model m = parseModel(yaml.str(), "budget.yaml");
  calib::Camera cam = kccd::testing::lookAt(Vec3(0.9, -0.7, 0.8), Vec3(0, 0, 0.1), 320, 240, 400.0, {0, 0, 0, 0, 0});
  const std::vector<double> q = {0.7};
  ModelView view(m, cam);
  ModelViewRequest request;
  request.state = q;
  request.colour = false;
  const ModelFrame f = view.draw(request);
  const cv::Mat drawn = f.images.mask == 1;
  // The independent silhouette of the body's own volume at its pose: the volume is convex and in
  // front of a distortion-free camera, so its outline is the convex hull of the projections of
  // its points moved by the radius in 2,000 directions, filled at 7x.
  const Pose pose = Pose(Eigen::Translation3d(0, 0, 0.1) * Eigen::AngleAxisd(0.7, Vec3::UnitZ()));
  const int k = kccd::testing::kSilhouetteScale;
  std::vector<cv::Point3d> surface;
  const double golden = 3.14159265358979 * (3.0 - std::sqrt(5.0));
  for (const Vec3& p : pts)
    for (int i = 0; i < 2000; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / 2000, s = std::sqrt(1.0 - z * z);
      const Vec3 w = pose * p + m.bodies[0].radius * Vec3(s * std::cos(golden * i), s * std::sin(golden * i), z);
      surface.emplace_back(w.x(), w.y(), w.z());
    }
  std::vector<cv::Point2d> image;
  cv::projectPoints(surface, cam.rvec, cam.tvec, cam.camera_matrix, cv::noArray(), image);
  std::vector<cv::Point> fine_pts;
  for (const cv::Point2d& p : image)  // pixel x's centre is the centre of fine pixel 7x + 3 (1/16 px units)
    fine_pts.emplace_back(cvRound((p.x * k + k / 2) * 16), cvRound((p.y * k + k / 2) * 16));
  std::vector<cv::Point> outline;
  cv::convexHull(fine_pts, outline);
  cv::Mat fine = cv::Mat::zeros(cam.height * k, cam.width * k, CV_8UC1);
  cv::fillConvexPoly(fine, outline, cv::Scalar(255), cv::LINE_8, 4);
  cv::Mat to_inside, to_outside;
  cv::distanceTransform(fine == 0, to_inside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(fine != 0, to_outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  double far = 0.0;
  int silhouette = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const int fy = y * k + k / 2, fx = x * k + k / 2;
      const bool in = fine.at<uchar>(fy, fx) != 0;
      silhouette += in;
      if ((drawn.at<uchar>(y, x) != 0) == in) continue;
      far = std::max(far, static_cast<double>((in ? to_outside : to_inside).at<float>(fy, fx)) / k);
    }
  ASSERT_GT(silhouette, 2000);
  EXPECT_LE(far, f.images.mask_edge_px + 0.15)
      << "drawn " << cv::countNonZero(drawn) << " px, silhouette " << silhouette;
  // The checker's stand-in for this body: 4 points and a larger radius, a larger silhouette.
  Checker checker(m);
  checker.query(q, q, QueryOptions{.type = QueryType::Distances});
  const SschView standin = checker.sweptVolume(0, kWorld);
  ASSERT_LE(standin.points.size(), 4u);
  Renderer renderer(cam);
  const Volume v{standin.points, standin.radius, SafetyStatus::Clear, "link"};
  const int larger = cv::countNonZero(renderer.render(std::span<const Volume>(&v, 1), Style{}, false, true).mask);
  std::cout << "body of 14 points, budget 4: drawn " << cv::countNonZero(drawn) << " px, own silhouette " << silhouette
            << " px (farthest disagreeing pixel " << far << " px), the stand-in " << larger << " px\n";
  EXPECT_GT(larger, 1.1 * silhouette);
}

// A robot standing still: a request drawn onto an image that equals the last one bit for bit
// reuses the last answer and layer. Over a run of requests (static and swept, held for a few
// frames, changed in the last bit of one value, a style changed, a query-only request and a mask
// in between) each frame onto a fresh photo is, pixel for pixel and answer for answer, what a new
// view draws for that request alone; reuse happens exactly when the request repeats.
TEST_F(ModelViewTest, ARepeatedRequestReusesTheLastAnswerAndLayer) {
  const Model& m = *model_;
  std::mt19937_64 rng(5);
  ModelView view(m, smallCamera());
  std::vector<double> q = {0.3, 0.4, 0.6}, lo = q, hi = q;
  int reused = 0, expected_reused = 0;
  ModelViewRequest last;
  bool last_onto = false;
  for (int frame = 0; frame < 36; ++frame) {
    SCOPED_TRACE("frame " + std::to_string(frame));
    const bool swept = frame >= 18;
    const int step =
        frame % 6;  // 0: moved; 1, 2: held; 3: the last bit of one value; 4: held; 5: style or request kind changed
    if (step == 0) {
      for (std::size_t i = 0; i < q.size(); ++i) q[i] += 0.2 * std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
      for (std::size_t i = 0; i < q.size(); ++i) lo[i] = q[i] - 0.05, hi[i] = q[i] + 0.08;
    }
    if (step == 3) q[1] = std::nextafter(q[1], 10.0), lo[1] = std::nextafter(lo[1], -10.0);
    ModelViewRequest request;
    request.state = q;
    if (swept) request.lower = lo, request.upper = hi;
    request.mask = false;
    request.style.legend = step != 5 || frame % 12 != 5;
    cv::Mat photo(180, 320, CV_8UC3);
    cv::randu(photo, 0, 256);
    cv::Mat onto = photo.clone();
    const bool query_only = step == 5 && frame % 12 == 11;
    if (query_only)
      request.colour = false;
    else
      request.onto = &onto;
    if (frame == 20) (void)view.draw(ModelViewRequest{.state = q, .colour = false, .mask = true});  // a mask in between
    const ModelFrame f = view.draw(request);
    // The same request to a new view: nothing to reuse.
    ModelView fresh(m, smallCamera());
    cv::Mat expected_onto = photo.clone();
    ModelViewRequest again = request;
    if (!query_only) again.onto = &expected_onto;
    const ModelFrame e = fresh.draw(again);
    EXPECT_FALSE(e.reused);
    const bool repeats = last_onto && !query_only && frame != 20 && step != 0 && step != 3 &&
                         request.style == last.style && (swept == !last.lower.empty());
    EXPECT_EQ(f.reused, repeats);
    reused += f.reused, expected_reused += repeats;
    EXPECT_TRUE(sameImage(onto, expected_onto));
    ASSERT_EQ(f.query.has_value(), e.query.has_value());
    EXPECT_EQ(f.query->min_distance, e.query->min_distance);
    EXPECT_EQ(f.query->status, e.query->status);
    EXPECT_EQ(f.status, e.status);
    EXPECT_EQ(f.distances, e.distances);
    EXPECT_EQ(f.images.visibility, e.images.visibility);
    EXPECT_EQ(f.images.drawn, e.images.drawn);
    last = request;
    last_onto = !query_only;
  }
  EXPECT_GE(reused, 12);
  EXPECT_EQ(reused, expected_reused);
}

TEST_F(ModelViewTest, BoxDrawsTheSweptVolumes) {
  const Model& m = *model_;
  const std::vector<double> lo = {-0.5, 0.0, 0.0}, hi = {0.5, 0.1, 0.2};
  ModelView view(m, smallCamera());
  ModelViewRequest request;
  request.lower = lo;
  request.upper = hi;
  request.colour = false;
  const ModelFrame f = view.draw(request);
  EXPECT_TRUE(f.images.bgra.empty());

  Checker checker(m);
  const QueryResult& r = checker.query(lo, hi, QueryOptions{.type = QueryType::Distances, .tight_volumes = true});
  Renderer renderer(smallCamera());
  const Frame expected = renderer.render(sceneVolumes(m, checker, bodyStatus(m, r)), Style{}, false, true);
  EXPECT_TRUE(sameImage(f.images.mask, expected.mask));
  EXPECT_EQ(f.images.pixels, expected.pixels);
  EXPECT_EQ(f.status, bodyStatus(m, r));
  // A swept box covers more than the static volumes at one of its corners.
  request = ModelViewRequest{};
  request.state = lo;
  request.colour = false;
  EXPECT_GT(cv::countNonZero(f.images.mask), cv::countNonZero(view.draw(request).images.mask));
}

TEST_F(ModelViewTest, WithoutAStateOnlyTheFixedBodiesAreDrawnGrey) {
  const Model& m = *model_;
  ModelView view(m, smallCamera());
  const ModelFrame f = view.draw(ModelViewRequest{});
  EXPECT_FALSE(f.query.has_value());
  EXPECT_TRUE(f.distances.empty());
  ASSERT_EQ(f.images.visibility.size(), m.bodies.size());
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    EXPECT_EQ(f.status[i], SafetyStatus::NoState);
    if (m.bodies[i].frame == kWorld) {
      EXPECT_EQ(f.images.visibility[i], Visibility::Drawn) << m.bodies[i].name;
      EXPECT_GT(f.images.pixels[i], 0) << m.bodies[i].name;
    } else {
      EXPECT_EQ(f.images.visibility[i], Visibility::Empty) << m.bodies[i].name;
      EXPECT_EQ(f.images.pixels[i], 0) << m.bodies[i].name;
    }
  }
}

TEST_F(ModelViewTest, GivenStatusesAndColoursColourTheVolumes) {
  const Model& m = *model_;
  const std::vector<double> q = {0.3, 0.4, 0.6};
  ModelView view(m, smallCamera());
  const std::vector<SafetyStatus> colliding(m.bodies.size(), SafetyStatus::Colliding);
  ModelViewRequest request;
  request.state = q;
  request.status = colliding;
  request.style.legend = false;
  const ModelFrame f = view.draw(request);
  EXPECT_EQ(f.status, colliding);
  ASSERT_TRUE(f.query.has_value());
  EXPECT_EQ(f.query->status, Status::Ok);  // the query still ran

  Checker checker(m);
  checker.query(q, q, QueryOptions{.type = QueryType::Distances, .tight_volumes = true});
  Renderer renderer(smallCamera());
  const Frame expected =
      renderer.render(staticSceneVolumes(m, checker, q, colliding), Style{.legend = false}, true, true);
  EXPECT_TRUE(sameImage(f.images.bgra, expected.bgra));

  // One colour for every body, thinner volumes: fewer pixels, and the volumes' pixels in that hue.
  const std::vector<cv::Scalar> blue(m.bodies.size(), cv::Scalar(255, 0, 0));
  request.colours = blue;
  request.radius_scale = 0.5;
  request.style.fill_alpha = 1.0;
  const ModelFrame thin = view.draw(request);
  EXPECT_LT(cv::countNonZero(thin.images.mask), cv::countNonZero(f.images.mask));
  int blue_pixels = 0, other = 0;
  for (int y = 0; y < thin.images.bgra.rows; ++y)
    for (int x = 0; x < thin.images.bgra.cols; ++x) {
      const cv::Vec4b px = thin.images.bgra.at<cv::Vec4b>(y, x);
      if (px[3] != 255) continue;  // outlines are darker, edges translucent
      (px[0] > 200 && px[1] < 60 && px[2] < 60 ? blue_pixels : other) += 1;
    }
  EXPECT_GT(blue_pixels, 500);
  EXPECT_GT(blue_pixels, 4 * other);

  request.status = std::span<const SafetyStatus>(colliding.data(), 2);
  EXPECT_THROW(view.draw(request), std::invalid_argument);
}

TEST_F(ModelViewTest, VisualsArePlacedAtTheState) {
  Model m = *model_;
  const int upper_arm = 4;
  ASSERT_EQ(m.bodies[upper_arm].name, "upper_arm");
  Visual box;
  box.frame = m.bodies[upper_arm].frame;
  box.shape = Visual::Shape::Box;
  box.size = Vec3(0.3, 0.06, 0.06);  // inside the upper arm's volume (segment 0..0.4 m along x, radius 0.055 m)
  box.origin = Pose(Eigen::Translation3d(0.2, 0, 0));
  box.colour = {0.0, 0.0, 1.0, 1.0};  // blue (RGBA)
  m.visuals.push_back(box);
  const std::vector<LoadedVisual> visuals = loadVisuals(m);
  ASSERT_EQ(visuals.size(), 1u);
  EXPECT_EQ(visuals[0].label, upper_arm + 1);           // the mask label of the body in its frame
  EXPECT_EQ(visuals[0].colour, cv::Scalar(255, 0, 0));  // BGR
  ASSERT_TRUE(visuals[0].mesh);
  EXPECT_EQ(visuals[0].mesh->triangles.size(), 12u);

  ModelView view(m, smallCamera(), RenderOptions{}, visuals);
  const std::vector<double> q = {0.3, 0.4, 0.6};
  ModelViewRequest request;
  request.state = q;
  request.volumes = false;
  request.visuals = true;
  request.colour = false;
  const ModelFrame f = view.draw(request);
  EXPECT_EQ(f.first_visual, 0u);
  ASSERT_EQ(f.images.visibility.size(), 1u);
  EXPECT_EQ(f.images.visibility[0], Visibility::Drawn);
  const int pixels = f.images.pixels[0];
  EXPECT_GT(pixels, 50);
  EXPECT_EQ(cv::countNonZero(f.images.mask == upper_arm + 1), pixels);
  EXPECT_EQ(cv::countNonZero(f.images.mask), pixels);
  // The box lies inside the upper arm's volume: within the volumes' pixels.
  request.volumes = true;
  const ModelFrame both = view.draw(request);
  EXPECT_EQ(both.first_visual, m.bodies.size());
  ASSERT_EQ(both.images.visibility.size(), m.bodies.size() + 1);
  request.visuals = false;
  const cv::Mat volumes = view.draw(request).images.mask != 0;
  EXPECT_EQ(cv::countNonZero((f.images.mask != 0) & ~volumes), 0);
  EXPECT_EQ(cv::countNonZero(both.images.mask != 0), cv::countNonZero(volumes));
  request.visuals = true;
  // Another state moves the box with its frame.
  const std::vector<double> q2 = {-0.6, 0.4, 0.6};
  request.state = q2;
  request.volumes = false;
  const ModelFrame moved = view.draw(request);
  EXPECT_GT(cv::countNonZero(moved.images.mask != f.images.mask), pixels / 2);
  // Without a state, no visuals.
  request.state = {};
  EXPECT_EQ(view.draw(request).images.visibility.size(), 0u);
}

TEST(RenderVisuals, AMeshFileThatCannotBeReadNamesTheVisual) {
  Model m = loadModel(kData + "/demo_arm.yaml");
  Visual v;
  v.shape = Visual::Shape::Mesh;
  v.mesh = "/nonexistent/kccd_part.stl";
  m.visuals.push_back(v);
  try {
    loadVisuals(m);
    FAIL() << "no error";
  } catch (const VisualError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("visuals[0]: ", 0), 0u) << what;
    EXPECT_NE(what.find("kccd_part.stl"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  // An invalid state places nothing.
  const std::vector<double> wrong = {0.1};
  m.visuals[0].shape = Visual::Shape::Sphere;
  m.visuals[0].size = Vec3(0.1, 0.1, 0.1);
  EXPECT_TRUE(visualVolumes(m, loadVisuals(m), wrong).empty());
  EXPECT_EQ(visualVolumes(m, loadVisuals(m), std::vector<double>{0.1, 0.2, 0.3}).size(), 1u);
}

}  // namespace

namespace {

// The camera `c` (fixed in the world) as a camera fixed to joint frame `frame` at state `q`: the
// same view there, moving with the frame at other states.
calib::Camera mountedAt(const Model& m, calib::Camera c, const std::string& frame, const std::vector<double>& q) {
  std::vector<Pose> poses(m.joints.size());
  EXPECT_TRUE(framePoses(m, q, poses));
  const Pose mount_to_camera = c.worldToCamera() * framePose(poses, m.jointIndex(frame));
  cv::Matx33d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = mount_to_camera.linear()(i, j);
  cv::Rodrigues(r, c.rvec);
  c.tvec = cv::Vec3d(mount_to_camera.translation().x(), mount_to_camera.translation().y(),
                     mount_to_camera.translation().z());
  c.frame = frame;
  return c;
}

}  // namespace

// A camera on the robot (Camera::frame): at the state it was placed at, the world camera's picture;
// at another state the bodies on its own link stay where they were in the picture while the world
// moves; with no state nothing is drawn; a frame the model lacks is one CameraError.
TEST_F(ModelViewTest, ACameraOnTheRobotSeesFromItsLink) {
  const Model& m = *model_;
  const std::vector<double> q = {0.3, 0.4, 0.6}, q2 = {-0.2, 0.1, 0.9};
  const calib::Camera world = smallCamera(), mounted = mountedAt(m, world, "shoulder_pitch", q);
  ModelView fixed(m, world), moving(m, mounted);
  ModelViewRequest request;
  request.state = q;
  const ModelFrame a = fixed.draw(request), b = moving.draw(request);
  // The same picture up to float rounding of the composed pose: the same labels in every pixel but a few on edges.
  ASSERT_EQ(a.images.mask.size(), b.images.mask.size());
  cv::Mat differ;
  cv::compare(a.images.mask, b.images.mask, differ, cv::CMP_NE);
  EXPECT_LT(cv::countNonZero(differ), 20);
  EXPECT_GT(cv::countNonZero(b.images.mask), 1000);
  // At q2 the upper arm (on shoulder_pitch) is where it was; the pedestal (world) is not.
  request.state = q2;
  const ModelFrame c = moving.draw(request);
  const auto labelOf = [&](const std::string& body) { return static_cast<uchar>(m.bodyIndex(body) + 1); };
  cv::Mat before, after;
  cv::compare(b.images.mask, labelOf("upper_arm"), before, cv::CMP_EQ);
  cv::compare(c.images.mask, labelOf("upper_arm"), after, cv::CMP_EQ);
  EXPECT_GT(cv::countNonZero(before), 100);
  cv::Mat moved;
  cv::bitwise_xor(before, after, moved);
  EXPECT_LT(cv::countNonZero(moved), cv::countNonZero(before) / 10);
  cv::compare(b.images.mask, labelOf("pedestal"), before, cv::CMP_EQ);
  cv::compare(c.images.mask, labelOf("pedestal"), after, cv::CMP_EQ);
  cv::bitwise_xor(before, after, moved);
  EXPECT_GT(cv::countNonZero(moved), cv::countNonZero(before) / 10);
  // No state: the camera cannot be placed, nothing is drawn.
  request.state = {};
  EXPECT_EQ(cv::countNonZero(moving.draw(request).images.mask), 0);
  calib::Camera lost = mounted;
  lost.frame = "wrist_cam";
  EXPECT_THROW(ModelView(m, lost), calib::CameraError);
  try {
    cameraFrame(m, lost, "cam.yaml");
  } catch (const calib::CameraError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cam.yaml: frame: 'wrist_cam' is neither a joint nor a body", 0), 0u)
        << e.what();
  }
  EXPECT_EQ(cameraFrame(m, mounted), m.jointIndex("shoulder_pitch"));
  calib::Camera by_body = mounted;
  by_body.frame = "upper_arm";
  EXPECT_EQ(cameraFrame(m, by_body), m.bodies[static_cast<std::size_t>(m.bodyIndex("upper_arm"))].frame);
}
