// Local maps on real Kinect data (7-Scenes RedKitchen from ../shared/data; skipped when absent).
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/local_map/ellipsoid_filter.h"
#include "mapping/local_map/local_map_integrator.h"
#include "mapping/sequence/sequence.h"
#include "tests/support/local_map_oracle.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

Sequence openKitchen(const std::filesystem::path& dir, int first, int last) {
  SequenceOptions options;
  options.frames = {first, last};
  return Sequence::open(dir, options);
}

// 30 frames into one keyframe: the kept ellipsoid means reproject into frame 30's depth with a
// median |dz| under 1 cm (the data's README: frame 0's raw depth against frame 30 gives ~7 mm,
// the poses being KinectFusion's; averaging must not make it worse than 1 cm).
TEST(LocalMapRealData, ThirtyFramesReprojectIntoFrame30) {
  VDMAP_REQUIRE_SHARED_DATA(dir, "7scenes-redkitchen");
  const Sequence seq = openKitchen(dir, 0, 31);
  ASSERT_EQ(seq.size(), 31u);
  const PinholeCamera& cam = seq.camera();
  KeyframeContainer container(cam, 5);
  LocalMapIntegrator integrator;
  const Transform T_W_K = seq.entries()[0].T_W_C;
  for (std::size_t i = 0; i < 30; ++i) integrator.integrateFrame(seq.load(i), cam, T_W_K, &container, nullptr);
  const RgbdFrame f30 = seq.load(30);
  const Transform T_C_W = f30.T_W_C.inverse();
  std::vector<double> dz;
  const auto kept = keptEllipsoids(container, FilterParams{}, T_W_K, 0);
  for (const Ellipsoid& e : kept) {
    const Eigen::Vector3d p = T_C_W * e.mean;
    if (p.z() <= 0.1) continue;
    const Eigen::Vector2d uv = cam.project(p);
    if (!cam.inImage(uv.x(), uv.y())) continue;
    const std::uint16_t raw = f30.depth.at<std::uint16_t>(int(std::lround(uv.y())), int(std::lround(uv.x())));
    if (raw == 0) continue;
    dz.push_back(std::abs(raw / cam.depth_scale - p.z()));
  }
  ASSERT_GT(dz.size(), kept.size() / 2);
  std::nth_element(dz.begin(), dz.begin() + dz.size() / 2, dz.end());
  const double median = dz[dz.size() / 2];
  RecordProperty("median_dz_mm", std::to_string(median * 1000));
  std::printf("kept %zu of %zu ellipsoids, %zu reprojected, median |dz| %.2f mm\n", kept.size(), container.size(),
              dz.size(), median * 1000);
  EXPECT_LT(median, 0.01);
}

// The fast integrator equals the slow per-point reference on real frames (holes, edges, a
// moving camera): same cells and counts, statistics within float storage precision.
TEST(LocalMapRealData, FastIntegratorEqualsReference) {
  VDMAP_REQUIRE_SHARED_DATA(dir, "7scenes-redkitchen");
  const Sequence seq = openKitchen(dir, 0, 6);
  const PinholeCamera& cam = seq.camera();
  KeyframeContainer container(cam, 5);
  test::ReferenceMap reference;
  LocalMapIntegrator integrator;
  const Transform T_W_K = seq.entries()[0].T_W_C;
  for (std::size_t i = 0; i < seq.size(); i += 5) {  // frames 0 and 5
    const RgbdFrame f = seq.load(i);
    integrator.integrateFrame(f, cam, T_W_K, &container, nullptr);
    reference.integrate(f, cam, T_W_K, container);
  }
  ASSERT_EQ(container.size(), reference.points.size());
  int bad = 0;
  for (const StoredCell& c : container.cells()) {
    const CellStats ref = reference.stats(c.grid_index);
    const CellStats got = c.toStats();
    // Tolerances as in test_local_map FastIntegratorEqualsReference (float storage; depths
    // below 5 m here, so 3e-7 m per coordinate; batch-mean shifts below 5 cm).
    bad += got.n != ref.n || (got.mean - ref.mean).norm() > 2e-6 ||
           (got.scatter - ref.scatter).norm() > 1e-5 * ref.scatter.norm() + 3e-8 * ref.n;
  }
  EXPECT_EQ(bad, 0);
}

}  // namespace
}  // namespace vdmap
