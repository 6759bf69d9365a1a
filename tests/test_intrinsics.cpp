// Camera intrinsics from views of a planar tag board (kccd::calib::calibrateIntrinsics): accuracy
// on synthetic views of a known distorted camera, outlier views, and every way it refuses.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "kccd/calib/board_views.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/calib/intrinsics.hpp"
#include "support/tag_scene.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;
using kccd::testing::renderTagScene;

constexpr double kPi = 3.14159265358979323846;

// A camera with clearly visible barrel distortion, 960 x 720.
Camera trueCamera() {
  Camera c;
  c.width = 960;
  c.height = 720;
  c.camera_matrix = cv::Matx33d(820.0, 0.0, 487.5, 0.0, 815.0, 352.0, 0.0, 0.0, 1.0);
  c.distortion = {-0.28, 0.11, 0.0008, -0.0006, -0.02};
  return c;
}

TagGrid grid() { return TagGrid{.cols = 6, .rows = 4, .tag_size = 0.04, .spacing = 0.012, .first_id = 0}; }

// The board -> camera pose of a view: the board centred at (ox, oy, dist) in the camera, facing
// it, tilted by `tilt_deg` about the in-plane axis at angle `axis_deg`, rolled by `roll_deg`.
void boardPose(const Board& board, double tilt_deg, double axis_deg, double roll_deg, cv::Vec3d at, cv::Vec3d& rvec,
               cv::Vec3d& tvec) {
  cv::Matx33d flip(1, 0, 0, 0, -1, 0, 0, 0, -1);  // board y up, z to the viewer -> camera y down, z forward
  cv::Matx33d roll, tilt;
  cv::Rodrigues(cv::Vec3d(0, 0, roll_deg * kPi / 180), roll);
  const double a = axis_deg * kPi / 180, t = tilt_deg * kPi / 180;
  cv::Rodrigues(cv::Vec3d(std::cos(a), std::sin(a), 0) * t, tilt);
  const cv::Matx33d r = tilt * flip * roll;
  cv::Vec3d centre(0, 0, 0);
  int k = 0;
  for (const Tag& tag : board.layout.tags)
    for (const auto& c : tag.corners()) centre += cv::Vec3d(c.x, c.y, c.z), ++k;
  centre /= k;
  cv::Rodrigues(r, rvec);
  tvec = at - r * centre;
}

// The board's corners seen by `camera` from a pose, inside the image, with Gaussian noise.
IntrinsicsView view(const std::string& name, const Camera& camera, const Board& board, cv::Vec3d rvec, cv::Vec3d tvec,
                    double noise_px, std::mt19937_64& rng) {
  IntrinsicsView v;
  v.name = name;
  std::normal_distribution<double> noise(0.0, noise_px);
  for (const Tag& tag : board.layout.tags) {
    const auto corners = tag.corners();
    std::vector<cv::Point3d> world(corners.begin(), corners.end());
    std::vector<cv::Point2d> pix;
    cv::projectPoints(world, rvec, tvec, camera.camera_matrix, camera.distortion, pix);
    bool inside = true;
    for (const auto& p : pix)
      inside = inside && p.x > 3 && p.y > 3 && p.x < camera.width - 4 && p.y < camera.height - 4;
    if (!inside) continue;  // a tag is detected whole or not at all
    for (int i = 0; i < 4; ++i)
      v.points.push_back({"tag" + std::to_string(tag.id) + ".c" + std::to_string(i),
                          pix[static_cast<std::size_t>(i)] + cv::Point2d(noise(rng), noise(rng)),
                          world[static_cast<std::size_t>(i)]});
  }
  return v;
}

// `n` views from random tilted poses (tilt 20..45 deg about random axes) spread over the image.
std::vector<IntrinsicsView> tiltedViews(const Camera& camera, const Board& board, int n, double noise_px,
                                        std::mt19937_64& rng, double tilt_lo = 20, double tilt_hi = 45) {
  std::uniform_real_distribution<double> tilt(tilt_lo, tilt_hi), axis(0, 360), roll(-20, 20), off(-0.12, 0.12),
      dist(0.38, 0.55);
  std::vector<IntrinsicsView> views;
  while (static_cast<int>(views.size()) < n) {
    cv::Vec3d rvec, tvec;
    const double z = dist(rng);
    boardPose(board, tilt(rng), axis(rng), roll(rng), cv::Vec3d(off(rng) * z / 0.45, off(rng) * 0.8 * z / 0.45, z),
              rvec, tvec);
    IntrinsicsView v = view("view" + std::to_string(views.size() + 1), camera, board, rvec, tvec, noise_px, rng);
    if (v.points.size() >= 40) views.push_back(std::move(v));
  }
  return views;
}

TEST(CalibGrid, IdsAndPlacesRowByRow) {
  const Board b = Board::grid(TagGrid{.cols = 3, .rows = 2, .tag_size = 0.05, .spacing = 0.01, .first_id = 7});
  ASSERT_EQ(b.layout.tags.size(), 6u);
  EXPECT_EQ(b.layout.tags[0].id, 7);
  EXPECT_EQ(b.layout.tags[5].id, 12);
  const Tag* t = b.layout.find(11);  // row 1, column 1
  ASSERT_NE(t, nullptr);
  EXPECT_NEAR(t->xyz.x(), 0.06, 1e-12);
  EXPECT_NEAR(t->xyz.y(), -0.06, 1e-12);
  EXPECT_EQ(t->xyz.z(), 0.0);
  EXPECT_EQ(t->rpy.norm(), 0.0);
  EXPECT_THROW(Board::grid(TagGrid{.cols = 1, .rows = 1, .tag_size = 0.05}), InputError);
  EXPECT_THROW(Board::grid(TagGrid{.cols = 3, .rows = 2, .tag_size = 0.0}), InputError);
  EXPECT_THROW(Board::grid(TagGrid{.cols = 3, .rows = 2, .tag_size = 0.05, .spacing = -1}), InputError);
  EXPECT_THROW(Board::grid(TagGrid{.cols = 3, .rows = 2, .tag_size = 0.05, .first_id = 584}), InputError);
}

TEST(CalibBoard, LayoutMustBeFlatAndFaceOneWay) {
  TagLayout flat;
  flat.tags = {Tag{.id = 1, .size = 0.1, .xyz = Vec3(0, 0, 1), .rpy = Vec3(kPi / 2, 0, 0)},
               Tag{.id = 2, .size = 0.1, .xyz = Vec3(0.3, 0, 1.2), .rpy = Vec3(kPi / 2, 0, 0)}};
  EXPECT_NO_THROW(Board::fromLayout(flat, "wall.yaml"));

  TagLayout bent = flat;
  bent.tags[1].xyz.y() = 0.05;  // 5 cm in front of the wall
  try {
    Board::fromLayout(bent, "bent.yaml");
    ADD_FAILURE() << "a bent layout was accepted";
  } catch (const TagLayoutError& e) {
    EXPECT_NE(std::string(e.what()).find("bent.yaml: tags: tag "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("flat"), std::string::npos) << e.what();
  }
  TagLayout flipped = flat;
  flipped.tags[1].rpy = Vec3(-kPi / 2, 0, 0);  // same plane, seen from the back
  EXPECT_THROW(Board::fromLayout(flipped, "flipped.yaml"), TagLayoutError);
  TagLayout one;
  one.tags = {flat.tags[0]};
  EXPECT_THROW(Board::fromLayout(one, "one.yaml"), TagLayoutError);
}

TEST(CalibIntrinsics, RecoversAKnownDistortedCamera) {
  std::mt19937_64 rng(20261123);
  const Camera truth = trueCamera();
  const Board board = Board::grid(grid());
  for (int trial = 0; trial < 3; ++trial) {
    const auto views = tiltedViews(truth, board, 10, 0.2, rng);
    const IntrinsicsResult r = calibrateIntrinsics(views, cv::Size(truth.width, truth.height));
    ASSERT_EQ(r.status, IntrinsicsStatus::Solved) << r.message;
    const cv::Matx33d& k = r.camera.camera_matrix;
    const cv::Matx33d& t = truth.camera_matrix;
    std::printf("trial %d: fx %.2f (%+.3f %%) fy %.2f (%+.3f %%) cx %+.2f px cy %+.2f px k1 %+.4f rms %.3f px\n", trial,
                k(0, 0), 100 * (k(0, 0) / t(0, 0) - 1), k(1, 1), 100 * (k(1, 1) / t(1, 1) - 1), k(0, 2) - t(0, 2),
                k(1, 2) - t(1, 2), r.camera.distortion[0] - truth.distortion[0], r.rms_px);
    EXPECT_NEAR(k(0, 0), t(0, 0), 0.005 * t(0, 0));
    EXPECT_NEAR(k(1, 1), t(1, 1), 0.005 * t(1, 1));
    EXPECT_NEAR(k(0, 2), t(0, 2), 2.0);
    EXPECT_NEAR(k(1, 2), t(1, 2), 2.0);
    ASSERT_EQ(r.camera.distortion.size(), 5u);
    EXPECT_NEAR(r.camera.distortion[0], truth.distortion[0], 0.02);
    EXPECT_NEAR(r.rms_px, 0.2 * std::sqrt(2.0), 0.08);  // 2-D error of 0.2 px per coordinate
    EXPECT_EQ(r.used.size(), 10u);
    EXPECT_TRUE(r.rejected.empty());
    EXPECT_EQ(r.camera.rvec, cv::Vec3d(0, 0, 0));
    EXPECT_EQ(r.camera.tvec, cv::Vec3d(0, 0, 0));
    ASSERT_TRUE(r.camera.reprojection_rms_px.has_value());
    // Honest sigmas: the errors are within a few sigma.
    EXPECT_GT(r.sigmas.fx, 0.0);
    EXPECT_LT(std::abs(k(0, 0) - t(0, 0)), 5 * r.sigmas.fx + 0.05);
    EXPECT_LT(std::abs(k(0, 2) - t(0, 2)), 5 * r.sigmas.cx + 0.05);
    ASSERT_EQ(r.views.size(), 10u);
    for (const auto& v : r.views) {
      EXPECT_TRUE(v.used);
      EXPECT_GT(v.tilt_deg, 15.0);
      EXPECT_LT(v.tilt_deg, 50.0);
      EXPECT_LT(v.rms_px, 0.6);
    }
  }
}

TEST(CalibIntrinsics, TheIntrinsicsFileWritesAndReads) {
  std::mt19937_64 rng(7);
  const Camera truth = trueCamera();
  const IntrinsicsResult r =
      calibrateIntrinsics(tiltedViews(truth, Board::grid(grid()), 8, 0.2, rng), cv::Size(960, 720));
  ASSERT_EQ(r.status, IntrinsicsStatus::Solved) << r.message;
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / ("kccd_intr_" + std::to_string(getpid()) + ".yaml")).string();
  saveCamera(r.camera, path);
  const Camera c = loadCamera(path);
  std::filesystem::remove(path);
  EXPECT_EQ(c.width, 960);
  EXPECT_EQ(c.height, 720);
  EXPECT_NEAR(c.camera_matrix(0, 0), r.camera.camera_matrix(0, 0), 1e-9);
  EXPECT_EQ(c.distortion.size(), 5u);
  EXPECT_EQ(c.rvec, cv::Vec3d(0, 0, 0));
  EXPECT_NEAR(*c.reprojection_rms_px, r.rms_px, 1e-12);
}

// The camera file of a solve: what loadCamera reads, then OpenCV's two extra fields.
TEST(CalibIntrinsics, TheCameraFileTextCarriesOpenCVsFields) {
  std::mt19937_64 rng(7);
  const IntrinsicsResult r =
      calibrateIntrinsics(tiltedViews(trueCamera(), Board::grid(grid()), 8, 0.2, rng), cv::Size(960, 720));
  ASSERT_EQ(r.status, IntrinsicsStatus::Solved) << r.message;
  const std::string text = intrinsicsCameraText(r);
  EXPECT_EQ(text.rfind(cameraText(r.camera), 0), 0u) << text;
  char rms[64];
  std::snprintf(rms, sizeof rms, "%.17g", r.rms_px);
  EXPECT_NE(text.find("\navg_reprojection_error: " + std::string(rms) + "\nnr_of_frames: 8\n"), std::string::npos)
      << text;
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / ("kccd_intr_text_" + std::to_string(getpid()) + ".yaml")).string();
  std::ofstream(path) << text;
  const Camera c = loadCamera(path);
  std::filesystem::remove(path);
  EXPECT_EQ(c.camera_matrix, r.camera.camera_matrix);
  EXPECT_EQ(c.distortion, r.camera.distortion);
}

// Board views from image files: each image's board corners where the camera sees them, the tags
// it shows that the board lacks, and an image of another size named.
TEST(CalibBoardViews, CornersOfRenderedImagesAndTheirSize) {
  const Board board = Board::grid(TagGrid{.cols = 4, .rows = 3, .tag_size = 0.04, .spacing = 0.01, .first_id = 0});
  const Board smaller = Board::grid(TagGrid{.cols = 4, .rows = 2, .tag_size = 0.04, .spacing = 0.01, .first_id = 0});
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / ("kccd_board_views_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::vector<std::string> images;
  std::vector<Camera> cameras;
  for (int i = 0; i < 2; ++i) {
    Camera c = trueCamera();
    boardPose(board, 25, 90.0 * i, 10, cv::Vec3d(0.01 * i, 0, 0.45), c.rvec, c.tvec);
    images.push_back((dir / ("view" + std::to_string(i) + ".png")).string());
    ASSERT_TRUE(cv::imwrite(images.back(), renderTagScene(c, board.layout)));
    cameras.push_back(c);
  }
  std::vector<double> progress;
  const BoardViews v = detectBoardViews(images, smaller, [&](double f) { progress.push_back(f); });
  EXPECT_EQ(progress, (std::vector<double>{0.5, 1.0}));
  EXPECT_EQ(v.image_size, cv::Size(960, 720));
  ASSERT_EQ(v.views.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(v.views[i].name, images[i]);
    EXPECT_EQ(v.tags[i], 8);  // the 4 x 2 board's tags; the third row's are not on it
    EXPECT_EQ(v.unknown_ids[i], (std::vector<int>{8, 9, 10, 11}));
    ASSERT_EQ(v.views[i].points.size(), 32u);
    for (const Correspondence& p : v.views[i].points) {
      std::vector<cv::Point2d> q;
      cv::projectPoints(std::vector<cv::Point3d>{p.world}, cameras[i].rvec, cameras[i].tvec, cameras[i].camera_matrix,
                        cameras[i].distortion, q);
      EXPECT_LT(cv::norm(p.pixel - q[0]), 0.5) << p.name;
    }
  }
  ASSERT_TRUE(cv::imwrite((dir / "small.png").string(), cv::Mat(240, 320, CV_8UC1, cv::Scalar(128))));
  images.push_back((dir / "small.png").string());
  try {
    (void)detectBoardViews(images, board);
    ADD_FAILURE() << "an image of another size was accepted";
  } catch (const ImageError& e) {
    EXPECT_EQ(std::string(e.what()), images[2] + ": image: 320x240 differs from " + images[0] +
                                         " (960x720): all images must come from one camera at one resolution");
  }
  std::filesystem::remove_all(dir);
}

TEST(CalibIntrinsics, FixedK3AndRationalModels) {
  std::mt19937_64 rng(11);
  Camera truth = trueCamera();
  truth.distortion[4] = 0.0;
  const auto views = tiltedViews(truth, Board::grid(grid()), 10, 0.2, rng);
  IntrinsicsOptions fixed;
  fixed.fix_k3 = true;
  const IntrinsicsResult a = calibrateIntrinsics(views, cv::Size(960, 720), fixed);
  ASSERT_EQ(a.status, IntrinsicsStatus::Solved) << a.message;
  ASSERT_EQ(a.camera.distortion.size(), 5u);
  EXPECT_EQ(a.camera.distortion[4], 0.0);
  EXPECT_NEAR(a.camera.camera_matrix(0, 0), 820.0, 0.005 * 820.0);
  IntrinsicsOptions rational;
  rational.rational = true;
  const IntrinsicsResult b = calibrateIntrinsics(views, cv::Size(960, 720), rational);
  EXPECT_EQ(b.camera.distortion.size(), 8u) << b.message;
  IntrinsicsOptions both = fixed;
  both.rational = true;
  EXPECT_THROW(calibrateIntrinsics(views, cv::Size(960, 720), both), InputError);
}

TEST(CalibIntrinsics, AnOutlierViewIsLeftOutAndNamed) {
  std::mt19937_64 rng(3);
  const Camera truth = trueCamera();
  auto views = tiltedViews(truth, Board::grid(grid()), 8, 0.2, rng);
  // The fourth image's corners were detected in a different camera (or the board moved): 4 px noise.
  std::normal_distribution<double> bad(0.0, 4.0);
  for (auto& p : views[3].points) p.pixel += cv::Point2d(bad(rng), bad(rng));
  const IntrinsicsResult r = calibrateIntrinsics(views, cv::Size(960, 720));
  ASSERT_EQ(r.status, IntrinsicsStatus::Solved) << r.message;
  ASSERT_EQ(r.rejected.size(), 1u);
  EXPECT_EQ(r.rejected[0], "view4");
  EXPECT_FALSE(r.views[3].used);
  EXPECT_NE(r.views[3].note.find("outlier"), std::string::npos);
  EXPECT_GT(r.views[3].rms_px, 3.0);
  EXPECT_EQ(r.used.size(), 7u);
  EXPECT_NEAR(r.camera.camera_matrix(0, 0), 820.0, 0.005 * 820.0);
}

TEST(CalibIntrinsics, TooFewViews) {
  std::mt19937_64 rng(5);
  const Camera truth = trueCamera();
  const Board board = Board::grid(grid());
  auto views = tiltedViews(truth, board, 2, 0.2, rng);
  IntrinsicsResult r = calibrateIntrinsics(views, cv::Size(960, 720));
  EXPECT_EQ(r.status, IntrinsicsStatus::TooFewViews);
  EXPECT_NE(r.message.find("2 usable views"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("add images"), std::string::npos) << r.message;
  // A view with one tag (4 corners) does not count, and is named among the rejected.
  IntrinsicsView one = tiltedViews(truth, board, 1, 0.2, rng)[0];
  one.name = "one_tag.png";
  one.points.resize(4);
  views.push_back(one);
  r = calibrateIntrinsics(views, cv::Size(960, 720));
  EXPECT_EQ(r.status, IntrinsicsStatus::TooFewViews);
  ASSERT_EQ(r.rejected.size(), 1u);
  EXPECT_EQ(r.rejected[0], "one_tag.png");
  EXPECT_NE(r.views[2].note.find("only 4 board corners"), std::string::npos) << r.views[2].note;
  EXPECT_EQ(calibrateIntrinsics({}, cv::Size(960, 720)).status, IntrinsicsStatus::TooFewViews);
}

TEST(CalibIntrinsics, FaceOnViewsOnlyAreRefused) {
  std::mt19937_64 rng(9);
  const Camera truth = trueCamera();
  const auto views = tiltedViews(truth, Board::grid(grid()), 8, 0.2, rng, 0.0, 5.0);
  const IntrinsicsResult r = calibrateIntrinsics(views, cv::Size(960, 720));
  EXPECT_EQ(r.status, IntrinsicsStatus::FrontoParallel);
  EXPECT_NE(r.message.find("tilt the board"), std::string::npos) << r.message;
  for (const auto& v : r.views) EXPECT_LT(v.tilt_deg, 10.0) << v.name;
}

TEST(CalibIntrinsics, NonPlanarPointsAreRefused) {
  std::mt19937_64 rng(13);
  const Camera truth = trueCamera();
  // A "board" whose second half stands 10 cm in front of the first: seen from tilted poses.
  Board board = Board::grid(grid());
  for (Tag& t : board.layout.tags)
    if (t.xyz.x() > 0.12) t.xyz.z() = 0.1;
  const auto views = tiltedViews(truth, board, 8, 0.2, rng);
  const IntrinsicsResult r = calibrateIntrinsics(views, cv::Size(960, 720));
  EXPECT_EQ(r.status, IntrinsicsStatus::NotPlanar);
  EXPECT_NE(r.message.find("flat board"), std::string::npos) << r.message;
}

TEST(CalibIntrinsics, FewWeakViewsAreIllConditioned) {
  std::mt19937_64 rng(17);
  const Camera truth = trueCamera();
  // Three small, far, slightly tilted boards in the image centre: the focal length is barely observable.
  const Board board = Board::grid(TagGrid{.cols = 2, .rows = 1, .tag_size = 0.03, .spacing = 0.01});
  std::vector<IntrinsicsView> views;
  const double axes[] = {0, 120, 240};
  for (int i = 0; i < 3; ++i) {
    cv::Vec3d rvec, tvec;
    boardPose(board, 12, axes[i], 0, cv::Vec3d(0.01 * i, 0, 1.5), rvec, tvec);
    views.push_back(view("v" + std::to_string(i), truth, board, rvec, tvec, 0.2, rng));
  }
  const IntrinsicsResult r = calibrateIntrinsics(views, cv::Size(960, 720));
  EXPECT_EQ(r.status, IntrinsicsStatus::IllConditioned) << r.message;
  EXPECT_NE(r.message.find("add images"), std::string::npos) << r.message;
  // Four larger boards, but all tilted about one axis by 12 deg, far away: still too weak.
  const Board wide = Board::grid(TagGrid{.cols = 3, .rows = 2, .tag_size = 0.04, .spacing = 0.01});
  views.clear();
  for (int i = 0; i < 4; ++i) {
    cv::Vec3d rvec, tvec;
    boardPose(wide, 12, 90, 0, cv::Vec3d(0.02 * i, 0.01 * i, 2.0), rvec, tvec);
    views.push_back(view("w" + std::to_string(i), truth, wide, rvec, tvec, 0.2, rng));
  }
  const IntrinsicsResult w = calibrateIntrinsics(views, cv::Size(960, 720));
  EXPECT_EQ(w.status, IntrinsicsStatus::IllConditioned) << w.message;
}

TEST(CalibIntrinsics, UnusableInputThrows) {
  std::mt19937_64 rng(19);
  const Camera truth = trueCamera();
  auto views = tiltedViews(truth, Board::grid(grid()), 3, 0.2, rng);
  EXPECT_THROW(calibrateIntrinsics(views, cv::Size(0, 720)), InputError);
  EXPECT_THROW(calibrateIntrinsics(views, cv::Size(9000, 720)), InputError);
  auto twice = views;
  twice[1].name = twice[0].name;
  EXPECT_THROW(calibrateIntrinsics(twice, cv::Size(960, 720)), InputError);
  auto nan = views;
  nan[2].points[3].pixel.x = std::nan("");
  EXPECT_THROW(calibrateIntrinsics(nan, cv::Size(960, 720)), InputError);
  auto dup = views;
  dup[0].points[1].name = dup[0].points[0].name;
  EXPECT_THROW(calibrateIntrinsics(dup, cv::Size(960, 720)), InputError);
}

}  // namespace
