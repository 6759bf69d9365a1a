// Golden images: the demo arm through a 320x180 version of the sample camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/checker.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "support/golden.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;
using namespace kccd::calib;

const std::string kData = KCCD_DATA_DIR;

// ---------------------------------------------------------------------------------------------
// Golden images: the demo arm through a 320x180 version of the sample camera.

Camera goldenCamera() {
  Camera c = loadCamera(kData + "/demo_camera.yaml");
  const double s = 1.0 / 4.0;
  c.width = 320;
  c.height = 180;
  c.camera_matrix(0, 0) *= s;
  c.camera_matrix(1, 1) *= s;
  c.camera_matrix(0, 2) = (c.camera_matrix(0, 2) + 0.5) * s - 0.5;
  c.camera_matrix(1, 2) = (c.camera_matrix(1, 2) + 0.5) * s - 0.5;
  return c;
}

class RenderGolden : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    model_ = new Model(loadModel(kData + "/demo_arm.yaml"));
    renderer_ = new Renderer(goldenCamera());
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete model_;
  }
  Frame draw(const std::vector<double>& lower, const std::vector<double>& upper, const Style& style) {
    Checker checker(*model_);
    const QueryResult& q = checker.query(lower, upper, QueryOptions{.type = QueryType::Distances});
    EXPECT_EQ(q.status, Status::Ok);
    const std::vector<Volume> volumes = sceneVolumes(*model_, checker, bodyStatus(*model_, q));
    return renderer_->render(volumes, style);
  }
  static Model* model_;
  static Renderer* renderer_;
};
Model* RenderGolden::model_ = nullptr;
Renderer* RenderGolden::renderer_ = nullptr;

const kccd::testing::GoldenTolerance kMaskTolerance{0, 0.0025, 4};

TEST_F(RenderGolden, DemoArmStatic) {
  const Frame f = draw({0.3, 0.4, 0.6}, {0.3, 0.4, 0.6}, Style{.labels = false, .legend = false});
  EXPECT_TRUE(kccd::testing::compareGolden(f.bgra, "demo_static_rgba", renderer_->rendererString()));
  EXPECT_TRUE(kccd::testing::compareGolden(f.mask, "demo_static_mask", renderer_->rendererString(), kMaskTolerance));
}

TEST_F(RenderGolden, DemoArmSwept) {
  const Frame f = draw({-0.5, 0.0, 0.0}, {0.5, 0.1, 0.2}, Style{.labels = true, .legend = true});
  EXPECT_TRUE(kccd::testing::compareGolden(f.bgra, "demo_swept_rgba", renderer_->rendererString()));
  EXPECT_TRUE(kccd::testing::compareGolden(f.mask, "demo_swept_mask", renderer_->rendererString(), kMaskTolerance));
}

// Static frames place each body's own (cached) mesh with its pose: the same pixels as meshes
// built from the checker's world volumes, and no mesh rebuilt when only the state changes.
TEST_F(RenderGolden, StaticFramesReuseBodyMeshes) {
  for (const std::vector<double>& q : {std::vector<double>{0.3, 0.4, 0.6}, std::vector<double>{-0.7, 0.2, 1.1}}) {
    Checker checker(*model_);
    const QueryResult& r = checker.query(q, q, QueryOptions{.type = QueryType::Distances});
    const std::vector<Volume> world = sceneVolumes(*model_, checker, bodyStatus(*model_, r));
    const std::vector<Volume> posed = staticSceneVolumes(*model_, checker, q, bodyStatus(*model_, r));
    const Frame a = renderer_->render(world, Style{}, false, true);
    const Frame b = renderer_->render(posed, Style{}, false, true);
    // The sphere polytopes are turned with the body, so only edge pixels may differ (both
    // meshes contain the true volume and lie at most tolerance_px outside it).
    EXPECT_LE(cv::countNonZero(a.mask != b.mask), 0.01 * cv::countNonZero(a.mask));
    EXPECT_GT(cv::countNonZero(a.mask), 1000);
  }
  // A small motion (same tessellation levels): posed meshes all come from the cache, world
  // meshes of the moving bodies are rebuilt.
  auto frame = [&](const std::vector<double>& q, bool posed) {
    Checker checker(*model_);
    const QueryResult& r = checker.query(q, q, QueryOptions{.type = QueryType::Distances});
    const std::vector<Volume> v = posed ? staticSceneVolumes(*model_, checker, q, bodyStatus(*model_, r))
                                        : sceneVolumes(*model_, checker, bodyStatus(*model_, r));
    return renderer_->render(v, Style{}, false, true);
  };
  frame({0.1, -0.3, 0.9}, true);
  const int b2 = frame({0.1001, -0.3001, 0.9001}, true).meshes_built;
  frame({0.1, -0.3, 0.9}, false);
  const int b4 = frame({0.1001, -0.3001, 0.9001}, false).meshes_built;
  EXPECT_EQ(b2, 0);
  EXPECT_GT(b4, 0);
}

// Both GL back ends draw the same pixels here (llvmpipe under EGL surfaceless and under OSMesa):
// colour layers and masks bit for bit, static and swept.
TEST(RenderBackends, EglAndOsMesaAreBitIdentical) {
  if (!compiledIn(GlBackend::Egl) || !compiledIn(GlBackend::OsMesa)) GTEST_SKIP() << "this build has one GL back end";
  const Model model = loadModel(kData + "/demo_arm.yaml");
  const char* saved = std::getenv("KCCD_GL");
  const std::string restore = saved == nullptr ? "" : saved;
  std::vector<Frame> frames[2];
  std::string names[2];
  for (const int b : {0, 1}) {
    ::setenv("KCCD_GL", b == 0 ? "egl" : "osmesa", 1);
    Renderer r(goldenCamera());
    names[b] = r.rendererString();
    for (const auto& [lo, hi] : {std::pair<std::vector<double>, std::vector<double>>{{0.3, 0.4, 0.6}, {0.3, 0.4, 0.6}},
                                 {{-0.5, 0.0, 0.0}, {0.5, 0.1, 0.2}}}) {
      Checker checker(model);
      const QueryResult& q = checker.query(lo, hi, QueryOptions{.type = QueryType::Distances});
      const std::vector<Volume> volumes = sceneVolumes(model, checker, bodyStatus(model, q));
      frames[b].push_back(r.render(volumes, Style{.labels = true}));
      frames[b].push_back(r.render(volumes, Style{.shaded = true}, true, false));
    }
  }
  if (saved == nullptr)
    ::unsetenv("KCCD_GL");
  else
    ::setenv("KCCD_GL", restore.c_str(), 1);
  EXPECT_NE(names[0].find("EGL"), std::string::npos) << names[0];
  EXPECT_NE(names[1].find("OSMesa"), std::string::npos) << names[1];
  ASSERT_EQ(frames[0].size(), frames[1].size());
  for (std::size_t i = 0; i < frames[0].size(); ++i) {
    const Frame &a = frames[0][i], &b = frames[1][i];
    EXPECT_EQ(cv::norm(a.bgra, b.bgra, cv::NORM_INF), 0.0) << "colour " << i;
    if (!a.mask.empty()) {
      EXPECT_EQ(cv::norm(a.mask, b.mask, cv::NORM_INF), 0.0) << "mask " << i;
    }
    EXPECT_GT(cv::countNonZero(a.bgra.reshape(1) > 0), 1000) << i;
  }
}

}  // namespace
