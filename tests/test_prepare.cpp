// The CPU half of a frame (kccd/render/prepare.hpp) with no GL context at all (ctest runs this
// program with KCCD_GL=none, so any attempt to make one would fail): how each kind of volume is
// seen, meshes from the cache, silhouettes and outlines against the sphere's true image, and
// clipping planes that clip nothing drawn.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "kccd/render/gl_context.hpp"
#include "kccd/render/prepare.hpp"
#include "support/cameras.hpp"

namespace {

using namespace kccd;
using namespace kccd::render;

constexpr double kFocal = 300.0;

// 320 x 240, f = 300 px (fy 1 % more), no distortion, at x = 3 looking at the origin (the
// camera's z is -x).
Camera camera() { return kccd::testing::lookAt(Vec3(3, 0, 0), Vec3(0, 0, 0), 320, 240, kFocal, {0, 0, 0, 0, 0}); }

// The area of a polygon given by camera-space vertices, in normalised image coordinates (x/z, y/z).
double projectedArea(const std::vector<Vec3>& loop) {
  double twice = 0.0;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec3& a = loop[k];
    const Vec3& b = loop[(k + 1) % loop.size()];
    twice += (a.x() / a.z()) * (b.y() / b.z()) - (b.x() / b.z()) * (a.y() / a.z());
  }
  return std::abs(twice) / 2.0;
}

// The image of a ball of radius r whose centre is d in front of the camera on its axis: a disc
// of radius r / sqrt(d^2 - r^2) in normalised image coordinates.
double discRadius(double r, double d) { return r / std::sqrt(d * d - r * r); }
double discArea(double r, double d) { return std::numbers::pi * discRadius(r, d) * discRadius(r, d); }

// The environment this program runs in (KCCD_GL=none) has no GL: whatever passes below needed none.
TEST(RenderPrepare, RunsWhereNoGlContextCanBeMade) {
  const char* env = std::getenv("KCCD_GL");
  if (env == nullptr || std::string(env) != "none") GTEST_SKIP() << "run through ctest (KCCD_GL=none)";
  EXPECT_THROW(GlContext::make(), GlContextError);
}

TEST(RenderPrepare, SortsEveryKindOfVolume) {
  const Projection projection(camera());
  FramePreparer preparer(projection, projection, RenderOptions{});
  const std::vector<Vec3> centre = {Vec3(0, 0, 0)};
  const std::vector<Vec3> nan = {Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0)};
  const std::vector<Vec3> behind = {Vec3(6, 0, 0)};
  const std::vector<Vec3> far_away = {Vec3(-2e6, 0, 0)};
  const std::vector<Vec3> at_camera = {Vec3(3, 0, 0)};
  const Volume volumes[] = {
      {centre, 0.2, SafetyStatus::Clear, "ball"},  {{}, 0.2, SafetyStatus::Clear, "empty"},
      {nan, 0.2, SafetyStatus::Clear, "nan"},      {behind, 0.5, SafetyStatus::Clear, "behind"},
      {far_away, 0.5, SafetyStatus::Clear, "far"}, {at_camera, 0.5, SafetyStatus::Colliding, "around"},
  };
  const PreparedFrame f = preparer.prepare(volumes, PrepareNeeds{.outlines = true, .meshes = false});
  ASSERT_EQ(f.frame.visibility.size(), 6u);
  EXPECT_EQ(f.frame.visibility[0], Visibility::Drawn);
  EXPECT_EQ(f.frame.visibility[1], Visibility::Empty);
  EXPECT_EQ(f.frame.visibility[2], Visibility::NotFinite);
  EXPECT_EQ(f.frame.visibility[3], Visibility::BehindCamera);
  EXPECT_EQ(f.frame.visibility[4], Visibility::BeyondFar);
  EXPECT_EQ(f.frame.visibility[5], Visibility::FillsView);
  // The ball is drawn from its outline alone (no mesh asked for, none built).
  const PreparedVolume& ball = f.volumes[0];
  EXPECT_TRUE(ball.outlined());
  EXPECT_FALSE(ball.mesh);
  EXPECT_EQ(f.frame.outlines, 1);
  EXPECT_EQ(f.frame.meshes_built, 0);
  EXPECT_EQ(preparer.meshCache().size(), 0u);
  const std::size_t n = ball.outline_2d.size();
  ASSERT_GE(n, 3u);
  EXPECT_EQ(ball.outline_lines.size(), 2 * n);
  EXPECT_EQ(ball.outline_fill.size(), 3 * (n - 2));
  EXPECT_EQ(ball.colour, statusColour(SafetyStatus::Clear));
  EXPECT_NEAR(ball.depth, 3.0, 1e-9);
  // The outline contains the ball's image and lies at most the tolerance (0.5 px) outside it.
  std::vector<Vec3> corners;
  for (std::size_t k = 0; k < n; ++k)
    corners.emplace_back(ball.outline_vertices[3 * k], ball.outline_vertices[3 * k + 1],
                         ball.outline_vertices[3 * k + 2]);
  const double outside = discRadius(0.2, 3.0) + 0.5 / kFocal;  // half a pixel more
  EXPECT_GE(projectedArea(corners), discArea(0.2, 3.0) * (1.0 - 1e-6));
  EXPECT_LE(projectedArea(corners), std::numbers::pi * outside * outside);
  // The volume around the camera fills the view, in its status colour; the others are not drawn.
  EXPECT_TRUE(f.volumes[5].fills);
  EXPECT_EQ(f.volumes[5].colour, statusColour(SafetyStatus::Colliding));
  for (const int i : {1, 2, 3, 4, 5}) EXPECT_FALSE(f.volumes[static_cast<std::size_t>(i)].drawn()) << i;
  // Labels: index + 1 unless given.
  for (int i = 0; i < 6; ++i) EXPECT_EQ(f.volumes[static_cast<std::size_t>(i)].label, i + 1);
}

TEST(RenderPrepare, MeshesComeFromTheCacheAndTheirSilhouetteIsTheSphereImage) {
  const Projection projection(camera());
  FramePreparer preparer(projection, projection, RenderOptions{});
  const std::vector<Vec3> centre = {Vec3(0, 0, 0)};
  const Volume ball[] = {{centre, 0.2, SafetyStatus::WithinMargin, "ball"}};
  const PreparedFrame first = preparer.prepare(ball, PrepareNeeds{.outlines = false, .meshes = true});
  const PreparedVolume& p = first.volumes[0];
  ASSERT_TRUE(p.mesh);
  EXPECT_FALSE(p.outlined());
  EXPECT_EQ(first.frame.meshes_built, 1);
  EXPECT_EQ(first.frame.max_level, p.level);
  EXPECT_EQ(first.frame.triangles, static_cast<int>(p.mesh->triangles.size()));
  ASSERT_EQ(p.vertices.size(), 3 * p.mesh->vertices.size());
  // The silhouette is one loop, filled by loop - 2 triangles, and its image is the ball's disc
  // (the mesh lies outside the ball by at most the tessellation's tolerance).
  ASSERT_GE(p.silhouette.size(), 3u);
  EXPECT_EQ(p.fill.size(), 3 * (p.silhouette.size() - 2));
  EXPECT_EQ(p.outline.size(), 2 * p.silhouette.size());
  std::vector<Vec3> loop;
  for (const std::uint32_t k : p.silhouette)
    loop.emplace_back(p.vertices[3 * k], p.vertices[3 * k + 1], p.vertices[3 * k + 2]);
  const double disc = discArea(0.2, 3.0);
  EXPECT_GT(projectedArea(loop), disc);
  EXPECT_LT(projectedArea(loop), disc * 1.02);
  // The same volume again: its mesh comes from the cache.
  const PreparedFrame second = preparer.prepare(ball, PrepareNeeds{.outlines = false, .meshes = true});
  EXPECT_EQ(second.frame.meshes_built, 0);
  EXPECT_EQ(second.volumes[0].mesh, p.mesh);
  EXPECT_EQ(preparer.meshCache().built(), 1u);
  EXPECT_EQ(preparer.meshCache().reused(), 1u);
}

TEST(RenderPrepare, ClippingPlanesClipNothingDrawn) {
  const Projection projection(camera());
  RenderOptions options;
  FramePreparer preparer(projection, projection, options);
  const std::vector<Vec3> near_point = {Vec3(3 - 0.03, 0, 0)};  // 3 cm in front of the camera
  const std::vector<Vec3> far_point = {Vec3(-150, 0, 0)};       // 153 m in front
  const Volume volumes[] = {{near_point, 0.01, SafetyStatus::Clear, "near"},
                            {far_point, 1.0, SafetyStatus::Clear, "far"}};
  const PreparedFrame f = preparer.prepare(volumes, PrepareNeeds{.outlines = false, .meshes = true});
  ASSERT_EQ(f.frame.visibility[0], Visibility::Drawn);
  ASSERT_EQ(f.frame.visibility[1], Visibility::Drawn);
  EXPECT_LT(f.frame.near, options.near);
  EXPECT_GT(f.frame.near, 0.0);
  EXPECT_LE(f.frame.near, f.volumes[0].clearance);
  EXPECT_GT(f.frame.far, options.far);
  EXPECT_GE(f.frame.far, f.volumes[1].reach);
  // Every mesh vertex lies between the planes.
  for (const PreparedVolume& p : f.volumes)
    for (std::size_t k = 0; k < p.vertices.size(); k += 3) {
      EXPECT_GT(p.vertices[k + 2], f.frame.near);
      EXPECT_LT(p.vertices[k + 2], f.frame.far);
    }
  EXPECT_LT(f.volumes[0].depth, f.volumes[1].depth);
}

TEST(RenderPrepare, SurfacesAreDrawnAsGiven) {
  const Projection projection(camera());
  FramePreparer preparer(projection, projection, RenderOptions{});
  // A triangle 1 m in front of the camera, facing it, and one behind it.
  const std::vector<Vec3> soup = {Vec3(2, -0.1, -0.1), Vec3(2, 0.1, -0.1), Vec3(2, 0, 0.1)};
  const auto mesh = std::make_shared<const Mesh>(surfaceMesh(soup));
  Volume front;
  front.surface = mesh;
  front.mask_label = 300;  // clamped to 255
  Volume back = front;
  back.pose = Pose(Eigen::Translation3d(3, 0, 0));  // at x = 5: behind the camera
  back.mask_label = 0;
  const Volume volumes[] = {front, back};
  const PreparedFrame f = preparer.prepare(volumes, PrepareNeeds{});
  EXPECT_EQ(f.frame.visibility[0], Visibility::Drawn);
  EXPECT_EQ(f.frame.visibility[1], Visibility::BehindCamera);
  const PreparedVolume& p = f.volumes[0];
  EXPECT_TRUE(p.surface);
  EXPECT_EQ(p.mesh, mesh);
  EXPECT_EQ(p.label, 255);
  EXPECT_EQ(f.volumes[1].label, 0);
  // It comes no nearer than the plane x = 2 (1 m away) and not much farther than its corners.
  EXPECT_GT(p.clearance, 0.99 * 0.999);
  EXPECT_LE(p.clearance, 1.0);
  EXPECT_NEAR(p.reach, Vec3(1, 0.1, 0.1).norm(), 1e-6);
  EXPECT_EQ(f.frame.meshes_built, 0);  // surfaces are not SSCH meshes
}

}  // namespace
