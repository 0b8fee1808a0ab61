// Map exports (docs/method.md 11) through exportMap: every file written into one folder, each PLY
// reads back to the values written, and a folder that cannot be written fails cleanly.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <random>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "mapping/core/atomic_file.h"
#include "mapping/core/temporary_paths.h"
#include "mapping/files/map_export.h"
#include "mapping/files/octomap_export.h"
#include "mapping/files/ply_reader.h"
#include "mapping/files/ply_writer.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/json_text.h"
#include "tests/support/box_room_keyframes.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;

const PinholeCamera kCamera = cameraPreset("tum-default");

// Two neighbouring keyframes looking at the same wall of the box room, and their global map.
struct TwoViews {
  KeyframeGraph graph;
  GlobalMapParams params;
  GlobalMap map;
  TwoViews() {
    test::addBoxRoomKeyframe(&graph, kCamera, test::lookAt({0, 0, 0}, {0, 0, 2}), test::lookAt({0, 0, 0}, {0, 0, 2}));
    const Transform T = test::lookAt({0.3, 0, 0.2}, {0.5, 0.2, 2});
    test::addBoxRoomKeyframe(&graph, kCamera, T, T);
    graph.edges().strengthen(0, 1, 0.6);
    map = buildGlobalMap(graph, params);
  }
};

std::vector<std::string> filesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(Export, WritesEveryFileAndTheEllipsoidPlyReadsBack) {
  const TwoViews scene;
  ASSERT_GT(scene.map.ellipsoids.size(), 100u);
  test::TempDir tmp;
  MapExportOptions options;
  options.run_stats = {{"frames", 2}};
  const nlohmann::json stats = exportMap(tmp / "out", scene.graph, scene.map, options);
  EXPECT_EQ(filesIn(tmp / "out"),
            (std::vector<std::string>{"global_ellipsoids.ply", "global_gaussians.ply", "global_points.ply", "graph.txt",
                                      "keyframes.txt", "local_maps.ply", "stats.json"}));
  EXPECT_EQ(stats["frames"], 2);
  EXPECT_EQ(stats["sigma_e_prime"], scene.map.sigma_e_prime);

  const std::vector<EllipsoidRecord> back = readPlyEllipsoids(tmp / "out" / "global_ellipsoids.ply");
  ASSERT_EQ(back.size(), scene.map.ellipsoids.size());
  for (std::size_t i = 0; i < back.size(); ++i) {
    const Ellipsoid& e = scene.map.ellipsoids[i];
    // Stored as float: equal to the double rounded to float, exactly (the covariance as made
    // positive semi-definite by storedCovariance, which only rounds the others).
    ASSERT_EQ(back[i].mean, e.mean.cast<float>());
    ASSERT_EQ(back[i].cov, storedCovariance(e.cov));
    ASSERT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(back[i].cov.cast<double>()).eigenvalues()(0), 0.0) << i;
    ASSERT_EQ(back[i].count, e.count);
    ASSERT_EQ(back[i].keyframe, e.keyframe);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(back[i].rgb[k], static_cast<int>(std::lround(e.color(k))));
  }

  // local_maps.ply: every keyframe's ellipsoids as the filter selects them, in the world frame.
  std::vector<Ellipsoid> local;
  for (const Keyframe& k : scene.graph.keyframes())
    for (const Ellipsoid& e : keptEllipsoids(k.container, scene.params.filter, k.T_W_K, k.id)) local.push_back(e);
  EXPECT_EQ(local.size(), scene.map.sigma_e);
  const std::vector<EllipsoidRecord> local_back = readPlyEllipsoids(tmp / "out" / "local_maps.ply");
  ASSERT_EQ(local_back.size(), local.size());
  for (std::size_t i = 0; i < local.size(); ++i) {
    ASSERT_EQ(local_back[i].mean, local[i].mean.cast<float>());
    ASSERT_EQ(local_back[i].keyframe, local[i].keyframe);
  }
}

TEST(Export, PointPlyReadsBack) {
  const TwoViews scene;
  test::TempDir tmp;
  writePointPly(tmp / "p.ply", scene.map.ellipsoids);
  const PlyVertexTable t = readPlyVertices(tmp / "p.ply");
  ASSERT_EQ(t.names, (std::vector<std::string>{"x", "y", "z", "red", "green", "blue"}));
  ASSERT_EQ(t.count, scene.map.ellipsoids.size());
  for (std::size_t i = 0; i < t.count; ++i) {
    const Ellipsoid& e = scene.map.ellipsoids[i];
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(t.at(i, k), static_cast<float>(e.mean(k)));
      ASSERT_EQ(t.at(i, 3 + k), std::lround(e.color(k)));
    }
  }
}

// 3DGS rebuilds Sigma = R S S^T R^T from the normalised quaternion and S = diag(exp(scale)).
TEST(Export, GaussianScaleAndRotationReproduceTheCovariance) {
  const TwoViews scene;
  std::vector<Ellipsoid> ellipsoids = scene.map.ellipsoids;
  Ellipsoid skew;  // a long, tilted, non-axis-aligned one as well, and a flat one
  skew.mean = {1, 2, 3};
  const Eigen::Matrix3d R0 = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  skew.cov = R0 * Eigen::Vector3d(0.04, 1e-4, 1e-6).asDiagonal() * R0.transpose();
  skew.color = {255, 0, 128};
  ellipsoids.push_back(skew);
  test::TempDir tmp;
  writeGaussianPly(tmp / "g.ply", ellipsoids);
  const PlyVertexTable t = readPlyVertices(tmp / "g.ply");
  ASSERT_EQ(t.count, ellipsoids.size());
  // The reference 3DGS loader's full property list, in its order: it asserts 45 f_rest at its
  // default degree 3 (it refused a file with none).
  std::vector<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (int k = 0; k < 45; ++k) names.push_back("f_rest_" + std::to_string(k));
  for (const char* n : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    names.push_back(n);
  ASSERT_EQ(t.names, names);
  const int x = t.column("x"), f_dc = t.column("f_dc_0"), opacity = t.column("opacity"), scale = t.column("scale_0"),
            rot = t.column("rot_0"), nx = t.column("nx"), f_rest = t.column("f_rest_0");
  for (std::size_t i = 0; i < t.count; ++i) {
    const Ellipsoid& e = ellipsoids[i];
    const Eigen::Quaterniond q = Eigen::Quaterniond(t.at(i, rot), t.at(i, rot + 1), t.at(i, rot + 2), t.at(i, rot + 3));
    ASSERT_NEAR(q.norm(), 1.0, 1e-6);
    const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
    Eigen::Vector3d sigma2;
    for (int k = 0; k < 3; ++k) sigma2(k) = std::exp(2.0 * t.at(i, scale + k));
    const Eigen::Matrix3d cov = R * sigma2.asDiagonal() * R.transpose();
    // Float storage: ~1e-7 relative on the axes and the angles, so 1e-5 of the largest
    // eigenvalue; plus the clamp of a degenerate axis at kGaussianMinSigma.
    const double tol = 1e-5 * e.cov.norm() + kGaussianMinSigma * kGaussianMinSigma;
    ASSERT_LT((cov - e.cov).cwiseAbs().maxCoeff(), tol) << i << "\n" << cov << "\n" << e.cov;
    const Eigen::Vector3d normal(t.at(i, nx), t.at(i, nx + 1), t.at(i, nx + 2));
    ASSERT_NEAR(normal.norm(), 1.0, 1e-6);
    ASSERT_LE(normal.dot(e.cov * normal), sigma2.minCoeff() * (1 + 1e-4) + tol) << "normal: the flattest axis";
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(t.at(i, x + k), static_cast<float>(e.mean(k)));
      ASSERT_NEAR(t.at(i, f_dc + k), (e.color(k) / 255.0 - 0.5) / 0.28209479, 1e-6);
    }
    ASSERT_NEAR(1.0 / (1.0 + std::exp(-t.at(i, opacity))), 0.9, 1e-6);
    for (int k = 0; k < 45; ++k) ASSERT_EQ(t.at(i, f_rest + k), 0.0);
  }
}

TEST(Export, OctomapOpensWithLiboctomapAndItsOccupiedVoxelsContainTheMeans) {
  const TwoViews scene;
  test::TempDir tmp;
  MapExportOptions options;
  options.octomap_resolution_m = 0.05;
  std::vector<std::size_t> progress;  // one call per keyframe scan, counting up to the total
  options.octomap_progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(total, scene.graph.size());
    progress.push_back(done);
  };
  const nlohmann::json stats = exportMap(tmp / "out", scene.graph, scene.map, options);
  EXPECT_EQ(progress, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(stats["octomap"]["points"], 7 * scene.map.ellipsoids.size());
  EXPECT_EQ(stats["octomap"]["means_occupied"], 1.0);
  octomap::OcTree tree((tmp / "out" / "global.bt").string());
  ASSERT_EQ(tree.getResolution(), 0.05);
  ASSERT_GT(tree.getNumLeafNodes(), 0u);
  std::size_t occupied = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) occupied += tree.isNodeOccupied(*it);
  EXPECT_EQ(stats["octomap"]["occupied_leaves"], occupied);
  for (const Ellipsoid& e : scene.map.ellipsoids) {
    const octomap::OcTreeNode* node = tree.search(e.mean.x(), e.mean.y(), e.mean.z());
    ASSERT_TRUE(node && tree.isNodeOccupied(node)) << e.mean.transpose();
  }
  // The camera centres are free: the rays carved them.
  for (const Keyframe& k : scene.graph.keyframes()) {
    const Eigen::Vector3d c = k.T_W_K.translation();
    const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
    ASSERT_TRUE(node && !tree.isNodeOccupied(node));
  }
  MapExportOptions negative;
  negative.octomap_resolution_m = -1.0;
  EXPECT_THROW(exportMap(tmp / "bad", scene.graph, scene.map, negative), std::invalid_argument);
  EXPECT_FALSE(fs::exists(tmp / "bad"));
}

TEST(Export, EllipsoidSamplePointsAreTheSigmaPoints) {
  Ellipsoid e;
  e.mean = {1, 2, 3};
  e.cov = Eigen::Vector3d(0.01, 0.04, 0.0).asDiagonal();
  const std::vector<Eigen::Vector3d> p = ellipsoidSamplePoints(e);
  ASSERT_EQ(p.size(), 7u);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& x : p) mean += x / 7.0;
  for (const auto& x : p) scatter += (x - e.mean) * (x - e.mean).transpose();
  EXPECT_LT((mean - e.mean).norm(), 1e-12);
  EXPECT_LT((scatter / 2.0 - e.cov).norm(), 1e-12) << "+-1 sigma along each axis: scatter = 2 Sigma";
}

TEST(Export, AFolderThatCannotBeWrittenFailsClearlyAndWritesNothing) {
  const TwoViews scene;
  test::TempDir tmp;
  test::writeText(tmp / "file", "not a folder\n");
  for (const fs::path& dir : {tmp / "file", tmp / "file" / "sub"}) {
    try {
      exportMap(dir, scene.graph, scene.map);
      ADD_FAILURE() << "no error for " << dir;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
    }
    EXPECT_THROW(checkExportFolder(dir), std::runtime_error);
  }
  // A file that cannot be replaced (a folder of its name is in the way): no file of this export
  // appears, earlier files stay as they were.
  fs::create_directories(tmp / "out" / "stats.json" / "x");
  test::writeText(tmp / "out" / "graph.txt", "old\n");
  EXPECT_THROW(exportMap(tmp / "out", scene.graph, scene.map), std::runtime_error);
  EXPECT_EQ(filesIn(tmp / "out"), (std::vector<std::string>{"graph.txt", "stats.json"}));
  EXPECT_EQ(test::readFile(tmp / "out" / "graph.txt"), "old\n");
}

// A value the files cannot hold (inf, NaN, or a double beyond float32's range) fails the export
// before anything is written: vdmap's own readers would refuse the files. Valid input never gets
// here (input poses are bounded), so the maps are made so by hand.
TEST(Export, AMapWithAValueTheFilesCannotHoldIsNotExported) {
  const TwoViews scene;
  test::TempDir tmp;
  GlobalMap far = scene.map;
  ASSERT_GT(far.ellipsoids.size(), 3u);
  far.ellipsoids[3].mean.x() = 1e39;  // finite as a double, inf as a float
  try {
    exportMap(tmp / "out", scene.graph, far);
    ADD_FAILURE() << "exported a map with a mean beyond float range";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("out: nothing exported: global-map ellipsoid 3 (keyframe"), std::string::npos)
        << e.what();
  }
  GlobalMap nan = scene.map;
  nan.ellipsoids[0].cov(1, 2) = std::nan("");
  EXPECT_THROW(exportMap(tmp / "out", scene.graph, nan), std::runtime_error);
  MapExportOptions options;
  options.trajectory = {{0.0, Transform::Identity()}, {0.1, Transform::Identity()}};
  options.trajectory[1].T_W_C.translation().y() = INFINITY;
  try {
    exportMap(tmp / "out", scene.graph, scene.map, options);
    ADD_FAILURE() << "exported a non-finite trajectory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nothing exported: trajectory pose 1 is not finite"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(tmp / "out")) << "a refused export creates nothing";
  // The trajectory writer refuses on its own too (bench writes trajectories directly).
  EXPECT_THROW(writeTumTrajectory(tmp / "t.txt", options.trajectory, "test"), std::runtime_error);
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

// What the caller does before the export is put in place (vdmap map saves its session there)
// can fail the export: nothing of it appears and earlier files stay as they were.
TEST(Export, AFailureBeforeTheCommitLeavesNoExport) {
  const TwoViews scene;
  test::TempDir tmp;
  MapExportOptions options;
  options.before_commit = [] { throw std::runtime_error("s.vdmap: cannot write (No space left on device)"); };
  EXPECT_THROW(exportMap(tmp / "new", scene.graph, scene.map, options), std::runtime_error);
  EXPECT_FALSE(fs::exists(tmp / "new"));
  test::writeText(tmp / "old" / "graph.txt", "old\n");
  EXPECT_THROW(exportMap(tmp / "old", scene.graph, scene.map, options), std::runtime_error);
  EXPECT_EQ(filesIn(tmp / "old"), std::vector<std::string>{"graph.txt"});
  EXPECT_EQ(test::readFile(tmp / "old" / "graph.txt"), "old\n");
}

// vdmap map --save on a disk that fills up while the session is written (a file-size limit
// stands in for the full disk): the run fails and keeps no export of its own.
TEST(Export, MapWhoseSessionSaveFailsKeepsNoExport) {
  test::TempDir tmp;
  // Noise images (incompressible, in the session) of a flat wall in large cells (few ellipsoids,
  // in the export): the session is the largest file the run writes.
  test::writeTinySequence(tmp / "seq", 6, 160, 120);
  const std::string map =
      "map '" + (tmp / "seq").string() + "' --cell-size 16 --save '" + (tmp / "s.vdmap").string() + "' --out ";
  ASSERT_EQ(test::runVdmap(map + "'" + (tmp / "whole").string() + "'").exit_code, 0);
  std::uintmax_t largest_export = 0;
  for (const auto& entry : fs::directory_iterator(tmp / "whole"))
    largest_export = std::max(largest_export, entry.file_size());
  const std::uintmax_t session = fs::file_size(tmp / "s.vdmap");
  ASSERT_LT(largest_export + 1024, session) << "the limit must fall between the export files and the session";
  fs::remove(tmp / "s.vdmap");
  // dash's ulimit -f counts 512-byte blocks; with SIGXFSZ ignored a write past it fails (EFBIG).
  const std::string limit = "trap '' XFSZ; ulimit -f " + std::to_string((largest_export + session) / 2 / 512) + ";";
  const test::RunResult r = test::runVdmap(map + "'" + (tmp / "out").string() + "'", limit);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("s.vdmap: cannot write"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp / "out")) << "a run whose save failed keeps no export";
  EXPECT_FALSE(fs::exists(tmp / "s.vdmap"));
}

// info --json on a folder whose name is not UTF-8 (Latin-1 'é') prints JSON, the name's byte as U+FFFD.
TEST(Export, InfoJsonOnAFolderWhoseNameIsNotUtf8) {
  test::TempDir tmp;
  const fs::path seq = tmp / "caf\xe9";
  test::writeTinySequence(seq, 3);
  const test::RunResult r = test::runVdmap("info --json '" + seq.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("caf\xef\xbf\xbd"), std::string::npos) << r.out;
}

// --save into a folder that cannot be written fails before any mapping, as --out does. As root
// (who may write anywhere) vdmap runs as nobody through setpriv.
TEST(Export, MapSaveIntoAFolderThatCannotBeWrittenFailsAtOnce) {
  test::TempDir tmp;
  std::string as_user;
  if (::geteuid() == 0) {
    if (std::system("setpriv --help >/dev/null 2>&1") != 0) GTEST_SKIP() << "running as root without setpriv";
    as_user = "setpriv --reuid=65534 --regid=65534 --clear-groups";
  }
  fs::permissions(tmp.path(), fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
  test::writeTinySequence(tmp / "seq", 3);
  fs::create_directory(tmp / "writable");
  fs::permissions(tmp / "writable", fs::perms::all);
  fs::create_directory(tmp / "readonly");
  fs::permissions(tmp / "readonly", fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                        fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const test::RunResult r =
      test::runVdmap("map '" + (tmp / "seq").string() + "' --out '" + (tmp / "writable" / "out").string() +
                         "' --save '" + (tmp / "readonly" / "s.vdmap").string() + "'",
                     as_user);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("readonly/s.vdmap: cannot write into " + (tmp / "readonly").string()), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("mapping"), std::string::npos) << "fails before mapping: " << r.err;
  EXPECT_FALSE(fs::exists(tmp / "writable" / "out"));
}

// A flat cell whose smallest eigenvalue float accumulation left at -3e-12 m^2 (132 of 88,940
// were so in a real map) is stored positive semi-definite, changed by no more than its
// clamp; a well-conditioned one is only rounded.
TEST(Export, StoredCovariancesArePositiveSemiDefinite) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.9, Eigen::Vector3d(3, -1, 2).normalized()).toRotationMatrix();
  const auto eigenvalues = [](const Eigen::Matrix3f& m) {
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m.cast<double>()).eigenvalues();
  };
  for (const double smallest : {-3e-12, -1e-14, 0.0}) {
    const Eigen::Matrix3d cov = R * Eigen::Vector3d(2e-4, 3e-5, smallest).asDiagonal() * R.transpose();
    const Eigen::Matrix3f stored = storedCovariance(cov);
    EXPECT_GE(eigenvalues(stored)(0), 0.0) << smallest;
    EXPECT_LT((stored.cast<double>() - cov).cwiseAbs().maxCoeff(), 1e-10) << smallest;
  }
  const Eigen::Matrix3d negative = R * Eigen::Vector3d(2e-4, 3e-5, -3e-12).asDiagonal() * R.transpose();
  ASSERT_LT(eigenvalues(negative.cast<float>())(0), 0.0) << "the case must need the repair";
  const Eigen::Matrix3d good = R * Eigen::Vector3d(2e-4, 3e-5, 1e-6).asDiagonal() * R.transpose();
  EXPECT_EQ(storedCovariance(good), good.cast<float>());
}

// A second export into the same folder leaves one run there: global.bt of an earlier export with
// an OctoMap goes when the new one has none; files that are not the export's stay.
// The progress of an export: one call after each file before global.bt, counting to their number
// (7 with a trajectory, 6 without).
TEST(Export, ReportsProgressAfterEachFile) {
  const TwoViews scene;
  test::TempDir tmp;
  for (const bool with_trajectory : {false, true}) {
    MapExportOptions options;
    if (with_trajectory) options.trajectory = {{0.0, Transform::Identity()}, {0.1, Transform::Identity()}};
    std::vector<std::pair<std::size_t, std::size_t>> calls;
    options.progress = [&calls](std::size_t done, std::size_t total) { calls.emplace_back(done, total); };
    exportMap(tmp / "out", scene.graph, scene.map, options);
    const std::size_t files = with_trajectory ? 7 : 6;
    ASSERT_EQ(calls.size(), files);
    for (std::size_t i = 0; i < files; ++i) EXPECT_EQ(calls[i], std::make_pair(i + 1, files));
  }
}

TEST(Export, AnExportRemovesTheFilesOfAnOlderOneItDoesNotWrite) {
  const TwoViews scene;
  test::TempDir tmp;
  MapExportOptions with_octomap;
  with_octomap.octomap_resolution_m = 0.1;
  exportMap(tmp / "out", scene.graph, scene.map, with_octomap);
  ASSERT_TRUE(fs::exists(tmp / "out" / "global.bt"));
  test::writeText(tmp / "out" / "notes.txt", "mine\n");
  exportMap(tmp / "out", scene.graph, scene.map);
  EXPECT_EQ(filesIn(tmp / "out"),
            (std::vector<std::string>{"global_ellipsoids.ply", "global_gaussians.ply", "global_points.ply", "graph.txt",
                                      "keyframes.txt", "local_maps.ply", "notes.txt", "stats.json"}));
}

// Staging folders of processes that are gone (a SIGKILL, a power cut) are removed by the next
// export; one of a live process is not.
TEST(Export, StaleStagingFoldersOfDeadProcessesAreRemoved) {
  const TwoViews scene;
  test::TempDir tmp;
  const fs::path dead = tmp / "out" / ".vdmap-export-999999999";  // above any pid_max
  const fs::path alive = tmp / "out" / (".vdmap-export-" + std::to_string(::getppid()));
  test::writeText(dead / "local_maps.ply", "partial");
  test::writeText(alive / "local_maps.ply", "partial");
  exportMap(tmp / "out", scene.graph, scene.map);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive));
}

// A FILE.tmp-PID that a killed save left (a session: tens of MB) is removed by the next write
// of FILE; one of a live process is its own.
TEST(Export, StaleTemporaryFilesOfDeadProcessesAreRemoved) {
  test::TempDir tmp;
  const fs::path dead = tmp / "s.vdmap.tmp-999999999";  // above any pid_max
  const fs::path alive = tmp / ("s.vdmap.tmp-" + std::to_string(::getppid()));
  const fs::path other = tmp / "t.vdmap.tmp-999999999";  // another file's: left to its own next write
  for (const fs::path& f : {dead, alive, other}) test::writeText(f, "partial");
  writeFileAtomically(tmp / "s.vdmap", "new");
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive));
  EXPECT_TRUE(fs::exists(other));
  EXPECT_EQ(test::readFile(tmp / "s.vdmap"), "new");
}

// SIGTERM in the middle of an export (here from the OctoMap progress callback, so the moment is
// certain) ends the process as SIGTERM does, and the handler has removed the staging folder with
// its partial files: the folder holds nothing of the interrupted export.
TEST(Export, AnInterruptedExportRemovesItsStagingFolder) {
  test::TempDir tmp;
  const fs::path out = tmp / "out";
  const pid_t child = ::fork();  // before any thread exists in this process (TBB starts in the child)
  ASSERT_GE(child, 0);
  if (child == 0) {
    installTemporaryPathCleanup();
    const TwoViews scene;
    MapExportOptions options;
    options.octomap_resolution_m = 0.1;
    options.octomap_progress = [](std::size_t, std::size_t) { ::raise(SIGTERM); };
    try {
      exportMap(out, scene.graph, scene.map, options);
    } catch (...) {
    }
    ::_exit(3);  // not reached when the signal ends the process
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_FALSE(fs::exists(out)) << "the folder the export created, its staging folder or partial files were left";
}

// OctoMap's 16-bit keys hold 32767 voxels each way from the origin: a finer resolution than the
// map's extent allows is refused before anything is written (it used to write a map with every
// point in one 65 um cube and 92k liboctomap warnings), naming the finest that fits.
TEST(Export, AnOctomapResolutionTheMapDoesNotFitInIsRefused) {
  const TwoViews scene;
  const double extent = octomapExtent(scene.graph, scene.map.ellipsoids);
  ASSERT_GT(extent, 1.0);  // the box room reaches 2 m
  EXPECT_NO_THROW(checkOctomapResolution(extent / 32000, scene.graph, scene.map.ellipsoids));
  try {
    checkOctomapResolution(extent / 33000, scene.graph, scene.map.ellipsoids);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("too fine for this map"), std::string::npos) << e.what();
  }
  test::TempDir tmp;
  MapExportOptions options;
  options.octomap_resolution_m = 1e-9;
  EXPECT_THROW(exportMap(tmp / "out", scene.graph, scene.map, options), std::invalid_argument);
  EXPECT_FALSE(fs::exists(tmp / "out"));
  // The extent bounds every point liboctomap is given: the sample points and the keyframe centres.
  double reach = 0;
  for (const Ellipsoid& e : scene.map.ellipsoids)
    for (const Eigen::Vector3d& p : ellipsoidSamplePoints(e)) reach = std::max(reach, p.cwiseAbs().maxCoeff());
  for (const Keyframe& k : scene.graph.keyframes())
    reach = std::max(reach, k.T_W_K.translation().cwiseAbs().maxCoeff());
  EXPECT_LE(reach, extent);
}

// The .bt bytes equal liboctomap's own writeBinaryConst (written without it, because it prints a
// bare " done." on stderr).
TEST(Export, OctomapFileHasLiboctomapsBytes) {
  const TwoViews scene;
  test::TempDir tmp;
  writeOctomapBt(tmp / "a.bt", scene.graph, scene.map.ellipsoids, 0.1);
  octomap::OcTree tree((tmp / "a.bt").string());
  std::ostringstream reference;
  tree.writeBinaryConst(reference);
  EXPECT_EQ(test::readFile(tmp / "a.bt"), reference.str());
}

// The figures vdmap writes carry no float noise even where nlohmann::json's Grisu2
// writes a longer text than needed: each number is the shortest that reads back the same double
// (the reference: the decimal text it was parsed from, trailing zeros dropped); strings, integers
// and whole doubles keep their form.
TEST(JsonText, NumbersAreTheShortestTextThatReadsBack) {
  int noisy = 0;
  for (int k = 10000; k < 30000; ++k) {
    std::string text = "0.0" + std::to_string(k);
    while (text.back() == '0') text.pop_back();
    const double v = std::strtod(text.c_str(), nullptr);
    noisy += nlohmann::json(v).dump() != text;
    EXPECT_EQ(jsonText(nlohmann::json(v)), text);
  }
  std::printf("nlohmann::json wrote %d of 20000 such numbers longer than needed\n", noisy);
  const nlohmann::json mixed = {{"path", "run-0.010102999999999999/x\"1.50\""},
                                {"count", 7},
                                {"whole", 3.0},
                                {"small", -2.5e-07},
                                {"large", 1e20},
                                {"list", {0.010103, -1, 0.5, 320.0, 0.00012, 123456.5}}};
  const std::string text = jsonText(mixed, -1);
  EXPECT_EQ(
      text,
      "{\"count\":7,\"large\":1e+20,\"list\":[0.010103,-1,0.5,320.0,0.00012,123456.5],\"path\":\"run-0.010102999999999999/x\\\"1.50\\\"\","
      "\"small\":-2.5e-07,\"whole\":3.0}");
  EXPECT_EQ(nlohmann::json::parse(text), mixed);
  // JSON is UTF-8: a path in another encoding is written with U+FFFD, not an exception.
  EXPECT_EQ(jsonText(nlohmann::json{{"folder", "/data/caf\xe9"}}, -1), "{\"folder\":\"/data/caf\xef\xbf\xbd\"}");
  // Any double reads back as itself, at every magnitude.
  std::mt19937_64 random(7);
  for (int i = 0; i < 100000; ++i) {
    const double v =
        std::ldexp(std::uniform_real_distribution<double>(-1, 1)(random), static_cast<int>(random() % 120) - 60);
    ASSERT_EQ(nlohmann::json::parse(jsonText(nlohmann::json(v))).get<double>(), v) << jsonText(nlohmann::json(v));
  }
}

}  // namespace
}  // namespace vdmap
