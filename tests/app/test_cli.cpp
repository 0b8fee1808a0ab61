// End-to-end tests of the vdmap command line: exit codes and one-line errors.
#include <algorithm>
#include <limits>
#include <new>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/view/progress.h"
#include "mapping/core/message_text.h"
#include "tests/support/test_util.h"
#include "vdmap_version.h"

namespace vdmap {
namespace {

using test::runVdmap;

TEST(Cli, HelpListsVerbs) {
  const auto r = runVdmap("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* verb : {"info", "map", "render", "bench", "synth", "eval", "gui", "query"})
    EXPECT_NE(r.out.find(verb), std::string::npos) << verb;
  EXPECT_EQ(runVdmap("info --help").exit_code, 0);
}

// CLI11 prints each description on one line (some were 700 characters): every line of every
// verb's help fits 100 columns, and no word of a description is lost to the wrapping.
TEST(Cli, HelpLinesFitAHundredColumns) {
  for (const char* verb : {"", "info", "map", "render", "bench", "synth", "eval", "gui", "params", "query"}) {
    const auto r = runVdmap(std::string(verb) + " --help");
    ASSERT_EQ(r.exit_code, 0) << verb;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) EXPECT_LE(line.size(), 100u) << verb << ": " << line;
  }
  const auto gui = runVdmap("gui --help");
  std::string flat = std::regex_replace(gui.out, std::regex("\\s+"), " ");
  EXPECT_NE(flat.find("KEY=VALUE for this run (as in settings.json; not saved): thresholds: filter_sigma_factor,"),
            std::string::npos);
}

// std::bad_alloc says nothing of what was being built: a stage's error names it.
TEST(Cli, MemoryRunningOutNamesTheStage) {
  try {
    app::withStageBar("global map", []() -> int { throw std::bad_alloc(); });
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("out of memory building the global map: ", 0), 0u) << e.what();
  }
}

TEST(Cli, CountsAgreeWithTheirNounsAndNumbersAreShort) {
  EXPECT_EQ(counted(1, "point"), "1 point");
  EXPECT_EQ(counted(0, "point"), "0 points");
  EXPECT_EQ(counted(20, "body"), "20 bodies");
  EXPECT_EQ(counted(2, "key"), "2 keys");
  EXPECT_EQ(counted(2, "box"), "2 boxes");
  EXPECT_EQ(counted(2, "miss"), "2 misses");
  EXPECT_EQ(counted(3, "leaf", "leaves"), "3 leaves");
  EXPECT_EQ(shortNumber(1e308), "1e+308");
  EXPECT_EQ(shortNumber(std::numeric_limits<double>::max()), "1.79769313e+308");
  EXPECT_EQ(shortNumber(0.1), "0.1");
  EXPECT_EQ(shortNumber(1e38f), "1e+38");
  EXPECT_EQ(shortNumber(0.1f), "0.1");
  EXPECT_EQ(shortNumber(123456000.0), "123456000");
}

TEST(Cli, InfoOnTinySequence) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 4);
  const auto r = runVdmap("info '" + (dir / "seq").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"frames\": 4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("file camera.yaml"), std::string::npos) << r.out;
}

// Output that cannot be written is a failure with one line, not a silent success: stdout on a
// full disk, and a file past `ulimit -f` (SIGXFSZ would end the process with no message).
TEST(Cli, AFailedWriteIsAnErrorNamingIt) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 4);
  const std::string seq = "'" + (dir / "seq").string() + "'", err = (dir / "err").string();
  for (const std::string& verb : {"info " + seq + " --json", std::string("--help"), std::string("params --markdown")}) {
    // The runner's own redirections come after these; the run's stderr goes to `err`.
    const auto r = runVdmap(verb + " >/dev/full 2>'" + err + "' || exit $?; :");
    EXPECT_EQ(r.exit_code, 1) << verb;
    EXPECT_NE(test::readFile(err).find("cannot write to standard output"), std::string::npos)
        << verb << ": " << test::readFile(err);
  }
  const auto r =
      runVdmap("map " + seq + " --out '" + (dir / "out").string() + "' --save '" + (dir / "s.vdmap").string() + "'",
               "ulimit -f 8;");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("File too large"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_TRUE(entry.path().filename() == "seq" || entry.path().filename() == "err") << entry.path() << " left behind";
}

TEST(Cli, EveryVerbTellsTheVersion) {
  for (const char* verb : {"map", "render", "query", "gui"}) {
    const auto r = runVdmap(std::string(verb) + " --version");
    EXPECT_EQ(r.exit_code, 0) << verb << ": " << r.err;
    EXPECT_EQ(r.out.rfind("vdmap ", 0), 0u) << verb << ": " << r.out;
  }
}

TEST(Cli, BadInputIsOneLineErrorAndNonZeroExit) {
  const auto r = runVdmap("info /nonexistent/seq");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "vdmap info: error: /nonexistent/seq: no such sequence folder or recording\n");
  test::TempDir dir;
  test::writeTinySequence(dir.path());
  EXPECT_NE(runVdmap("info '" + dir.path().string() + "' --camera nope").err.find("unknown camera preset 'nope'"),
            std::string::npos);
  EXPECT_NE(runVdmap("info '" + dir.path().string() + "' --frames 5:2").exit_code, 0);
  EXPECT_NE(runVdmap("frobnicate").exit_code, 0);
  // Command-line mistakes are one line too, naming the option or file.
  const auto missing = runVdmap("eval --map x.ply");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_EQ(missing.err, "vdmap eval: error: --map requires --mesh (see --help)\n");
  test::writeText(dir / "points.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                      "property float z\nend_header\n0 0 1\n");
  const auto no_file = runVdmap("eval --map '" + (dir / "points.ply").string() + "' --mesh /nonexistent/mesh.ply");
  EXPECT_EQ(no_file.exit_code, 1) << "a missing file is exit 1, not a command-line error";
  EXPECT_EQ(std::count(no_file.err.begin(), no_file.err.end(), '\n'), 1) << no_file.err;
  EXPECT_NE(no_file.err.find("/nonexistent/mesh.ply"), std::string::npos) << no_file.err;
}

TEST(Cli, InfoOnSevenScenes) {
  VDMAP_REQUIRE_SHARED_DATA(folder, "7scenes-redkitchen");
  const auto r = runVdmap("info '" + folder.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("500 usable (all with poses, from groundtruth.txt)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("preset 7scenes"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("colour     fx 525.000 fy 525.000 cx 320.000 cy 240.000, 25.6 mm"), std::string::npos) << r.out;
}

// render without --out is a command-line error with CLI11's code, as map's is.
TEST(Cli, AMissingOutHasTheSameCodeInEveryVerb) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 2);
  const auto map = runVdmap("map '" + (dir / "seq").string() + "'");
  const auto render = runVdmap("render '" + (dir / "seq").string() + "'");
  EXPECT_GT(map.exit_code, 1);
  EXPECT_EQ(render.exit_code, map.exit_code) << render.err;
  EXPECT_EQ(render.err, "vdmap render: error: --out is required (see --help)\n");
}

// The help says that the edge to the previous keyframe is always kept (docs/method.md 5).
TEST(Cli, MapHelpSaysTheEdgeToThePreviousKeyframeIsKept) {
  const auto r = runVdmap("map --help");
  EXPECT_EQ(r.exit_code, 0);
  const std::string flat = std::regex_replace(r.out, std::regex("\\s+"), " ");  // lines wrap at 100 columns
  EXPECT_NE(flat.find("the edge to the previous keyframe is always kept"), std::string::npos) << r.out;
}

// vdmap info reports the range of valid depth and the share of invalid pixels;
// 65535 (7-Scenes' invalid code, 65.535 m there) is not a depth.
TEST(Cli, InfoReportsValidDepthAndTheShareOfInvalidPixels) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 2);  // 64x48, all 7500 (1.5 m at scale 5000)
  for (const char* name : {"000000.png", "000001.png"}) {
    cv::Mat depth(48, 64, CV_16UC1, cv::Scalar(7500));
    depth.rowRange(0, 12).setTo(65535);  // a quarter invalid code
    depth.rowRange(12, 24).setTo(0);     // a quarter no measurement
    depth.at<std::uint16_t>(30, 30) = 10000;
    test::writeImage((dir / "seq" / "depth" / name), depth);
  }
  const auto r = runVdmap("info '" + (dir / "seq").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out)["depth_m"];
  EXPECT_EQ(j["min"], 1.5);
  EXPECT_EQ(j["max"], 2.0);
  EXPECT_EQ(j["invalid_fraction"], 0.5);
  EXPECT_EQ(j["invalid_code_fraction"], 0.25);
  EXPECT_EQ(j["no_depth_fraction"], 0.25);
  const auto text = runVdmap("info '" + (dir / "seq").string() + "'");
  EXPECT_NE(text.out.find("1.500 .. 2.000 m"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("50% invalid (25% 0 = no measurement, 25% 65535 = invalid code)"), std::string::npos)
      << text.out;
}

// `vdmap --version`: the CMake project version and, when the build was configured from a git
// checkout, its commit; exit 0 (it was CLI11's "argument not expected", 109).
TEST(Cli, VersionPrintsTheProjectVersionAndCommit) {
  const auto r = runVdmap("--version");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_TRUE(std::regex_match(r.out, std::regex(R"(vdmap \d+\.\d+\.\d+( \(git [0-9A-Za-z.+-]+\))?\n)"))) << r.out;
  const std::string commit = kGitDescribe[0] ? std::string(" (git ") + kGitDescribe + ")" : "";
  EXPECT_EQ(r.out, std::string("vdmap ") + kVersion + commit + "\n");
}

// render --out names the format: x.jpg is a JPEG (it held PNG bytes), x.png a PNG.
TEST(Cli, RenderWritesTheFormatItsExtensionSays) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 3);
  for (const char* name : {"o.jpg", "o.JPEG", "o.png"}) {
    const auto r =
        runVdmap("render '" + (dir / "seq").string() + "' --size 64x48 --out '" + (dir / name).string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string bytes = test::readFile(dir / name);
    const bool png = std::string(name) == "o.png";
    EXPECT_EQ(bytes.substr(0, png ? 4 : 3), png ? std::string("\x89PNG") : std::string("\xff\xd8\xff")) << name;
    EXPECT_EQ(test::readImage((dir / name)).cols, 64) << name;
  }
}

}  // namespace
}  // namespace vdmap
