// `vdmap render` and `vdmap synth` end to end, and their errors on bad input.
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "mapping/io/tum_sequence.h"
#include "mapping/synth/builtin_scene.h"
#include "render/sequence_synth.h"
#include "tests/test_util.h"

namespace vdmap {
namespace {

using test::runVdmap;
using test::TempDir;
using test::writeText;

// Two ellipsoids in the docs/method.md 11 binary layout.
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
  const std::string bytes = test::readFile(VDMAP_BINARY);
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
  // A value wrong by itself is CLI11's error (its code, 100-114); one that needs a file, exit 1.
  struct Case {
    std::string args, expected;
    bool usage = false;
  };
  writeText(tmp / "noface.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                "end_header\n0 0 0 1 2 3\n");
  writeText(tmp / "nocolor.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                 "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(tmp / "truncated.ply", std::string(kSquarePly).substr(0, std::string(kSquarePly).size() - 20));
  const std::vector<Case> cases = {
      {"render" + map + out + " --size 0x0", "--size: '0x0': each side must be in 1..16384", true},
      {"render" + map + out + " --size 100000x100000", "each side must be in 1..16384", true},
      {"render" + map + out + " --size big", "expected WIDTHxHEIGHT", true},
      {"render" + map + out + " --color rainbow", "--color: unknown colour mode 'rainbow'", true},
      {"render --mesh '" + (tmp / "noface.ply").string() + "'" + out, "no faces"},
      {"render --mesh '" + (tmp / "nocolor.ply").string() + "'" + out, "no property 'red'"},
      {"render --mesh '" + (tmp / "truncated.ply").string() + "'" + out, "truncated"},
      {"render --map '" + (tmp / "missing.ply").string() + "'" + out, "cannot open"},
      {"render" + map + out + " --view keyframe:0", "needs keyframes"},
      {"render" + map + out + " --view side", "expected global, keyframe:K or container:K", true},
      {"render '" + tmp.path().string() + "'" + map + out, "SEQ excludes --map", true},
      {"render '" + (tmp / "no_such_sequence").string() + "'" + out, "no_such_sequence"},
  };
  for (const Case& c : cases) {
    const auto r = runVdmap(c.args);
    if (c.usage) {
      EXPECT_GE(r.exit_code, 100) << c.args << "\n" << r.err;
      EXPECT_LE(r.exit_code, 114) << c.args << "\n" << r.err;
    } else {
      EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.err;
    }
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
  EXPECT_TRUE(std::filesystem::exists(tmp / "o.png")) << "the control, with OSMesa found, must render";
  EXPECT_FALSE(std::filesystem::exists(tmp / "p.png"));
}

// `vdmap render SEQ`: the first 10 poses of a 40-pose walk around the built-in room (big steps,
// so a few keyframes), mapped by the binary and drawn in each view.
class RenderSequenceCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const BuiltinScene scene = makeBuiltinScene({.frames = 40});
    render::SynthOptions options;
    options.camera = scene.camera;
    options.last_frame = 10;
    render::synthesizeSequence(scene.mesh, scene.trajectory, options, *dir_ / "room");
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string seq() { return std::string("'").append((*dir_ / "room").string()).append("'"); }
  static std::string out(const std::string& name) { return (*dir_ / name).string(); }
  static TempDir* dir_;
};
TempDir* RenderSequenceCli::dir_ = nullptr;

// Pearson correlation of two images' grey values (equal sizes), after a blur that removes the
// texture finer than a container cell (5 px): ellipsoids carry a cell's mean colour.
double greyCorrelation(const cv::Mat& a_bgr, const cv::Mat& b_bgr) {
  cv::Mat a, b;
  cv::cvtColor(a_bgr, a, cv::COLOR_BGR2GRAY);
  cv::cvtColor(b_bgr, b, cv::COLOR_BGR2GRAY);
  a.convertTo(a, CV_32F);
  b.convertTo(b, CV_32F);
  cv::GaussianBlur(a, a, {0, 0}, 4.0);
  cv::GaussianBlur(b, b, {0, 0}, 4.0);
  cv::Mat r;
  cv::matchTemplate(a, b, r, cv::TM_CCOEFF_NORMED);
  return r.at<float>(0, 0);
}

TEST_F(RenderSequenceCli, GlobalViewShowsTheMapAndTheKeyframeGraph) {
  const auto r = runVdmap("render " + seq() + " --view global --size 320x240 --out '" + out("global.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("keyframes"), std::string::npos) << r.out;
  const cv::Mat img = cv::imread(out("global.png"));
  ASSERT_EQ(img.size(), cv::Size(320, 240));
  EXPECT_GT(cv::countNonZero(img.reshape(1) < 250), 3000) << "nothing was drawn";
}

TEST_F(RenderSequenceCli, KeyframeViewReproducesTheKeyframesImage) {
  // Keyframe 0 is frame 0; seen from its own pose with its intrinsics, the map (ellipsoids in
  // their mean colour, shaded) must look like the frame: the same image up to cell-sized blur
  // and shading. Seen from the wrong pose (or with the y axis flipped) the correlation drops
  // near 0.
  const auto r = runVdmap("render " + seq() + " --view keyframe:0 --out '" + out("kf0.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = cv::imread(out("kf0.png"));
  const cv::Mat frame = cv::imread((*dir_ / "room" / "rgb" / "000000.png").string());
  ASSERT_EQ(img.size(), frame.size()) << "the default size of keyframe:K is the camera's";
  const double own = greyCorrelation(img, frame);
  cv::Mat flipped;
  cv::flip(frame, flipped, 0);
  const double upside_down = greyCorrelation(img, flipped);
  std::printf("keyframe:0 view vs frame 0: correlation %.3f (flipped frame: %.3f)\n", own, upside_down);
  // Measured 0.58 (llvmpipe, 10 frames): shading and the gaps between cells keep it well below 1.
  EXPECT_GT(own, 0.4);
  EXPECT_LT(upside_down, own - 0.3);
}

TEST_F(RenderSequenceCli, ContainerViewIsTheKeyframeImageWithItsEllipses) {
  const auto r = runVdmap("render " + seq() + " --view container:0 --size 640x480 --grid --out '" +
                          out("container0.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = cv::imread(out("container0.png"));
  ASSERT_EQ(img.size(), cv::Size(640, 480));
  // The image occupies the middle half of the 2W x 2H container (here scaled by 1/2).
  const cv::Mat frame = cv::imread((*dir_ / "room" / "rgb" / "000000.png").string());
  cv::Mat small;
  cv::resize(frame, small, {320, 240}, 0, 0, cv::INTER_AREA);
  EXPECT_GT(greyCorrelation(img(cv::Rect(160, 120, 320, 240)), small), 0.8);
}

TEST_F(RenderSequenceCli, AnUnknownKeyframeNamesTheValidRange) {
  const auto r = runVdmap("render " + seq() + " --view container:999 --out '" + out("none.png") + "'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("has keyframes 0.."), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out("none.png")));
}

// render draws a saved session (every view, from its keyframes and graph) without
// mapping again, pixel for pixel what mapping the sequence draws, and a `vdmap map` folder.
TEST_F(RenderSequenceCli, ASessionAndAMapFolderRenderWithoutMapping) {
  const auto saved = runVdmap("map " + seq() + " --out '" + out("map") + "' --save '" + out("s.vdmap") + "'");
  ASSERT_EQ(saved.exit_code, 0) << saved.err;
  for (const char* view : {"global", "keyframe:1", "container:1"}) {
    const std::string a = out(std::string("seq-") + view + ".png"), b = out(std::string("session-") + view + ".png");
    const auto from_seq = runVdmap("render " + seq() + " --view " + view + " --size 320x240 --out '" + a + "'");
    const auto from_session = runVdmap("render '" + out("s.vdmap") + "' --view " + view + " --size 320x240 --out '" + b + "'");
    ASSERT_EQ(from_seq.exit_code, 0) << from_seq.err;
    ASSERT_EQ(from_session.exit_code, 0) << from_session.err;
    EXPECT_EQ(cv::norm(cv::imread(a), cv::imread(b), cv::NORM_INF), 0.0) << view;
    EXPECT_NE(from_session.out.find("keyframes"), std::string::npos) << from_session.out;
  }
  const auto with_map = runVdmap("render --map '" + out("s.vdmap") + "' --view keyframe:0 --out '" + out("k.png") + "'");
  EXPECT_EQ(with_map.exit_code, 0) << with_map.err;
  const auto folder = runVdmap("render --map '" + out("map") + "' --size 320x240 --out '" + out("folder.png") + "'");
  ASSERT_EQ(folder.exit_code, 0) << folder.err;
  // --map alone frames the whole map: nothing drawn touches the image's edges (it was cropped
  // at the left and bottom).
  const cv::Mat img = cv::imread(out("folder.png"), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(img.empty());
  EXPECT_GT(cv::countNonZero(img < 250), 1000) << "nothing was drawn";
  for (const cv::Mat& edge : {img.row(0), img.row(img.rows - 1), img.col(0), img.col(img.cols - 1)})
    EXPECT_EQ(cv::countNonZero(edge < 250), 0) << "the map reaches the image's edge";
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
