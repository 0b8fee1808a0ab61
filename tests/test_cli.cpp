// End-to-end tests of the vdmap command line: exit codes and one-line errors.
#include <algorithm>

#include <gtest/gtest.h>

#include "tests/test_util.h"

namespace vdmap {
namespace {

using test::runVdmap;

TEST(Cli, HelpListsVerbs) {
  const auto r = runVdmap("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* verb : {"info", "map", "render", "bench", "synth", "eval", "gui"})
    EXPECT_NE(r.out.find(verb), std::string::npos) << verb;
  EXPECT_EQ(runVdmap("info --help").exit_code, 0);
}

TEST(Cli, InfoOnTinySequence) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 4);
  const auto r = runVdmap("info '" + (dir / "seq").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"frames\": 4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("file camera.yaml"), std::string::npos) << r.out;
}

TEST(Cli, BadInputIsOneLineErrorAndNonZeroExit) {
  const auto r = runVdmap("info /nonexistent/seq");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "vdmap info: error: /nonexistent/seq: no such sequence folder\n");
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
  const auto no_file = runVdmap("eval --map x.ply --mesh /nonexistent/mesh.ply");
  EXPECT_NE(no_file.exit_code, 0);
  EXPECT_EQ(std::count(no_file.err.begin(), no_file.err.end(), '\n'), 1) << no_file.err;
  EXPECT_NE(no_file.err.find("/nonexistent/mesh.ply"), std::string::npos) << no_file.err;
}

TEST(Cli, InfoOnSevenScenes) {
  VDMAP_REQUIRE_SHARED_DATA(folder, "7scenes-redkitchen");
  const auto r = runVdmap("info '" + folder.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("500 usable (all with poses)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("preset 7scenes"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace vdmap
