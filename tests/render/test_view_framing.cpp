// Where a view's camera is (render/view_framing.h), the same for the window and `vdmap render`.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "mapping/files/map_file.h"
#include "render/map_scene.h"
#include "render/view_framing.h"
#include "tests/support/test_util.h"

namespace vdmap::render {
namespace {

Transform cameraAt(const Eigen::Vector3d& t, double yaw = 0.0) {
  Transform T = Transform::Identity();
  // Camera looking along +y with image-down -z (x right): a level camera in a z-up world.
  Eigen::Matrix3d R;
  R << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R;
  T.translation() = t;
  return T;
}

glm::vec2 project(const ViewCamera& v, const glm::vec3& p) {
  const glm::vec4 q = v.T_C_W * glm::vec4(p, 1.f);
  return {v.fx * q.x / q.z + v.cx, v.fy * q.y / q.z + v.cy};
}

TEST(ViewFraming, TheDefaultViewFramesTheRobustBoxAndEveryCameraAtTheViewsAspect) {
  // 1000 means in a 2 x 1 x 0.5 m box and 10 strays 20 m away; two keyframes and a trajectory.
  std::vector<glm::vec3> means;
  for (int i = 0; i < 1000; ++i)
    means.emplace_back(2.f * (i % 10) / 9.f, 1.f * ((i / 10) % 10) / 9.f, 0.5f * (i / 100) / 9.f);
  for (int i = 0; i < 10; ++i) means.emplace_back(20.f, 20.f, 20.f);
  GraphScene graph;
  graph.camera = PinholeCamera{};
  graph.keyframes = {cameraAt({-1, -1, 1}), cameraAt({3, -1, 1})};
  graph.trajectory = {cameraAt({1, -2, 1.2})};
  const auto [lo, hi] = frameBounds(means, graph);
  EXPECT_LT(hi.x, 10.f) << "the strays are not framed";
  EXPECT_LE(lo.y, -2.f) << "the trajectory's camera is framed";
  EXPECT_LE(lo.x, -1.f);
  EXPECT_GE(hi.x, 3.f);
  for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{480, 640}}) {
    ViewSpec spec;
    ViewScene scene;
    scene.bounds = {lo, hi};
    const FramedView v = viewCamera(spec, scene, w, h);
    EXPECT_EQ(v.image, (PixelRect{0, 0, w, h}));
    // Every corner of the box is inside the image, and the box spans most of its narrow side.
    glm::vec2 a(INFINITY), b(-INFINITY);
    for (int c = 0; c < 8; ++c) {
      const glm::vec2 p = project(v.camera, {(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
      a = glm::min(a, p), b = glm::max(b, p);
    }
    EXPECT_GE(a.x, 0.f) << w << "x" << h;
    EXPECT_GE(a.y, 0.f) << w << "x" << h;
    EXPECT_LE(b.x, w) << w << "x" << h;
    EXPECT_LE(b.y, h) << w << "x" << h;
    EXPECT_GT(std::max((b.x - a.x) / w, (b.y - a.y) / h), 0.6f) << w << "x" << h;
    // It is the window's default view: OrbitCamera::framing at the image's aspect.
    const ViewCamera window = OrbitCamera::framing(lo, hi, {0, 0, 1}, float(w) / h).view(w, h);
    EXPECT_EQ(v.camera.T_C_W, window.T_C_W);
    EXPECT_EQ(v.camera.fx, window.fx);
  }
}

Ellipsoid ellipsoidAt(const glm::vec3& m, const glm::vec3& sd) {
  Ellipsoid e;
  e.mean = {m.x, m.y, m.z};
  e.cov = Eigen::Vector3d(sd.x * sd.x, sd.y * sd.y, sd.z * sd.z).asDiagonal();
  return e;
}

// 500 small ellipsoids in a 2 x 1 x 0.5 m box.
std::vector<Ellipsoid> boxMap() {
  std::vector<Ellipsoid> map;
  for (int i = 0; i < 500; ++i)
    map.push_back(
        ellipsoidAt({2.f * (i % 10) / 9.f, 1.f * ((i / 10) % 10) / 9.f, 0.5f * (i / 100) / 4.f}, glm::vec3(0.01f)));
  return map;
}

// The projected box of the 8 corners of [lo, hi] in `v`.
std::pair<glm::vec2, glm::vec2> projectedBox(const ViewCamera& v, const glm::vec3& lo, const glm::vec3& hi) {
  glm::vec2 a(INFINITY), b(-INFINITY);
  for (int c = 0; c < 8; ++c) {
    const glm::vec2 p = project(v, {(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
    a = glm::min(a, p), b = glm::max(b, p);
  }
  return {a, b};
}

TEST(ViewFraming, FramesEveryDrawnExtentAtSigma) {
  // Long thin ellipsoids at a corner of the map: their means are inside the map's box, their
  // surfaces at 2 sigma reach 1.2 m beyond it (the old frame cut them).
  std::vector<Ellipsoid> map = boxMap();
  for (int i = 0; i < 5; ++i) map.push_back(ellipsoidAt({2.f, 1.f, 0.5f}, {0.6f, 0.02f, 0.02f}));
  map.push_back(ellipsoidAt({0.f, 0.f, 0.f}, {0.02f, 0.02f, 0.5f}));
  const float sigma = 2.f;
  const DrawnBounds drawn = drawnBounds(map, sigma, DrawMode::kEllipsoids);
  EXPECT_EQ(drawn.drawn, map.size());
  EXPECT_EQ(drawn.strays, 0u);
  EXPECT_NEAR(drawn.hi.x, 2.f + 1.2f, 1e-4f);
  EXPECT_NEAR(drawn.lo.z, -1.f, 1e-4f);
  // Centres mode frames the centres only.
  const DrawnBounds centres = drawnBounds(map, sigma, DrawMode::kCentres);
  EXPECT_NEAR(centres.hi.x, 2.f, 1e-4f);
  EXPECT_TRUE(drawnBounds(map, sigma, DrawMode::kNone).empty) << "a hidden map frames nothing";
  for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{480, 640}})
    for (const float azimuth : {-60.f, 20.f, 135.f}) {
      ViewSpec spec;
      spec.orbit = Orbit{azimuth, 35.f, std::nullopt};
      ViewScene scene;
      scene.bounds = frameBounds(drawn, GraphScene{});
      const ViewCamera v = viewCamera(spec, scene, w, h).camera;
      for (const Ellipsoid& e : map) {
        const glm::vec3 m(e.mean.x(), e.mean.y(), e.mean.z());
        const glm::vec3 half =
            sigma * glm::vec3(std::sqrt(e.cov(0, 0)), std::sqrt(e.cov(1, 1)), std::sqrt(e.cov(2, 2)));
        const auto [a, b] = projectedBox(v, m - half, m + half);
        ASSERT_TRUE(a.x >= 0.f && a.y >= 0.f && b.x <= w && b.y <= h)
            << w << "x" << h << " azimuth " << azimuth << ": (" << a.x << ", " << a.y << ")-(" << b.x << ", " << b.y
            << ")";
      }
    }
}

TEST(ViewFraming, FitUsesTheViewNotABoundingSphere) {
  // A flat, wide box fills the view on its limiting axis (the bounding sphere filled ~22 %).
  const glm::vec3 lo(-2.f, -0.5f, 0.f), hi(2.f, 0.5f, 0.2f);
  for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{752, 870}, std::pair{480, 640}})
    for (const float pitch : {10.f, 35.f, 80.f}) {
      OrbitCamera cam = OrbitCamera::framing(lo, hi, {0, 0, 1}, float(w) / h);
      cam.pitch = glm::radians(pitch);
      cam.fit(lo, hi, float(w) / h);
      const auto [a, b] = projectedBox(cam.view(w, h), lo, hi);
      EXPECT_TRUE(a.x >= 0.f && a.y >= 0.f && b.x <= w && b.y <= h) << w << "x" << h << " pitch " << pitch;
      EXPECT_GE(std::max((b.x - a.x) / w, (b.y - a.y) / h), 0.9f) << w << "x" << h << " pitch " << pitch;
      // Centred: the margins on the limiting axis are equal within a pixel or two.
      if ((b.x - a.x) / w > (b.y - a.y) / h) EXPECT_NEAR(a.x, w - b.x, 2.f) << w << "x" << h;
      else EXPECT_NEAR(a.y, h - b.y, 2.f) << w << "x" << h;
    }
}

TEST(ViewFraming, ARoomTurnedAboutUpIsBoxedAlongItsWalls) {
  // A 4 x 2 m floor turned 30 degrees about +z: boxed along its walls, the box is 4 x 2, not the
  // 4.5 x 3.7 m of the world axes.
  std::vector<Ellipsoid> map;
  const float t = glm::radians(30.f);
  for (int i = 0; i < 41; ++i)
    for (int j = 0; j < 21; ++j) {
      const float x = 0.1f * i - 2.f, y = 0.1f * j - 1.f;
      map.push_back(
          ellipsoidAt({std::cos(t) * x - std::sin(t) * y, std::sin(t) * x + std::cos(t) * y, 0.f}, glm::vec3(0.01f)));
    }
  const glm::mat3 axes = frameAxes(map, {0, 0, 1});
  EXPECT_NEAR(glm::length(axes[2] - glm::vec3(0, 0, 1)), 0.f, 1e-6f);
  const DrawnBounds drawn = drawnBounds(map, 2.f, DrawMode::kEllipsoids, {}, {}, axes);
  const glm::vec3 size = drawn.hi - drawn.lo;
  EXPECT_NEAR(size.x * size.y, 4.04f * 2.04f, 0.2f);
  // Every centre lies in the turned box.
  for (const Ellipsoid& e : map) {
    const glm::vec3 q = glm::transpose(axes) * glm::vec3(e.mean.x(), e.mean.y(), e.mean.z());
    EXPECT_TRUE(glm::all(glm::greaterThanEqual(q, drawn.lo - 1e-4f)) &&
                glm::all(glm::lessThanEqual(q, drawn.hi + 1e-4f)));
  }
}

TEST(ViewFraming, StraysBeyondTheDiagonalAreCountedNotFramed) {
  std::vector<Ellipsoid> map = boxMap();
  for (int i = 0; i < 10; ++i) map.push_back(ellipsoidAt({20.f, 20.f, 20.f}, glm::vec3(0.01f)));
  map.push_back(ellipsoidAt({2.5f, 1.f, 0.5f}, glm::vec3(0.01f)));  // near the box: framed
  const DrawnBounds drawn = drawnBounds(map, 2.f, DrawMode::kEllipsoids);
  EXPECT_EQ(drawn.strays, 10u);
  EXPECT_EQ(drawn.drawn, map.size() - 10);
  EXPECT_LT(drawn.hi.x, 3.f);
  EXPECT_GE(drawn.hi.x, 2.5f);
}

TEST(ViewFraming, ASliceFramesOnlyWhatItKeeps) {
  // Two floors 3 m apart: a slice of the upper one frames only it.
  std::vector<Ellipsoid> map;
  for (int i = 0; i < 200; ++i) map.push_back(ellipsoidAt({0.01f * i, 0.f, (i % 2) * 3.f}, glm::vec3(0.01f)));
  const HeightFrame frame = heightFrame(map, {0, 0, 1});
  EXPECT_NEAR(frame.floor_m, 0.f, 1e-6f);
  const DrawnBounds upper = drawnBounds(map, 2.f, DrawMode::kEllipsoids, HeightSlice{true, 2.f, 4.f}, frame);
  EXPECT_EQ(upper.drawn, 100u);
  EXPECT_NEAR(upper.lo.z, 3.f - 0.02f, 1e-4f);
}

TEST(ViewCamera, UnprojectInvertsProjection) {
  const ViewCamera v = ViewCamera::lookAt({1, -2, 1.5f}, {0, 0, 0.3f}, {0, 0, 1}, 55.f, 640, 360);
  for (const glm::vec3 p : {glm::vec3(0, 0, 0.3f), glm::vec3(0.4f, 0.2f, -0.1f), glm::vec3(-0.3f, 0.5f, 0.8f)}) {
    const glm::vec4 clip = v.viewProjection() * glm::vec4(p, 1.f);
    const float depth01 = 0.5f * (clip.z / clip.w) + 0.5f;
    const glm::vec2 px = project(v, p);
    const auto back = unproject(v, px.x, px.y, depth01);
    ASSERT_TRUE(back);
    EXPECT_NEAR(glm::length(*back - p), 0.f, 1e-3f);
  }
  EXPECT_FALSE(unproject(v, 10, 10, 1.f)) << "the cleared depth is no surface";
}

TEST(ViewFraming, UpFromDataMatchesTheWindowsBeforeTheMove) {
  // The window's up vector was estimateUp of every mapped camera and the map, or the axis named.
  std::vector<Transform> cameras;
  for (int i = 0; i < 20; ++i) cameras.push_back(cameraAt({0.1 * i, 0, 1.5}, 0.2 * i));
  std::vector<Ellipsoid> floor;
  for (int i = 0; i < 400; ++i) {
    Ellipsoid e;
    e.mean = {0.05 * (i % 20), 0.05 * (i / 20), 0.01 * ((i * 7) % 3)};
    floor.push_back(e);
  }
  EXPECT_EQ(upDirection(UpAxis::kData, cameras, floor), estimateUp(cameras, floor));
  EXPECT_NEAR(upDirection(UpAxis::kData, cameras, floor).z, 1.f, 1e-3f);
  EXPECT_EQ(upDirection(UpAxis::kPlusZ, cameras, floor), glm::vec3(0, 0, 1));
  EXPECT_EQ(upDirection(UpAxis::kPlusY, {}, {}), glm::vec3(0, 1, 0));
  EXPECT_EQ(upDirection(UpAxis::kMinusY, {}, {}), glm::vec3(0, -1, 0));
  EXPECT_EQ(upDirection(UpAxis::kData, {}, {}), glm::vec3(0, 0, 1)) << "no cameras: +z";
}

// The 7-Scenes kitchen mapped by `vdmap map --octomap`: its ellipsoid PLY and OctoMap have no
// cameras, and stand on their level planes as the map folder does on its cameras and floor.
TEST(ViewFraming, TheSevenScenesKitchensMapFilesStandUprightWithoutCameras) {
  VDMAP_REQUIRE_SHARED_DATA(data, "7scenes-redkitchen");
  test::TempDir dir;
  const test::RunResult map = test::runVdmap("map '" + data.string() + "' --frames 0:250 --octomap 0.05 --out '" +
                                             (dir / "map").string() + "'");
  ASSERT_EQ(map.exit_code, 0) << map.err;
  const StaticMap folder = loadStaticMap((dir / "map").string());
  std::vector<Transform> cameras;
  for (const StampedPose& p : folder.trajectory) cameras.push_back(p.T_W_C);
  UpFrom from = UpFrom::kDefault;
  const glm::vec3 reference = estimateUp(cameras, folder.ellipsoids, &from);
  ASSERT_EQ(from, UpFrom::kCameras);
  EXPECT_LT(glm::degrees(std::acos(std::min(1.f, -reference.y))), 35.f) << "7-Scenes' up is about -y";
  for (const char* file : {"global_ellipsoids.ply", "global.bt"}) {
    const StaticMap m = loadStaticMap((dir / "map" / file).string());
    ASSERT_TRUE(m.trajectory.empty() && m.keyframes.empty()) << file;
    const glm::vec3 up = estimateUp({}, m.ellipsoids, &from);
    EXPECT_EQ(from, UpFrom::kLevelPlanes) << file;
    const float error = glm::degrees(std::acos(std::clamp(glm::dot(up, reference), -1.f, 1.f)));
    std::printf("%s: up (%.3f, %.3f, %.3f), %.2f degrees from the map folder's (%.3f, %.3f, %.3f)\n", file, up.x, up.y,
                up.z, error, reference.x, reference.y, reference.z);
    EXPECT_LT(error, 5.f) << file;
  }
}

// Orthographic: parallel rays. Points along the viewing direction land on one pixel (to a
// tenth of a pixel over 2 m of depth), and the target's plane has the perspective view's scale.
TEST(OrbitCamera, TheOrthographicViewHasParallelRaysAndThePerspectiveScaleAtTheTarget) {
  const glm::vec3 eye(4.f, -3.f, 2.f), target(0.5f, 0.2f, 0.3f), up(0, 0, 1);
  const ViewCamera persp = ViewCamera::lookAt(eye, target, up, 50.f, 800, 600);
  const ViewCamera ortho = ViewCamera::lookAt(eye, target, up, 50.f, 800, 600, true);
  const glm::vec3 f = glm::normalize(target - eye), side(0.3f, 0.4f, 0.5f);
  for (const float depth : {-1.f, 0.f, 1.f}) {
    const glm::vec2 a = project(ortho, target + depth * f), b = project(ortho, target + side + depth * f);
    // Float rounding of an eye 1000 times further away: a few hundredths of a pixel.
    EXPECT_NEAR(glm::length(a - glm::vec2(399.5f, 299.5f)), 0.f, 0.05f);
    const glm::vec2 b0 = project(ortho, target + side);
    EXPECT_NEAR(glm::length(b - b0), 0.f, 0.1f) << "depth " << depth;
  }
  // At the target's depth both views agree (to a hundredth of a pixel off the view axis).
  const glm::vec3 q = target + glm::vec3(0.2f, -0.1f, 0.25f) - glm::dot(glm::vec3(0.2f, -0.1f, 0.25f), f) * f;
  EXPECT_NEAR(glm::length(project(ortho, q) - project(persp, q)), 0.f, 0.02f);
  // fit() holds a box's corners inside the orthographic image too.
  OrbitCamera cam = OrbitCamera::fromLookAt(eye, target, up, 50.f);
  cam.orthographic = true;
  const FrameBox box(glm::vec3(-1.f, -2.f, 0.f), glm::vec3(3.f, 1.f, 2.5f));
  cam.fit(box, 800.f / 600.f);
  const ViewCamera v = cam.view(800, 600);
  float lo = 1e9f, hi = -1e9f;
  for (int c = 0; c < 8; ++c) {
    const glm::vec2 p = project(v, box.corner(c));
    EXPECT_GE(p.x, -0.5f);
    EXPECT_LE(p.x, 799.5f);
    EXPECT_GE(p.y, -0.5f);
    EXPECT_LE(p.y, 599.5f);
    lo = std::min({lo, p.x / 800.f, p.y / 600.f});
    hi = std::max({hi, p.x / 800.f, p.y / 600.f});
  }
  EXPECT_LT(lo, 0.05f) << "the box fills the view (margin 3 %)";
  EXPECT_GT(hi, 0.95f);
}

// Trackball: the view turns about its own axes, past the orbit's 89-degree limit, and may roll;
// distance and target stay.
TEST(OrbitCamera, TheTrackballTurnsPastThePoleAndRolls) {
  OrbitCamera cam = OrbitCamera::fromLookAt({3.f, 0.f, 1.f}, {0.f, 0.f, 0.f}, {0, 0, 1}, 60.f);
  const float distance = cam.distance_m;
  for (int i = 0; i < 10; ++i) cam.tumble(0.f, 0.3f);  // 3 radians over the top
  EXPECT_NEAR(cam.distance_m, distance, 1e-4f);
  EXPECT_NEAR(glm::length(cam.target), 0.f, 1e-6f);
  // Turned by 3 rad about the image's right axis (the y axis here): the eye is behind the target
  // and upside down, where an orbit would stop at 89 degrees.
  const glm::vec3 dir = glm::normalize(cam.eye() - cam.target);
  EXPECT_NEAR(dir.x, std::cos(std::atan2(1.f, 3.f) + 3.f), 1e-3f);
  EXPECT_LT(cam.imageUp().z, 0.f) << "past the pole the image's up points down";
  OrbitCamera orbit = OrbitCamera::fromLookAt({3.f, 0.f, 1.f}, {0.f, 0.f, 0.f}, {0, 0, 1}, 60.f);
  for (int i = 0; i < 10; ++i) orbit.orbit(0.f, 0.3f);
  EXPECT_NEAR(orbit.pitch, glm::radians(89.f), 1e-5f);
}

// The presets look along the map's axes: from above (89 degrees, h2 up in the image), level along
// h2 (front) and along -h1 (side), about the same target at the same distance.
TEST(OrbitCamera, PresetsLookAlongTheMapsAxes) {
  const glm::vec3 h1 = glm::normalize(glm::vec3(1.f, 1.f, 0.f)), h2 = glm::normalize(glm::vec3(-1.f, 1.f, 0.f));
  const glm::mat3 axes(h1, h2, glm::vec3(0, 0, 1));
  OrbitCamera cam = OrbitCamera::fromLookAt({3.f, -1.f, 2.f}, {0.5f, 0.5f, 0.5f}, {0, 0, 1}, 60.f);
  cam.orthographic = true;
  const float distance = cam.distance_m;
  const auto forward = [&cam] { return glm::normalize(cam.target - cam.eye()); };
  presetView(cam, ViewPreset::kTop, axes);
  EXPECT_NEAR(glm::dot(forward(), glm::vec3(0, 0, -1)), std::sin(glm::radians(89.f)), 1e-4f);
  EXPECT_GT(glm::dot(cam.imageUp(), h2), 0.99f);
  EXPECT_TRUE(cam.orthographic);
  EXPECT_NEAR(cam.distance_m, distance, 1e-4f);
  presetView(cam, ViewPreset::kFront, axes);
  EXPECT_GT(glm::dot(forward(), h2), 0.9999f);
  presetView(cam, ViewPreset::kSide, axes);
  EXPECT_GT(glm::dot(forward(), -h1), 0.9999f);
  EXPECT_NEAR(glm::length(cam.target - glm::vec3(0.5f)), 0.f, 1e-5f);
}

TEST(OrbitCamera, FromLookAtReproducesEyeAndTarget) {
  for (const glm::vec3 up : {glm::vec3(0, 0, 1), glm::vec3(0, -0.9f, -0.45f), glm::vec3(1, 0, 0)}) {
    const glm::vec3 eye(1.5f, -2.f, 0.7f), target(0.2f, 0.3f, -0.1f);
    const OrbitCamera cam = OrbitCamera::fromLookAt(eye, target, up, 50.f);
    EXPECT_NEAR(glm::length(cam.eye() - eye), 0.f, 1e-5f) << up.x << up.y << up.z;
    EXPECT_EQ(cam.target, target);
    EXPECT_EQ(cam.fov_y_deg, 50.f);
    EXPECT_NEAR(cam.distance_m, glm::length(eye - target), 1e-6f);
  }
  // The default view's eye gives the default angles back.
  const OrbitCamera framed = OrbitCamera::framing({-1, -1, 0}, {1, 1, 1}, {0, 0, 1}, 16.f / 9.f);
  const OrbitCamera back = OrbitCamera::fromLookAt(framed.eye(), framed.target, framed.up);
  EXPECT_NEAR(back.yaw, framed.yaw, 1e-5f);
  EXPECT_NEAR(back.pitch, framed.pitch, 1e-5f);
  // Straight down the up axis the pitch is clamped to 89 degrees.
  const OrbitCamera down = OrbitCamera::fromLookAt({0, 0, 5}, {0, 0, 0}, {0, 0, 1});
  EXPECT_NEAR(down.pitch, glm::radians(89.f), 1e-5f);
}

TEST(ViewFraming, AnOrbitOfTheDefaultAnglesIsTheDefaultViewAndALookAtIsDrawnAsGiven) {
  ViewScene scene;
  scene.bounds = {glm::vec3(-1, -2, 0), glm::vec3(2, 1, 1.5f)};
  scene.up = glm::normalize(glm::vec3(0.1f, -0.9f, -0.4f));
  ViewSpec spec;
  const ViewCamera framed = viewCamera(spec, scene, 640, 360).camera;
  spec.orbit = Orbit{-60.f, 35.f, std::nullopt};
  EXPECT_EQ(viewCamera(spec, scene, 640, 360).camera.T_C_W, framed.T_C_W);
  spec.orbit = Orbit{30.f, 35.f, std::nullopt};
  EXPECT_NE(viewCamera(spec, scene, 640, 360).camera.T_C_W, framed.T_C_W);
  spec.orbit.reset();
  spec.look_at = LookAt{{3, 3, 3}, {0, 0, 0}, {0, 0, 1}, 40.f};
  EXPECT_EQ(viewCamera(spec, scene, 640, 360).camera.T_C_W,
            ViewCamera::lookAt({3, 3, 3}, {0, 0, 0}, {0, 0, 1}, 40.f, 640, 360).T_C_W);
}

TEST(ViewFraming, AKeyframeViewIsTheKeyframesCameraLetterboxed) {
  ViewScene scene;
  scene.camera = PinholeCamera{};  // 640 x 480
  ViewSpec spec;
  spec.kind = ViewKind::kKeyframe;
  const FramedView own = viewCamera(spec, scene, scene.camera.width, scene.camera.height);
  EXPECT_EQ(own.image, (PixelRect{0, 0, scene.camera.width, scene.camera.height}));
  const FramedView wide = viewCamera(spec, scene, 1280, 720);
  EXPECT_EQ(wide.image, letterbox(1280, 720, scene.camera.width, scene.camera.height));
  EXPECT_EQ(wide.camera.width, wide.image.width);
}

}  // namespace
}  // namespace vdmap::render
