// `vdmap render` and `vdmap synth` end to end, and their errors on bad input.
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <regex>

#include "app/view/view_file.h"
#include "mapping/files/ply_reader.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/sequence/sequence.h"
#include "mapping/synth/builtin_scene.h"
#include "render/colormap.h"
#include "render/map_scene.h"
#include "render/sequence_synth.h"
#include "render/view_camera.h"
#include "render/view_framing.h"
#include "tests/support/test_util.h"

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
                          (tmp / "out.png").string() + "' --color keyframe --background white");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = test::readImage((tmp / "out.png"));
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
      {"render" + map + out + " --mesh-style flat", "--mesh-style: flat not in {shaded,colour,wireframe}", true},
      {"render" + map + out + " --layers mesh",
       "--layers mesh draws the surface mesh of local maps: give a sequence (SEQ), a session (.vdmap) or a `vdmap map` folder"},
      {"render" + map + out + " --set mesh_style=flat", "view.mesh_style must be shaded or colour or wireframe"},
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
  const auto r =
      runVdmap("render --map '" + (tmp / "map.ply").string() + "' --out '" + (tmp / "o.png").string() +
               "' 2>&1; VDMAP_OSMESA_LIBRARY=/nonexistent/libOSMesa.so '" + VDMAP_BINARY + "' render --map '" +
               (tmp / "map.ply").string() + "' --out '" + (tmp / "p.png").string() + "'");
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
  const auto r = runVdmap("render " + seq() + " --view global --size 320x240 --background white --out '" +
                          out("global.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("keyframes"), std::string::npos) << r.out;
  const cv::Mat img = test::readImage(out("global.png"));
  ASSERT_EQ(img.size(), cv::Size(320, 240));
  EXPECT_GT(cv::countNonZero(img.reshape(1) < 250), 3000) << "nothing was drawn";
}

TEST_F(RenderSequenceCli, KeyframeViewReproducesTheKeyframesImage) {
  // Keyframe 0 is frame 0; seen from its own pose with its intrinsics, the map (ellipsoids in
  // their mean colour, shaded) must look like the frame: the same image up to cell-sized blur
  // and shading. Seen from the wrong pose (or with the y axis flipped) the correlation drops
  // near 0.
  const auto r = runVdmap("render " + seq() + " --view keyframe:0 --background white --out '" + out("kf0.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = test::readImage(out("kf0.png"));
  const cv::Mat frame = test::readImage((*dir_ / "room" / "rgb" / "000000.png"));
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
  const auto r =
      runVdmap("render " + seq() + " --view container:0 --size 640x480 --grid --out '" + out("container0.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const cv::Mat img = test::readImage(out("container0.png"));
  ASSERT_EQ(img.size(), cv::Size(640, 480));
  // The image occupies the middle half of the 2W x 2H container (here scaled by 1/2).
  const cv::Mat frame = test::readImage((*dir_ / "room" / "rgb" / "000000.png"));
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
    const auto from_session =
        runVdmap("render '" + out("s.vdmap") + "' --view " + view + " --size 320x240 --out '" + b + "'");
    ASSERT_EQ(from_seq.exit_code, 0) << from_seq.err;
    ASSERT_EQ(from_session.exit_code, 0) << from_session.err;
    EXPECT_EQ(cv::norm(test::readImage(a), test::readImage(b), cv::NORM_INF), 0.0) << view;
    EXPECT_NE(from_session.out.find("keyframes"), std::string::npos) << from_session.out;
  }
  const auto with_map =
      runVdmap("render --map '" + out("s.vdmap") + "' --view keyframe:0 --out '" + out("k.png") + "'");
  EXPECT_EQ(with_map.exit_code, 0) << with_map.err;
  const auto folder =
      runVdmap("render --map '" + out("map") + "' --size 320x240 --background white --out '" + out("folder.png") + "'");
  ASSERT_EQ(folder.exit_code, 0) << folder.err;
  // --map alone frames the map as the window does: the box of the central 96 % of the means
  // (a few strays may reach past the edges) projects inside the image and spans at least 60 % of
  // its width or height (the default view is from 35 degrees above the horizon, so the
  // projected box is not the image).
  cv::Mat img;
  cv::cvtColor(test::readImage(out("folder.png")), img, cv::COLOR_BGR2GRAY);
  ASSERT_FALSE(img.empty());
  EXPECT_GT(cv::countNonZero(img < 250), 1000) << "nothing was drawn";
  std::vector<glm::vec3> means;
  for (const EllipsoidRecord& e : readPlyEllipsoids(out("map") + "/global_ellipsoids.ply"))
    means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
  const auto [lo, hi] = render::robustBounds(means);
  const render::ViewCamera view = render::OrbitCamera::framing(lo, hi, {0, 0, 1}, 320.f / 240.f).view(320, 240);
  glm::vec2 a(INFINITY), b(-INFINITY);
  for (int c = 0; c < 8; ++c) {
    const glm::vec4 q =
        view.T_C_W * glm::vec4((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z, 1.f);
    const glm::vec2 p(view.fx * q.x / q.z + view.cx, view.fy * q.y / q.z + view.cy);
    a = glm::min(a, p), b = glm::max(b, p);
  }
  EXPECT_GE(a.x, 0.f);
  EXPECT_GE(a.y, 0.f);
  EXPECT_LE(b.x, 320.f);
  EXPECT_LE(b.y, 240.f);
  EXPECT_GE(std::max((b.x - a.x) / 320.f, (b.y - a.y) / 240.f), 0.6f);
  // What was drawn spans as much (the image, not only the formula).
  cv::Rect drawn = cv::boundingRect(img < 250);
  EXPECT_GE(std::max(drawn.width / 320.0, drawn.height / 240.0), 0.6) << drawn;
}

// The number in "N ellipsoids" of render's summary line (-1 when missing).
long ellipsoidsDrawn(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex(R"(, (\d+) ellipsoids?,)")) ? std::stol(m[1]) : -1;
}

// A PNG's pixels (BGR).
cv::Mat png(const std::string& file) { return test::readImage(file); }

double maxDifference(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() ? cv::norm(a, b, cv::NORM_INF) : 1e9;
}

// Pixels of `image` (BGR) within 12 counts of `rgb`.
int countColour(const cv::Mat& image, const glm::u8vec3& rgb) {
  cv::Mat mask;
  cv::inRange(image, cv::Scalar(rgb.b - 12, rgb.g - 12, rgb.r - 12), cv::Scalar(rgb.b + 12, rgb.g + 12, rgb.r + 12),
              mask);
  return cv::countNonZero(mask);
}

// The session of the room, saved once for the tests below.
class RenderSessionCli : public RenderSequenceCli {
 protected:
  static void SetUpTestSuite() {
    RenderSequenceCli::SetUpTestSuite();
    const auto saved = runVdmap("map " + seq() + " --out '" + out("m") + "' --save '" + out("s.vdmap") + "'");
    ASSERT_EQ(saved.exit_code, 0) << saved.err;
  }
  static test::RunResult render(const std::string& name, const std::string& options) {
    return runVdmap("render '" + out("s.vdmap") + "' --size 320x240 --out '" + out(name) + "' " + options);
  }
};

TEST_F(RenderSessionCli, TheDefaultGlobalViewUsesTheWindowsThemeUpAndFraming) {
  const auto r = render("default.png", "");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("vdmap render: note: settings: the session's thresholds\n"), std::string::npos) << r.err;
  const cv::Mat img = png(out("default.png"));
  EXPECT_EQ(img.at<cv::Vec3b>(0, 0), cv::Vec3b(38, 33, 33)) << "the window's dark background (BGR)";
  // The up vector is the window's: estimateUp of every mapped camera and the session's map.
  const Session session = loadSession(out("s.vdmap"));
  const auto cameras = render::graphSceneOf(session.graph, session.info.state, session.info.camera, false).trajectory;
  const glm::vec3 up = render::estimateUp(cameras, buildGlobalMap(session.graph, session.info.global).ellipsoids);
  char expected[64];
  std::snprintf(expected, sizeof expected, "up (%.2f, %.2f, %.2f))", up.x, up.y, up.z);
  EXPECT_NE(r.out.find(expected), std::string::npos) << r.out << " expected " << expected;
  // --up names an axis instead.
  const auto y_up = render("y.png", "--up +y");
  EXPECT_NE(y_up.out.find("up (0.00, 1.00, 0.00))"), std::string::npos) << y_up.out;
  EXPECT_GT(maxDifference(img, png(out("y.png"))), 0.0);
}

TEST_F(RenderSessionCli, UncertaintyAndKeyframeColoursDrawTheirLegend) {
  ASSERT_EQ(render("rgb.png", "").exit_code, 0);
  ASSERT_EQ(render("u.png", "--color uncertainty").exit_code, 0);
  ASSERT_EQ(render("k.png", "--color keyframe").exit_code, 0);
  const cv::Rect corner(0, 240 - 60, 240, 60);  // the legend's place, bottom left
  const cv::Mat rgb = png(out("rgb.png"))(corner), u = png(out("u.png"))(corner), k = png(out("k.png"))(corner);
  EXPECT_GT(countColour(u, render::colormap(0.f)), 10) << "the ramp's dark end";
  EXPECT_GT(countColour(u, render::colormap(1.f)), 10) << "the ramp's bright end";
  EXPECT_GT(countColour(k, render::keyframeColor(0)), 10) << "K0's swatch";
  EXPECT_GT(countColour(k, render::keyframeColor(1)), 10) << "K1's swatch";
  EXPECT_LT(countColour(rgb, render::colormap(1.f)) + countColour(rgb, render::keyframeColor(1)), 5)
      << "rgb: no legend";
}

TEST_F(RenderSessionCli, EachLayerCanBeSwitchedOffAlone) {
  ASSERT_EQ(render("all.png", "--color keyframe").exit_code, 0);
  const cv::Mat all = png(out("all.png"));
  const std::vector<std::string> layers = {"frustums", "graph", "trajectory", "legend"};
  // The covisibility edges join keyframes the trajectory passes through: the graph is looked
  // for with the trajectory off on both sides.
  ASSERT_EQ(render("no-path.png", "--color keyframe --layers frustums,graph,legend").exit_code, 0);
  for (const std::string& off : layers) {
    std::string list;
    for (const std::string& l : layers)
      if (l != off && (off != "graph" || l != "trajectory")) list += (list.empty() ? "" : ",") + l;
    const auto r = render("no-" + off + ".png", "--color keyframe --layers " + list);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const cv::Mat without = png(out("no-" + off + ".png"));
    cv::Mat diff;
    cv::absdiff(off == "graph" ? png(out("no-path.png")) : all, without, diff);
    EXPECT_GT(cv::countNonZero(diff.reshape(1)), 0) << off << " changed nothing";
  }
  ASSERT_EQ(render("none.png", "--color keyframe --layers none").exit_code, 0);
  EXPECT_GT(maxDifference(all, png(out("none.png"))), 0.0);
  // White changes the background only where nothing is drawn over it.
  ASSERT_EQ(render("white.png", "--color keyframe --layers none --background white").exit_code, 0);
  EXPECT_EQ(png(out("white.png")).at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  ASSERT_EQ(render("hex.png", "--color keyframe --layers none --background '#102030'").exit_code, 0);
  EXPECT_EQ(png(out("hex.png")).at<cv::Vec3b>(0, 0), cv::Vec3b(0x30, 0x20, 0x10));
}

// The mesh layer: off by default (the default picture is unchanged by its style), drawn where the
// map's surfaces are, and each style draws its own picture.
TEST_F(RenderSessionCli, TheMeshLayerDrawsTheSurfaceWhereTheMapIs) {
  ASSERT_EQ(render("plain.png", "").exit_code, 0);
  ASSERT_EQ(render("plain-wire.png", "--mesh-style wireframe").exit_code, 0);
  EXPECT_EQ(maxDifference(png(out("plain.png")), png(out("plain-wire.png"))), 0.0) << "the layer is off by default";
  // The ellipsoids alone, the mesh alone, from one camera (the mesh lies on the ellipsoids' surfaces).
  const std::string camera = " --look-at 0,-5,4,0,0,1 --up 0,0,1";
  ASSERT_EQ(render("ellipsoids.png", "--layers none --color keyframe" + camera).exit_code, 0);
  const auto shaded = render("shaded.png", "--layers mesh --draw none" + camera);
  ASSERT_EQ(shaded.exit_code, 0) << shaded.err;
  EXPECT_EQ(shaded.out.find(" 0 triangles"), std::string::npos) << "the summary counts the mesh's: " << shaded.out;
  ASSERT_EQ(render("colour.png", "--layers mesh --draw none --mesh-style colour" + camera).exit_code, 0);
  ASSERT_EQ(render("wire.png", "--layers mesh --draw none --mesh-style wireframe" + camera).exit_code, 0);
  ASSERT_EQ(render("nothing.png", "--layers none --draw none" + camera).exit_code, 0);
  // What each draws besides what is always drawn (the camera now).
  const cv::Mat always = png(out("nothing.png"));
  const cv::Vec3b background = always.at<cv::Vec3b>(0, 0);
  const auto drawn = [&](const cv::Mat& image) {
    cv::Mat mask, camera;
    cv::inRange(image, background, background, mask);
    cv::inRange(always, background, background, camera);
    return (mask == 0) & (camera != 0);
  };
  const cv::Mat wire = png(out("wire.png")), colour = png(out("colour.png")), grey = png(out("shaded.png"));
  const cv::Mat mesh = drawn(grey), map = drawn(png(out("ellipsoids.png")));
  EXPECT_GT(cv::countNonZero(mesh), 320 * 240 / 10) << "the mesh covers the room";
  cv::Mat near_map;
  cv::dilate(map, near_map, cv::Mat::ones(7, 7, CV_8U));
  EXPECT_GT(cv::countNonZero(mesh & near_map), 0.95 * cv::countNonZero(mesh)) << "drawn where the map is";
  // Pixels where two images differ by more than 8 counts.
  const auto differing = [](const cv::Mat& a, const cv::Mat& b) {
    cv::Mat diff;
    cv::absdiff(a, b, diff);
    cv::cvtColor(diff, diff, cv::COLOR_BGR2GRAY);
    return cv::countNonZero(diff > 8);
  };
  EXPECT_GT(differing(grey, wire), cv::countNonZero(mesh) / 10) << "the wireframe is its triangles' edges";
  EXPECT_GT(differing(grey, colour), cv::countNonZero(mesh) / 10) << "the mesh's colours, not grey";
  // Shaded is grey: every pixel it draws has equal channels.
  std::vector<cv::Mat> bgr;
  cv::split(grey, bgr);
  EXPECT_EQ(cv::countNonZero(cv::Mat(((bgr[0] != bgr[2]) | (bgr[1] != bgr[2])) & mesh)), 0);
}

// `vdmap mesh`'s options make render's mesh layer too, as the settings' mesh keys do.
TEST_F(RenderSessionCli, TheMeshOptionsChangeTheMeshLayer) {
  const auto triangles = [](const test::RunResult& r) {
    const std::size_t at = r.out.find(" triangles");
    const std::size_t from = r.out.rfind(' ', at - 1);
    return at == std::string::npos ? 0ul : std::stoul(r.out.substr(from + 1, at - from - 1));
  };
  const auto plain = render("m.png", "--layers mesh");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto steep = render("m-slope.png", "--layers mesh --mesh-max-slope 20");
  ASSERT_EQ(steep.exit_code, 0) << steep.err;
  EXPECT_LT(triangles(steep), triangles(plain)) << steep.out << plain.out;
  EXPECT_GT(maxDifference(png(out("m.png")), png(out("m-slope.png"))), 0.0);
  const auto set = render("m-set.png", "--layers mesh --set mesh_max_slope=20");
  ASSERT_EQ(set.exit_code, 0) << set.err;
  EXPECT_EQ(maxDifference(png(out("m-slope.png")), png(out("m-set.png"))), 0.0) << "the flag is the key";
  const auto both = render("m-both.png", "--layers mesh --set mesh_max_slope=20 --mesh-max-slope 60");
  EXPECT_EQ(maxDifference(png(out("m.png")), png(out("m-both.png"))), 0.0) << "the flag over --set";
  const auto coarse = render("m-stride.png", "--layers mesh --mesh-stride 4 --mesh-no-fuse");
  ASSERT_EQ(coarse.exit_code, 0) << coarse.err;
  EXPECT_NE(triangles(coarse), triangles(plain));
  for (const auto& [options, named] : std::vector<std::pair<std::string, std::string>>{
           {"--layers mesh --mesh-stride 0", "--mesh-stride: Value 0 not in range 1 to 16"},
           {"--layers mesh --mesh-max-slope 95", "--mesh-max-slope: Value 95 not in range"},
           {"--layers mesh --set mesh_stride=40", "view.mesh_stride must be in 1..16"}}) {
    const auto r = render("bad.png", options);
    EXPECT_NE(r.exit_code, 0) << options;
    EXPECT_NE(r.err.find(named), std::string::npos) << options << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
  }
}

// A `vdmap map` folder's local maps (local_maps.ply, the cells its map kept) give the mesh layer:
// the mesh `vdmap mesh` makes of the folder; a folder without them says which file is missing.
TEST_F(RenderSessionCli, AMapFolderDrawsTheMeshOfItsLocalMaps) {
  const auto folder = runVdmap("render --map '" + out("m") + "' --size 320x240 --layers mesh --draw none --out '" +
                               out("folder-mesh.png") + "'");
  ASSERT_EQ(folder.exit_code, 0) << folder.err;
  const auto meshed = runVdmap("mesh '" + out("m") + "' --out '" + out("folder.ply") + "' --json");
  ASSERT_EQ(meshed.exit_code, 0) << meshed.err;
  const std::size_t triangles = nlohmann::json::parse(meshed.out).at("triangles").get<std::size_t>();
  EXPECT_GT(triangles, 0u);
  EXPECT_NE(folder.out.find(" " + std::to_string(triangles) + " triangles"), std::string::npos)
      << folder.out << " expected " << triangles;
  const auto bare = runVdmap("render --map '" + out("m") + "' --size 320x240 --layers none --draw none --out '" +
                             out("folder-bare.png") + "'");
  ASSERT_EQ(bare.exit_code, 0) << bare.err;
  EXPECT_GT(maxDifference(png(out("folder-mesh.png")), png(out("folder-bare.png"))), 0.0) << "the mesh is drawn";

  TempDir copy;
  std::filesystem::copy(out("m"), copy.path() / "m");
  std::filesystem::remove(copy.path() / "m" / "local_maps.ply");
  const auto missing = runVdmap("render --map '" + (copy.path() / "m").string() + "' --layers mesh --out '" +
                                (copy.path() / "x.png").string() + "'");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("local_maps.ply: missing"), std::string::npos) << missing.err;
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << "one line: " << missing.err;
}

TEST_F(RenderSessionCli, TheContainerViewDrawsTheImagesOutlineAsTheBoundsLayer) {
  ASSERT_EQ(render("c.png", "--view container:1").exit_code, 0);
  ASSERT_EQ(render("cn.png", "--view container:1 --layers none").exit_code, 0);
  // At 320x240 the image fills the middle half: its outline runs along rows 60 and 179, columns
  // 80 and 239.
  const cv::Mat with = png(out("c.png")), without = png(out("cn.png"));
  const glm::u8vec3 yellow{255, 220, 0};
  for (const cv::Rect& edge :
       {cv::Rect(100, 58, 120, 4), cv::Rect(100, 178, 120, 4), cv::Rect(78, 80, 4, 80), cv::Rect(238, 80, 4, 80)}) {
    EXPECT_GT(countColour(with(edge), yellow), 100) << edge;
    EXPECT_EQ(countColour(without(edge), yellow), 0) << edge;
  }
}

// --- picture stream: height slice and draw none ---
TEST_F(RenderSessionCli, ASliceDrawsOnlyTheEllipsoidsWithinItAndDrawNoneNone) {
  const auto all = render("slice-all.png", "--layers none");
  const auto low = render("slice-low.png", "--layers none --slice -100:0.5");
  const auto high = render("slice-high.png", "--layers none --slice 0.5:100");
  ASSERT_EQ(all.exit_code, 0) << all.err;
  ASSERT_EQ(low.exit_code, 0) << low.err;
  ASSERT_EQ(high.exit_code, 0) << high.err;
  EXPECT_GT(ellipsoidsDrawn(low.out), 0) << low.out;
  EXPECT_GT(ellipsoidsDrawn(high.out), 0) << high.out;
  EXPECT_EQ(ellipsoidsDrawn(low.out) + ellipsoidsDrawn(high.out), ellipsoidsDrawn(all.out))
      << "whole ellipsoids, each once";
  EXPECT_GT(maxDifference(png(out("slice-low.png")), png(out("slice-high.png"))), 0.0);
  const auto none = render("draw-none.png", "--layers none --draw none");
  ASSERT_EQ(none.exit_code, 0) << none.err;
  EXPECT_EQ(ellipsoidsDrawn(none.out), 0) << none.out;
  // Only the camera's red frustum (drawn with every layer off) is left of the picture.
  const auto drawnPixels = [](const cv::Mat& image) {
    cv::Mat bg;
    cv::inRange(image, cv::Scalar(38, 33, 33), cv::Scalar(38, 33, 33), bg);
    return image.rows * image.cols - cv::countNonZero(bg);
  };
  EXPECT_LT(drawnPixels(png(out("draw-none.png"))), drawnPixels(png(out("slice-all.png"))) / 20);
  EXPECT_GE(render("bad-slice.png", "--slice 2:1").exit_code, 100) << "CLI11's code, as every bad flag value";
}

TEST_F(RenderSessionCli, OrbitOfTheDefaultAnglesIsTheDefaultView) {
  ASSERT_EQ(render("d.png", "").exit_code, 0);
  ASSERT_EQ(render("o.png", "--orbit -60,35").exit_code, 0);
  ASSERT_EQ(render("o2.png", "--orbit 30,35").exit_code, 0);
  EXPECT_EQ(maxDifference(png(out("d.png")), png(out("o.png"))), 0.0) << "pixel-identical";
  EXPECT_GT(maxDifference(png(out("d.png")), png(out("o2.png"))), 0.0);
  const auto both = render("x.png", "--orbit 30,35 --look-at 1,1,1,0,0,0");
  EXPECT_GE(both.exit_code, 100) << "--orbit excludes --look-at (CLI11's code)";
}

TEST_F(RenderSessionCli, LookAtFromAViewFilesCameraIsThatView) {
  // A hand-written view file with a camera, and the same camera as flags.
  writeText(out("v.json"),
            R"({"vdmap_view": 2, "slice": null, "source": "s.vdmap", "view": "global", "size": [320, 240],
    "camera": {"eye": [2.5, -1.5, -2.0], "target": [0.1, 0.2, 1.5], "up": [0, -1, 0], "fov_y_deg": 50},
    "up_axis": "data", "color": "rgb", "draw": "ellipsoids", "sigma": 2, "sphere_level": 0,
    "points_below_px": 4, "background": "white",
    "layers": {"frustums": true, "graph": true, "trajectory": true, "groundtruth": true, "legend": true,
               "grid": false, "bounds": true},
    "selected_keyframe": -1, "thresholds": {}})");
  // thresholds are required in full: the reader names the first missing one.
  const auto partial =
      runVdmap("render '" + out("s.vdmap") + "' --view-file '" + out("v.json") + "' --out '" + out("v.png") + "'");
  EXPECT_EQ(partial.exit_code, 1);
  EXPECT_NE(partial.err.find("v.json: missing key 'thresholds."), std::string::npos) << partial.err;
  EXPECT_EQ(std::count(partial.err.begin(), partial.err.end(), '\n'), 1) << partial.err;
  EXPECT_FALSE(std::filesystem::exists(out("v.png")));
  // A file the window saves has every threshold: take them from one written by the view core.
  std::string text = test::readFile(out("v.json"));
  {
    render::ViewSpec spec;
    app::writeViewFile(out("full.json"), spec, GlobalMapParams{}, "s.vdmap");
    nlohmann::json view = nlohmann::json::parse(text);
    view["thresholds"] = nlohmann::json::parse(test::readFile(out("full.json")))["thresholds"];
    text = view.dump(2);
  }
  writeText(out("v.json"), text);
  const auto from_file =
      runVdmap("render '" + out("s.vdmap") + "' --view-file '" + out("v.json") + "' --out '" + out("v.png") + "'");
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  const auto from_flags =
      render("f.png", "--look-at 2.5,-1.5,-2.0,0.1,0.2,1.5 --up 0,-1,0 --fov 50 --background white");
  ASSERT_EQ(from_flags.exit_code, 0) << from_flags.err;
  const cv::Mat a = png(out("v.png")), b = png(out("f.png"));
  ASSERT_EQ(a.size(), cv::Size(320, 240)) << "the view file's size";
  EXPECT_EQ(maxDifference(a, b), 0.0);
  ASSERT_EQ(render("d.png", "--background white").exit_code, 0);
  EXPECT_GT(maxDifference(a, png(out("d.png"))), 0.0) << "the camera is not the default one";
  // A flag beside the view file overrides it.
  const auto dark = runVdmap("render '" + out("s.vdmap") + "' --view-file '" + out("v.json") +
                             "' --background dark --out '" + out("vd.png") + "'");
  ASSERT_EQ(dark.exit_code, 0) << dark.err;
  EXPECT_EQ(png(out("vd.png")).at<cv::Vec3b>(0, 0), cv::Vec3b(38, 33, 33));
}

TEST_F(RenderSessionCli, ASettingsFileGivesTheWindowsThresholds) {
  const auto plain = render("p.png", "");
  writeText(out("settings.json"), R"({"thresholds": {"filter_sigma_factor": 1.0}})");
  const auto with_file = render("s.png", "--settings '" + out("settings.json") + "'");
  const auto with_set = render("t.png", "--set filter_sigma_factor=1.0");
  ASSERT_EQ(with_file.exit_code, 0) << with_file.err;
  ASSERT_EQ(with_set.exit_code, 0) << with_set.err;
  EXPECT_NE(with_file.err.find("note: settings: " + out("settings.json") + " over the session's thresholds\n"),
            std::string::npos)
      << with_file.err;
  EXPECT_LT(ellipsoidsDrawn(with_file.out), ellipsoidsDrawn(plain.out)) << "k = 1 keeps fewer ellipsoids";
  EXPECT_EQ(ellipsoidsDrawn(with_file.out), ellipsoidsDrawn(with_set.out));
  // --set comes over --settings.
  const auto both = render("b.png", "--settings '" + out("settings.json") + "' --set filter_sigma_factor=3");
  EXPECT_EQ(ellipsoidsDrawn(both.out), ellipsoidsDrawn(plain.out));
  // A malformed file is one line and exit 1.
  writeText(out("bad.json"), R"({"thresholds": {"filter_sigma_factor": "many"}})");
  const auto bad = render("bad.png", "--settings '" + out("bad.json") + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(bad.err.rfind("vdmap render: error: " + out("bad.json") + ": ", 0), 0u) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
}

TEST_F(RenderSessionCli, AViewFileServesAsSettings) {
  render::ViewSpec spec;
  GlobalMapParams thresholds;
  thresholds.filter.filter_sigma_factor = 1.0;
  app::writeViewFile(out("tv.json"), spec, thresholds, "s.vdmap");
  const auto r = render("tv.png", "--settings '" + out("tv.json") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ellipsoidsDrawn(r.out), ellipsoidsDrawn(render("t1.png", "--set filter_sigma_factor=1.0").out));
  EXPECT_NE(r.err.find("note: settings: " + out("tv.json") + " over the session's thresholds"), std::string::npos);
  // A sequence has no session thresholds: the defaults, or the file alone.
  const auto seq_default = runVdmap("render " + seq() + " --size 64x48 --out '" + out("sd.png") + "'");
  EXPECT_NE(seq_default.err.find("note: settings: defaults\n"), std::string::npos) << seq_default.err;
}

// 7-Scenes' kitchen (its cameras' y axis is not the world's z): the default view is upright
// (the floor below the table tops in the image) and framed (the robust box inside the image,
// spanning most of it), as the window shows it.
TEST(RenderCli, TheKitchenRendersUprightAndFramed) {
  VDMAP_REQUIRE_SHARED_DATA(folder, "7scenes-redkitchen");
  TempDir tmp;
  const auto mapped = runVdmap("map '" + folder.string() + "' --frames 0:150 --out '" + (tmp / "m").string() +
                               "' --save '" + (tmp / "k.vdmap").string() + "'");
  ASSERT_EQ(mapped.exit_code, 0) << mapped.err;
  const auto r =
      runVdmap("render '" + (tmp / "k.vdmap").string() + "' --size 640x360 --out '" + (tmp / "k.png").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex(R"(up \((\S+), (\S+), (\S+)\)\))"))) << r.out;
  const glm::vec3 up = glm::normalize(glm::vec3(std::stof(m[1]), std::stof(m[2]), std::stof(m[3])));
  std::printf("kitchen: up (%.2f, %.2f, %.2f)\n", up.x, up.y, up.z);
  EXPECT_LT(std::abs(up.z), 0.9f) << "not the +z convention: the kitchen's up is not its z axis";
  // The view the render drew, from the session (the same framing functions).
  const Session session = loadSession(tmp / "k.vdmap");
  const render::GraphScene graph = render::graphSceneOf(session.graph, session.info.state, session.info.camera, false);
  const std::vector<Ellipsoid> map = buildGlobalMap(session.graph, session.info.global).ellipsoids;
  std::vector<glm::vec3> means;
  for (const Ellipsoid& e : map) means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
  render::ViewScene scene;
  scene.bounds = render::frameBounds(means, graph);
  scene.up = up;
  const render::ViewCamera view = render::viewCamera(render::ViewSpec{}, scene, 640, 360).camera;
  const auto project = [&](const glm::vec3& p) {
    const glm::vec4 q = view.T_C_W * glm::vec4(p, 1.f);
    return glm::vec2(view.fx * q.x / q.z + view.cx, view.fy * q.y / q.z + view.cy);
  };
  const auto [lo, hi] = render::robustBounds(means);
  glm::vec2 a(INFINITY), b(-INFINITY);
  for (int c = 0; c < 8; ++c) {
    const glm::vec2 p = project({(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
    a = glm::min(a, p), b = glm::max(b, p);
  }
  EXPECT_GE(a.x, 0.f);
  EXPECT_GE(a.y, 0.f);
  EXPECT_LE(b.x, 640.f);
  EXPECT_LE(b.y, 360.f);
  EXPECT_GE(std::max((b.x - a.x) / 640.f, (b.y - a.y) / 360.f), 0.6f);
  // Upright: the lowest fifth of the means (along up) lies lower in the image than the highest.
  std::vector<std::pair<float, float>> height_row;
  for (const glm::vec3& p : means) height_row.emplace_back(glm::dot(p, up), project(p).y);
  std::sort(height_row.begin(), height_row.end());
  const std::size_t fifth = height_row.size() / 5;
  double low_rows = 0, high_rows = 0;
  for (std::size_t i = 0; i < fifth; ++i)
    low_rows += height_row[i].second, high_rows += height_row[height_row.size() - 1 - i].second;
  EXPECT_GT(low_rows / fifth, high_rows / fifth + 20.0) << "the floor is not below the rest in the image";
  // The image: dark, and the map fills a good part of it.
  const cv::Mat img = png((tmp / "k.png").string());
  EXPECT_EQ(img.at<cv::Vec3b>(0, 0), cv::Vec3b(38, 33, 33));
  cv::Mat drawn;
  cv::inRange(img, cv::Scalar(30, 25, 25), cv::Scalar(46, 41, 41), drawn);
  const cv::Rect box = cv::boundingRect(~drawn);
  std::printf("kitchen: drawn box %dx%d of 640x360\n", box.width, box.height);
  EXPECT_GE(std::max(box.width / 640.0, box.height / 360.0), 0.6);
}

TEST(SynthCli, WritesASequenceAndRejectsBadTrajectories) {
  TempDir tmp;
  writeText(tmp / "square.ply", kSquarePly);
  writeText(tmp / "traj.txt",
            "# t tx ty tz qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 0.01 0 0 0 0 0 1\n0.2 0.02 0 0 0 0 0 1\n");
  const std::string mesh = " --mesh '" + (tmp / "square.ply").string() + "'";
  auto r = runVdmap("synth" + mesh + " --trajectory '" + (tmp / "traj.txt").string() +
                    "' --camera tum-default --noise none --frames 1: --out '" + (tmp / "seq").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Sequence seq = Sequence::open(tmp / "seq");
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
