// `vdmap render` and `vdmap synth` end to end, and their errors on bad input.
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "mapping/io/tum_sequence.h"
#include "tests/test_util.h"

namespace vdmap {
namespace {

using test::runVdmap;
using test::TempDir;
using test::writeText;

// Two ellipsoids in the SPEC section 7 binary layout.
void writeEllipsoidPly(const std::filesystem::path& file) {
  std::ofstream out(file, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
         "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
         "property float cxx\nproperty float cxy\nproperty float cxz\nproperty float cyy\n"
         "property float cyz\nproperty float czz\nproperty uint count\nproperty int keyframe\nend_header\n";
  for (int i = 0; i < 2; ++i) {
    const float xyz[3] = {i * 0.5f, 0.f, 0.f};
    const unsigned char rgb[3] = {200, static_cast<unsigned char>(50 + 100 * i), 40};
    const float cov[6] = {0.01f, 0.f, 0.f, 0.004f, 0.f, 0.001f};
    const unsigned count = 10;
    const int kf = i;
    out.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
    out.write(reinterpret_cast<const char*>(rgb), sizeof rgb);
    out.write(reinterpret_cast<const char*>(cov), sizeof cov);
    out.write(reinterpret_cast<const char*>(&count), 4);
    out.write(reinterpret_cast<const char*>(&kf), 4);
  }
}

// A coloured square in the plane z = 2 (ascii PLY), seen by an identity camera.
const char* kSquarePly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
    "property list uchar int vertex_indices\nend_header\n"
    "-2 -2 2 255 0 0\n2 -2 2 0 255 0\n2 2 2 0 0 255\n-2 2 2 255 255 0\n4 0 1 2 3\n";

TEST(RenderCli, RendersAMapThroughOsmesaWithLibGlLinked) {
  // The binary links libGL and glfw (for the workbench) and must still render via OSMesa.
  std::ifstream binary(VDMAP_BINARY, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(binary)), {});
  EXPECT_NE(bytes.find("libGL.so"), std::string::npos) << "vdmap no longer links libGL: the test proves nothing";
  TempDir tmp;
  writeEllipsoidPly(tmp / "map.ply");
  const auto r = runVdmap("render --map '" + (tmp / "map.ply").string() + "' --view global --size 160x120 --out '" +
                          (tmp / "out.png").string() + "' --color keyframe");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = cv::imread((tmp / "out.png").string());
  ASSERT_EQ(img.cols, 160);
  ASSERT_EQ(img.rows, 120);
  EXPECT_GT(cv::countNonZero(img.reshape(1) < 250), 100) << "nothing was drawn";
}

TEST(RenderCli, BadInputGivesOneLineErrors) {
  TempDir tmp;
  writeEllipsoidPly(tmp / "map.ply");
  const std::string map = " --map '" + (tmp / "map.ply").string() + "'";
  const std::string out = " --out '" + (tmp / "out.png").string() + "'";
  struct Case {
    std::string args, expected;
  };
  writeText(tmp / "noface.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                "end_header\n0 0 0 1 2 3\n");
  writeText(tmp / "nocolor.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                 "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(tmp / "truncated.ply", std::string(kSquarePly).substr(0, std::string(kSquarePly).size() - 20));
  const std::vector<Case> cases = {
      {"render" + map + out + " --size 0x0", "each side must be in 1..16384"},
      {"render" + map + out + " --size 100000x100000", "each side must be in 1..16384"},
      {"render" + map + out + " --size big", "expected WIDTHxHEIGHT"},
      {"render" + map + out + " --color rainbow", "unknown colour mode 'rainbow'"},
      {"render --mesh '" + (tmp / "noface.ply").string() + "'" + out, "no faces"},
      {"render --mesh '" + (tmp / "nocolor.ply").string() + "'" + out, "no property 'red'"},
      {"render --mesh '" + (tmp / "truncated.ply").string() + "'" + out, "truncated"},
      {"render --map '" + (tmp / "missing.ply").string() + "'" + out, "cannot open"},
  };
  for (const Case& c : cases) {
    const auto r = runVdmap(c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(tmp / "out.png"));
}

TEST(RenderCli, MissingOsmesaIsAClearError) {
  TempDir tmp;
  writeEllipsoidPly(tmp / "map.ply");
  const auto r = runVdmap("render --map '" + (tmp / "map.ply").string() + "' --out '" + (tmp / "o.png").string() +
                          "' 2>&1; VDMAP_OSMESA_LIBRARY=/nonexistent/libOSMesa.so '" + VDMAP_BINARY +
                          "' render --map '" + (tmp / "map.ply").string() + "' --out '" + (tmp / "p.png").string() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("needs OSMesa, which is not available"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "p.png"));
}

TEST(SynthCli, WritesASequenceAndRejectsBadTrajectories) {
  TempDir tmp;
  writeText(tmp / "square.ply", kSquarePly);
  writeText(tmp / "traj.txt", "# t tx ty tz qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 0.01 0 0 0 0 0 1\n0.2 0.02 0 0 0 0 0 1\n");
  const std::string mesh = " --mesh '" + (tmp / "square.ply").string() + "'";
  auto r = runVdmap("synth" + mesh + " --trajectory '" + (tmp / "traj.txt").string() +
                    "' --camera tum-default --noise none --frames 1: --out '" + (tmp / "seq").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const TumSequence seq = TumSequence::open(tmp / "seq");
  ASSERT_EQ(seq.size(), 2u);
  const RgbdFrame f = seq.load(0);
  EXPECT_EQ(f.depth.at<std::uint16_t>(240, 320), 10000);  // 2 m at depth scale 5000, noise off
  writeText(tmp / "bad.txt", "0.0 0 0 0 0 0 0 1\n0.1 0 0 zero 0 0 0 1\n");
  r = runVdmap("synth" + mesh + " --trajectory '" + (tmp / "bad.txt").string() + "' --camera tum-default --out '" +
               (tmp / "seq2").string() + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad.txt:2"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "seq2"));
}

}  // namespace
}  // namespace vdmap
