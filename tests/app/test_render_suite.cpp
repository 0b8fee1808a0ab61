// `vdmap render --expect` (one image against its golden) and `--suite` (many views of loaded-once
// maps against theirs), end to end on a session of the built-in room; and the session's lazy
// images that let render skip decoding them.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "app/view/render_check.h"
#include "app/view/view_file.h"
#include "mapping/core/error.h"
#include "mapping/files/session_file.h"
#include "mapping/synth/builtin_scene.h"
#include "render/image_compare.h"
#include "render/sequence_synth.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

using test::runVdmap;
using test::TempDir;
using test::writeText;

// The lines of stderr that are not notes ("vdmap VERB: note: ...", e.g. the settings' source).
int lines(const std::string& text) {
  int n = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    n += text.substr(at, end - at).find(": note: ") == std::string::npos;
    at = end + 1;
  }
  return n;
}

int occurrences(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The first `frames` poses of a 40-pose walk around the built-in room (big steps: a keyframe
// every few poses), mapped by the binary into DIR/map and DIR/s.vdmap.
void saveWalkSession(const std::filesystem::path& dir, int frames) {
  const BuiltinScene scene = makeBuiltinScene({.frames = 40});
  render::SynthOptions options;
  options.camera = scene.camera;
  options.last_frame = frames;
  render::synthesizeSequence(scene.mesh, scene.trajectory, options, dir / "room");
  const auto saved = runVdmap("map '" + (dir / "room").string() + "' --out '" + (dir / "map").string() + "' --save '" +
                              (dir / "s.vdmap").string() + "'");
  ASSERT_EQ(saved.exit_code, 0) << saved.err;
}

// The first 10 poses of the walk (a few keyframes), saved as a session once for all tests.
class RenderGolden : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    saveWalkSession(dir_->path(), 10);
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string quoted(const std::filesystem::path& p) { return std::string("'").append(p.string()).append("'"); }
  static std::string session() { return quoted(*dir_ / "s.vdmap"); }
  // A golden of the global view at 160x120 in `dir`.
  static std::filesystem::path makeGolden(const TempDir& dir, const std::string& extra = "") {
    const auto golden = dir / "g.png";
    const auto r = runVdmap("render " + session() + " --size 160x120 --expect " + quoted(golden) + " --update" + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return golden;
  }
  static TempDir* dir_;
};
TempDir* RenderGolden::dir_ = nullptr;

TEST_F(RenderGolden, AnImageWithinToleranceExitsZero) {
  TempDir tmp;
  const auto golden = makeGolden(tmp);
  // Within the default tolerance: every pixel off by 5 counts, and 1 % of them off by far more.
  cv::Mat img = test::readImage(golden);
  ASSERT_EQ(img.size(), cv::Size(160, 120));
  img += cv::Scalar::all(5);
  img(cv::Rect(0, 0, 16, 12)) = cv::Scalar(0, 0, 255);  // 192 of 19200 pixels
  test::writeImage(golden, img);
  auto r = runVdmap("render " + session() + " --size 160x120 --expect " + quoted(golden));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("matches"), std::string::npos) << r.out;
  EXPECT_EQ(lines(r.err), 0) << r.err;
  // The same image against a tolerance of 0.5 % of the pixels and 4 counts: every pixel differs.
  r = runVdmap("render " + session() + " --size 160x120 --expect " + quoted(golden) + " --tolerance 4,0.5%");
  EXPECT_EQ(r.exit_code, 2) << r.err;
}

TEST_F(RenderGolden, AChangedColourExitsTwoWithOneLineAndADiffImage) {
  TempDir tmp;
  const auto golden = makeGolden(tmp);
  const auto diff = tmp / "d.png";
  const auto r = runVdmap("render " + session() + " --size 160x120 --expect " + quoted(golden) +
                          " --color keyframe --diff " + quoted(diff));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("vdmap render: differs: " + golden.string() + ": "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("differ by more than 8 counts"), std::string::npos) << r.err;
  const cv::Mat d = test::readImage(diff);
  ASSERT_EQ(d.size(), cv::Size(160, 120)) << "the diff image was not written";
  cv::Mat red;
  cv::inRange(d, cv::Scalar(0, 0, 255), cv::Scalar(0, 0, 255), red);  // BGR
  EXPECT_GT(cv::countNonZero(red), 100) << "the differing pixels are red";
  EXPECT_EQ(std::filesystem::directory_iterator(tmp.path()) == std::filesystem::directory_iterator(), false);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(tmp.path()), std::filesystem::directory_iterator()), 2)
      << "the golden and the diff only (no --out, nothing else)";
}

TEST_F(RenderGolden, UpdateWritesTheGoldenAndTheNextRunPasses) {
  TempDir tmp;
  const auto golden = tmp / "kf.png";
  auto r = runVdmap("render " + session() + " --view keyframe:1 --expect " + quoted(golden));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no such golden image (render it once with --update)"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(golden));
  r = runVdmap("render " + session() + " --view keyframe:1 --expect " + quoted(golden) + " --update");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(std::filesystem::exists(golden));
  r = runVdmap("render " + session() + " --view keyframe:1 --expect " + quoted(golden));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // The golden is the keyframe view at its default size, the camera's.
  EXPECT_EQ(test::readImage(golden).size(), cv::Size(640, 480));
}

TEST_F(RenderGolden, TimingsNameEveryStageOnOneNoteLine) {
  TempDir tmp;
  const auto r = runVdmap("render " + session() + " --size 160x120 --out " + quoted(tmp / "o.png") + " --timings");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(occurrences(r.err, "vdmap render: note: timings: context "), 1) << r.err;
  EXPECT_NE(r.err.find(", load "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(", total "), std::string::npos) << r.err;
}

// A session whose keyframe 0 holds a colour image that does not decode.
void saveSessionWithABrokenImage(const std::filesystem::path& file) {
  Mapper mapper = test::mapTurningBoxRoom(2);
  KeyframeGraph graph = mapper.graph();
  Keyframe& k = graph.keyframe(0);
  k.rgb_image =
      CompressedImage::fromEncoded(k.rgb_image.rows(), k.rgb_image.cols(), CV_8UC3, "\x89PNG not really", false);
  saveSession(file, graph, sessionInfo(mapper, {}));
}

TEST(SessionImages, LoadWithoutDecodingThenDecodeOneKeyframeNamingIt) {
  TempDir tmp;
  saveSessionWithABrokenImage(tmp / "s.vdmap");
  EXPECT_THROW(loadSession(tmp / "s.vdmap"), InputError) << "the workbench's eager load checks every image";
  const Session s = loadSession(tmp / "s.vdmap", {.decode_images = false});
  ASSERT_GE(s.graph.size(), 1u);
  try {
    keyframeImage(s.graph.keyframe(0), "s.vdmap");
    FAIL() << "the broken image decoded";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("s.vdmap: keyframe 0: rgb image: cannot decode colour image", 0), 0u)
        << e.what();
  }
}

TEST(SessionImages, RenderDrawsTheGlobalViewOfASessionWithABrokenImageAndRefusesItsContainer) {
  TempDir tmp;
  saveSessionWithABrokenImage(tmp / "s.vdmap");
  auto r =
      runVdmap("render '" + (tmp / "s.vdmap").string() + "' --size 80x60 --out '" + (tmp / "g.png").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << "the global view needs no keyframe image: " << r.err;
  r = runVdmap("render '" + (tmp / "s.vdmap").string() + "' --view container:0 --out '" + (tmp / "c.png").string() +
               "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("s.vdmap: keyframe 0: rgb image: cannot decode colour image"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "c.png"));
}

// --- suites ---------------------------------------------------------------------------------

class RenderSuite : public RenderGolden {
 protected:
  // A suite of four views of the session (two global, a keyframe view, a container).
  static void writeSuite(const TempDir& tmp, const std::string& extra_view = "") {
    writeText(tmp / "views.yaml",
              "version: 1\n"
              "goldens: goldens\n"
              "out: out\n"
              "maps:\n"
              "  room: " +
                  (*dir_ / "s.vdmap").string() +
                  "\n"
                  "views:\n"
                  "  - {name: global, map: room, size: 160x120}\n"
                  "  - {name: orbit, map: room, size: 160x120, orbit: \"30,20\"}\n"
                  "  - {name: kf1, map: room, view: \"keyframe:1\", size: 160x120, color: uncertainty}\n"
                  "  - {name: c1, map: room, view: \"container:1\", size: 320x240, tolerance: {share: 0.01}}\n" +
                  extra_view);
  }
  static test::RunResult runSuite(const TempDir& tmp, const std::string& extra = "") {
    return runVdmap("render --suite '" + (tmp / "views.yaml").string() + "'" + extra);
  }
};

TEST_F(RenderSuite, RendersEveryViewAndLoadsEachMapOnce) {
  TempDir tmp;
  writeSuite(tmp);
  auto r = runSuite(tmp, " --update");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("maps loaded: 1, global maps built: 1"), std::string::npos) << r.out;
  for (const char* view : {"global", "orbit", "kf1", "c1"})
    EXPECT_TRUE(std::filesystem::exists(tmp / "goldens" / (std::string(view) + ".png"))) << view;
  EXPECT_EQ(test::readImage((tmp / "goldens" / "c1.png")).size(), cv::Size(320, 240));
  r = runSuite(tmp);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("maps loaded: 1, global maps built: 1"), std::string::npos) << r.out;
  EXPECT_EQ(occurrences(r.out, "| pass "), 4) << r.out;
  EXPECT_NE(r.out.find("view"), std::string::npos);
  EXPECT_NE(r.out.find("differing px"), std::string::npos) << r.out;
  // The orbit is another picture than the default view.
  EXPECT_GT(cv::norm(test::readImage((tmp / "goldens" / "global.png")),
                     test::readImage((tmp / "goldens" / "orbit.png")), cv::NORM_L1),
            0.0);
}

TEST_F(RenderSuite, EachMapLoadsOnceAndEachSetOfThresholdsBuildsOneGlobalMap) {
  // Two maps (the session and its `vdmap map` folder); the session's views with two sets of
  // thresholds: two loads, two global maps built (the folder's is read).
  TempDir tmp;
  writeText(tmp / "views.yaml",
            "version: 1\nmaps:\n  room: " + (*dir_ / "s.vdmap").string() + "\n  folder: " + (*dir_ / "map").string() +
                "\nviews:\n"
                "  - {name: a, map: room, size: 80x60}\n"
                "  - {name: b, map: room, size: 80x60, orbit: \"0,30\"}\n"
                "  - {name: c, map: room, size: 80x60, set: [filter_sigma_factor=1.5]}\n"
                "  - {name: d, map: room, size: 80x60, view: \"keyframe:0\", set: [filter_sigma_factor=1.5]}\n"
                "  - {name: e, map: folder, size: 80x60}\n"
                "  - {name: f, map: folder, size: 80x60, color: count}\n");
  const auto r = runSuite(tmp, " --update");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("maps loaded: 2, global maps built: 2"), std::string::npos) << r.out;
  // The thresholds took effect: the stricter filter keeps fewer ellipsoids, another picture.
  EXPECT_GT(
      cv::norm(test::readImage((tmp / "goldens" / "a.png")), test::readImage((tmp / "goldens" / "c.png")), cv::NORM_L1),
      0.0);
}

TEST_F(RenderSuite, EachQuerySliceIsOfItsOwnViewsThresholds) {
  // Views alternating between thresholds, each with the query slice: every slice is the one a
  // single render with those thresholds draws (the suite's cache of point queries follows the
  // thresholds, however many global maps it holds).
  TempDir tmp;
  const std::string slice = "size: 80x60, query-slice: up=0.5, query-slice-color: distance";
  const char* sets[] = {"", "filter_sigma_factor=1.5", "min_points=40", "", "filter_sigma_factor=1.5"};
  std::string views;
  for (int i = 0; i < 5; ++i)
    views += "  - {name: v" + std::to_string(i) + ", map: room, " + slice +
             (*sets[i] ? std::string(", set: [") + sets[i] + "]" : "") + "}\n";
  writeText(tmp / "views.yaml", "version: 1\nmaps:\n  room: " + (*dir_ / "s.vdmap").string() + "\nviews:\n" + views);
  ASSERT_EQ(runSuite(tmp, " --update").exit_code, 0);
  for (int i = 0; i < 5; ++i) {
    const auto one = tmp / ("one" + std::to_string(i) + ".png");
    const auto r = runVdmap("render '" + (*dir_ / "s.vdmap").string() + "' --out '" + one.string() +
                            "' --size 80x60 --query-slice up=0.5 --query-slice-color distance" +
                            (*sets[i] ? std::string(" --set ") + sets[i] : ""));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(cv::norm(test::readImage(one), test::readImage(tmp / "goldens" / ("v" + std::to_string(i) + ".png")),
                       cv::NORM_INF),
              0.0)
        << i;
  }
}

TEST_F(RenderSuite, ViewFilesAndSettingsAreReadRelativeToTheSuite) {
  // A view file beside the suite (white, an explicit camera) draws what render --view-file draws;
  // the suite's settings (a view file's thresholds: a stricter filter) reach every view.
  TempDir tmp;
  std::filesystem::create_directories(tmp / "suite");
  render::ViewSpec spec;
  spec.width = 96;
  spec.height = 72;
  spec.background = render::kWhiteBackground;
  spec.look_at = render::LookAt{.eye = {2.f, -2.f, 2.f}, .target = {0.f, 0.f, 0.5f}, .up = {0.f, 0.f, 1.f}};
  app::writeViewFile(tmp / "suite" / "white.json", spec, GlobalMapParams{}, "s.vdmap");
  GlobalMapParams strict;
  strict.filter.filter_sigma_factor = 1.0;
  app::writeViewFile(tmp / "suite" / "strict.json", render::ViewSpec{}, strict, "s.vdmap");
  const std::string head = "version: 1\nmaps: {room: " + (*dir_ / "s.vdmap").string() + "}\n";
  writeText(tmp / "suite" / "views.yaml", head + "views:\n  - {name: white, map: room, view-file: white.json}\n"
                                                 "  - {name: plain, map: room, size: 96x72}\n");
  writeText(tmp / "suite" / "strict.yaml", head + "settings: strict.json\ngoldens: strict\n"
                                                  "views:\n  - {name: plain, map: room, size: 96x72}\n");
  for (const char* suite : {"views.yaml", "strict.yaml"}) {
    const auto r = runVdmap("render --suite '" + (tmp / "suite" / suite).string() + "' --update");
    ASSERT_EQ(r.exit_code, 0) << suite << ": " << r.err;
  }
  const auto white = tmp / "suite" / "goldens" / "white.png";
  const auto r = runVdmap("render " + session() + " --view-file " + quoted(tmp / "suite" / "white.json") +
                          " --expect " + quoted(white) + " --tolerance 0,0");
  EXPECT_EQ(r.exit_code, 0) << "the suite's view is render --view-file's, pixel for pixel: " << r.err;
  EXPECT_EQ(test::readImage(white).at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  EXPECT_GT(cv::norm(test::readImage((tmp / "suite" / "goldens" / "plain.png")),
                     test::readImage((tmp / "suite" / "strict" / "plain.png")), cv::NORM_L1),
            0.0)
      << "the suite's settings did not reach the view";
}

TEST_F(RenderSuite, WritesJUnitXmlWithOneTestcasePerView) {
  TempDir tmp;
  writeSuite(tmp);
  ASSERT_EQ(runSuite(tmp, " --update").exit_code, 0);
  const auto r = runSuite(tmp);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string xml = test::readFile(tmp / "out" / "junit.xml");
  EXPECT_EQ(occurrences(xml, "<testcase "), 4) << xml;
  EXPECT_NE(xml.find("<testsuite name=\"views.yaml\" tests=\"4\" failures=\"0\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("classname=\"vdmap.render.room\" name=\"kf1\""), std::string::npos) << xml;
}

TEST_F(RenderSuite, OneDifferingViewFailsTheSuiteWithExitTwo) {
  TempDir tmp;
  writeSuite(tmp);
  ASSERT_EQ(runSuite(tmp, " --update").exit_code, 0);
  // The orbit's golden gets a block of another colour over a fifth of it.
  cv::Mat img = test::readImage((tmp / "goldens" / "orbit.png"));
  img(cv::Rect(0, 0, 80, 48)) = cv::Scalar(255, 0, 255);
  test::writeImage((tmp / "goldens" / "orbit.png"), img);
  const auto r = runSuite(tmp);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("1 of 4 views differ from their goldens: orbit"), std::string::npos) << r.err;
  EXPECT_EQ(occurrences(r.out, "| DIFFERS "), 1) << r.out;
  EXPECT_TRUE(std::filesystem::exists(tmp / "out" / "orbit.actual.png"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "out" / "orbit.diff.png"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "out" / "global.actual.png")) << "only failing views leave images";
  const std::string xml = test::readFile(tmp / "out" / "junit.xml");
  EXPECT_NE(xml.find("tests=\"4\" failures=\"1\""), std::string::npos) << xml;
  EXPECT_EQ(occurrences(xml, "<failure "), 1) << xml;
}

TEST_F(RenderSuite, ABadViewStopsTheSuiteBeforeAnythingIsWritten) {
  TempDir tmp;
  writeSuite(tmp, "  - {name: far, map: room, view: \"container:99\"}\n");
  const auto r = runSuite(tmp, " --update");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("views.yaml:11: view 'far': "), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "goldens")) << "nothing is written before the whole suite is valid";
  EXPECT_FALSE(std::filesystem::exists(tmp / "out"));
}

TEST_F(RenderSuite, SuiteOptionsExcludeASingleViewsOptions) {
  TempDir tmp;
  writeSuite(tmp);
  const auto r = runSuite(tmp, " --expect '" + (tmp / "g.png").string() + "'");
  EXPECT_GE(r.exit_code, 100) << r.err;
  EXPECT_LE(r.exit_code, 114) << r.err;
  EXPECT_NE(r.err.find("--suite excludes --expect"), std::string::npos) << r.err;
}

// --- a suite's details: missing goldens, --update VIEW..., orphans, the command line's options

TEST_F(RenderSuite, AViewWithoutAGoldenFailsAloneAndUpdateNamesViews) {
  TempDir tmp;
  writeSuite(tmp, "  - {name: slice, map: room, size: 80x60, query-slice: up=1.0, query-slice-color: distance}\n");
  auto r = runSuite(tmp, " --update global orbit");
  ASSERT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.out.find("goldens changed: global (new), orbit (new)"), std::string::npos) << r.out;
  EXPECT_EQ(occurrences(r.out, "| NO GOLDEN "), 3) << r.out;
  EXPECT_NE(r.err.find("3 of 5 views differ from their goldens: kf1 (no golden), c1 (no golden), slice (no golden)"),
            std::string::npos)
      << r.err;
  std::string xml = test::readFile(tmp / "out" / "junit.xml");
  EXPECT_NE(xml.find("<failure message=\"no golden: goldens/kf1.png (write it with --update kf1)\""), std::string::npos)
      << "a path relative to the suite file: " << xml;
  EXPECT_TRUE(std::filesystem::exists(tmp / "out" / "kf1.actual.png"));
  // A plain --update writes the rest and says which goldens changed; an orphan is listed.
  test::writeImage(tmp / "goldens" / "gone.png", cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(0)));
  r = runSuite(tmp, " --update");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("goldens changed: kf1 (new), c1 (new), slice (new)"), std::string::npos) << r.out;
  EXPECT_EQ(occurrences(r.out, "| same "), 2) << r.out;
  EXPECT_NE(r.out.find("orphan goldens (no view of the suite names them) in goldens: gone.png"), std::string::npos)
      << r.out;
  EXPECT_GT(cv::norm(test::readImage(tmp / "goldens" / "slice.png"),
                     test::readImage(tmp / "goldens" / "global.png")(cv::Rect(0, 0, 80, 60)), cv::NORM_L1),
            0.0);
  r = runSuite(tmp, " --update nothere");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--update nothere: no view of that name"), std::string::npos) << r.err;
}

TEST_F(RenderSuite, OutSetSettingsAndAShareInPercentWorkWithSuites) {
  TempDir tmp;
  writeText(tmp / "views.yaml",
            "version: 1\ntolerance: {share: 2.5%}\ncompare: plain\nmaps: {room: " + (*dir_ / "s.vdmap").string() +
                "}\nviews:\n  - {name: a, map: room, size: 80x60}\n");
  ASSERT_EQ(runSuite(tmp, " --update").exit_code, 0);
  // A stricter filter for every view from the command line: another picture, reported in --out.
  auto r = runSuite(tmp, " --set filter_sigma_factor=1.0 --out '" + (tmp / "o").string() + "' --tolerance 8,0");
  EXPECT_EQ(r.exit_code, 2) << r.err << r.out;
  EXPECT_TRUE(std::filesystem::exists(tmp / "o" / "junit.xml"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "o" / "a.diff.png"));
  GlobalMapParams strict;
  strict.filter.filter_sigma_factor = 1.0;
  app::writeViewFile(tmp / "strict.json", render::ViewSpec{}, strict, "s.vdmap");
  r = runSuite(tmp, " --settings '" + (tmp / "strict.json").string() + "' --tolerance 8,0");
  EXPECT_EQ(r.exit_code, 2) << "--settings reached the view: " << r.err << r.out;
  r = runSuite(tmp, " --tolerance 8,0");
  EXPECT_EQ(r.exit_code, 0) << r.err << r.out;
}

TEST_F(RenderSuite, EveryOptionTheWorkbenchSpellsOutIsAViewKey) {
  // The workbench's Copy render command spells out every field of the view it saves; each
  // option becomes a key of a suite view, which draws what the saved view file draws.
  TempDir tmp;
  render::ViewSpec spec;
  spec.width = 96;
  spec.height = 72;
  spec.look_at = render::LookAt{.eye = {2.f, -2.f, 2.f}, .target = {0.f, 0.f, 0.5f}, .up = {0.f, 0.f, 1.f}};
  spec.look_at->fov_y_deg = 50.f;
  spec.color = render::ColorMode::kKeyframe;
  spec.setDraw(render::DrawMode::kCentres);
  spec.slice = {.on = true, .lo_m = 0.2f, .hi_m = 1.5f};
  spec.sigma = 2.f;
  spec.sphere_level = 2;
  spec.points_below_px = 2.f;
  spec.background = render::kWhiteBackground;
  spec.layers.graph = false;
  spec.layers.bounds = false;
  spec.layers.mesh = true;
  spec.mesh_style = render::MeshStyle::kWireframe;
  spec.selected_keyframe = 1;
  app::writeViewFile(tmp / "v.json", spec, GlobalMapParams{}, "s.vdmap");
  std::istringstream command(app::renderCommand(spec, "s.vdmap"));
  std::string word, view = "  - {name: all, map: room";
  int keys = 0;
  for (command >> word >> word >> word; command >> word && word != "--out"; ++keys) {
    std::string value;
    command >> value;
    view += ", " + word.substr(2) + ": \"" + value + "\"";
  }
  EXPECT_GE(keys, 12) << view;
  writeText(tmp / "views.yaml", "version: 1\ncompare: plain\ntolerance: {counts: 0, share: 0}\nmaps: {room: " +
                                    (*dir_ / "s.vdmap").string() + "}\nviews:\n" + view +
                                    "}\n  - {name: file, map: room, view-file: v.json}\n");
  auto r = runSuite(tmp, " --update");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const cv::Mat all = test::readImage(tmp / "goldens" / "all.png"),
                file = test::readImage(tmp / "goldens" / "file.png");
  ASSERT_EQ(all.size(), cv::Size(96, 72));
  EXPECT_EQ(cv::norm(all, file, cv::NORM_INF), 0.0) << "the keys draw what the view file draws";
  EXPECT_NE(view.find("mesh-style: \"wireframe\""), std::string::npos) << view;
  const render::ViewSpec read = app::readViewFile(tmp / "v.json");
  EXPECT_TRUE(read.layers.mesh);
  EXPECT_EQ(read.mesh_style, render::MeshStyle::kWireframe);
}

// --- the nearby compare: another driver passes, a real change fails --------------------------

// A session of 20 frames of the built-in walk (7 keyframes) and a suite of three views at
// 640x480 whose goldens llvmpipe draws (at 320x240 a merge seen from keyframe 3 moves no pixel
// by more than 1 px).
class DriverOrChange : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    saveWalkSession(dir_->path(), 20);
    if (HasFatalFailure()) return;
    writeViews("views.yaml", "-60,35");
    writeViews("orbited.yaml", "-59.8,35");
    const auto r = suite("views.yaml", " --update");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static void writeViews(const std::string& name, const std::string& orbit) {
    writeText(*dir_ / name, "version: 1\nmaps: {room: s.vdmap}\nviews:\n"
                            "  - {name: global, map: room, size: 640x480, orbit: \"" +
                                orbit +
                                "\"}\n"
                                "  - {name: kf3, map: room, size: 640x480, view: \"keyframe:3\"}\n"
                                "  - {name: kf4, map: room, size: 640x480, view: \"keyframe:4\"}\n");
  }
  static test::RunResult suite(const std::string& name, const std::string& extra, const std::string& prefix = "") {
    return runVdmap("render --suite '" + (*dir_ / name).string() + "'" + extra, prefix);
  }
  // The share of pixels the compare `method` finds differing between a view's golden and its actual.
  static double share(const std::string& view, render::CompareMethod method) {
    const cv::Mat golden = test::readImage(*dir_ / "goldens" / (view + ".png"));
    const cv::Mat actual = test::readImage(*dir_ / "render-out" / (view + ".actual.png"));
    const render::ImageComparison c =
        render::compareImages(golden, actual, {.channel_counts = 8, .pixel_share = 1, .method = method});
    std::printf("%s: %.4f %% differ (%s)\n", view.c_str(), 100 * c.share, render::compareMethodName(method));
    return c.share;
  }
  static TempDir* dir_;
};
TempDir* DriverOrChange::dir_ = nullptr;

TEST_F(DriverOrChange, SoftpipeRendersPassTheLlvmpipeGoldens) {
  // The plain compare at 8 counts and no share fails each, so that every actual is written.
  const auto r = suite("views.yaml", " --compare plain --tolerance 8,0", "GALLIUM_DRIVER=softpipe");
  ASSERT_EQ(r.exit_code, 2) << "softpipe drew the same pixels as llvmpipe? " << r.err << r.out;
  for (const char* view : {"global", "kf3", "kf4"}) {
    share(view, render::CompareMethod::kPlain);
    EXPECT_LE(share(view, render::CompareMethod::kNearby), app::kSuiteTolerance.pixel_share) << view;
  }
}

TEST_F(DriverOrChange, AMergeDistanceAndATurnedCameraFail) {
  auto r = suite("views.yaml", " --set merge_distance=0.1");
  EXPECT_EQ(r.exit_code, 2) << r.err << r.out;
  EXPECT_NE(r.err.find("kf3, kf4"), std::string::npos) << r.err;
  for (const char* view : {"kf3", "kf4"}) {
    EXPECT_LT(share(view, render::CompareMethod::kPlain), app::kGoldenTolerance.pixel_share)
        << view << ": the old compare passed it";
    EXPECT_GT(share(view, render::CompareMethod::kNearby), app::kSuiteTolerance.pixel_share) << view;
  }
  r = suite("orbited.yaml", "");
  EXPECT_EQ(r.exit_code, 2) << r.err << r.out;
  EXPECT_NE(r.err.find(": global"), std::string::npos) << r.err;
  share("global", render::CompareMethod::kPlain);
  EXPECT_GT(share("global", render::CompareMethod::kNearby), app::kSuiteTolerance.pixel_share);
}

}  // namespace
}  // namespace vdmap
