// View files (app/view/view_file.h): strict reading, writing, the render command of a view, and
// --settings files (a settings.json or a view file).
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/view/render_view.h"
#include "app/view/view_file.h"
#include "mapping/core/error.h"
#include "tests/support/test_util.h"

namespace vdmap::app {
namespace {

using test::TempDir;

// A view with every key away from its default.
render::ViewSpec unusualSpec() {
  render::ViewSpec spec;
  spec.kind = render::ViewKind::kKeyframe;
  spec.keyframe = 3;
  spec.width = 640;
  spec.height = 360;
  spec.up = render::UpAxis::kMinusY;
  spec.color = render::ColorMode::kUncertainty;
  spec.ellipsoids = false;
  spec.sigma = 1.5f;
  spec.sphere_level = 2;
  spec.points_below_px = 0.f;
  spec.layers = {.frustums = false,
                 .graph = true,
                 .trajectory = false,
                 .groundtruth = true,
                 .legend = false,
                 .grid = true,
                 .bounds = false};
  spec.background = {1.f, 0.f, 0.2f};
  spec.selected_keyframe = 2;
  return spec;
}

TEST(ViewFile, RoundTripsEveryKey) {
  TempDir tmp;
  GlobalMapParams thresholds;
  thresholds.merge_distance_m = 0.31;
  thresholds.occlusion_removal = false;
  render::ViewSpec spec = unusualSpec();
  // The background goes through #rrggbb: a colour of whole counts round-trips exactly.
  spec.background = glm::vec3(255, 0, 51) / 255.f;
  writeViewFile(tmp / "v.json", spec, thresholds, "/abs/s.vdmap");
  GlobalMapParams read_back;
  EXPECT_EQ(readViewFile(tmp / "v.json", &read_back), spec);
  EXPECT_EQ(read_back.merge_distance_m, 0.31);
  EXPECT_FALSE(read_back.occlusion_removal);
  // A camera, with floats that need all their digits.
  render::ViewSpec global;
  global.width = 1280;
  global.height = 720;
  global.look_at = render::LookAt{{0.1f, -2.3456789f, 1.f / 3.f}, {0.f, 0.5f, 0.25f}, {0.f, -0.9f, -0.45f}, 47.5f};
  global.fov_y_deg = 47.5f;
  writeViewFile(tmp / "g.json", global, {}, "x");
  EXPECT_EQ(readViewFile(tmp / "g.json"), global);
}

// Writes a valid view file, then lets `edit` change its JSON.
std::filesystem::path editedViewFile(const TempDir& tmp, const std::function<void(nlohmann::json&)>& edit) {
  writeViewFile(tmp / "v.json", unusualSpec(), {}, "s.vdmap");
  nlohmann::json j = nlohmann::json::parse(test::readFile(tmp / "v.json"));
  edit(j);
  test::writeText(tmp / "e.json", j.dump());
  return tmp / "e.json";
}

std::string errorOf(const std::filesystem::path& file) {
  try {
    readViewFile(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ViewFile, RefusesAMissingKeyNamingIt) {
  TempDir tmp;
  const auto file = editedViewFile(tmp, [](nlohmann::json& j) { j.erase("sigma"); });
  EXPECT_EQ(errorOf(file), file.string() + ": missing key 'sigma'");
  const auto nested = editedViewFile(tmp, [](nlohmann::json& j) { j["layers"].erase("legend"); });
  EXPECT_EQ(errorOf(nested), nested.string() + ": missing key 'layers.legend'");
  const auto threshold = editedViewFile(tmp, [](nlohmann::json& j) { j["thresholds"].erase("merge_distance"); });
  EXPECT_NE(errorOf(threshold).find("missing key 'thresholds.merge_distance'"), std::string::npos)
      << errorOf(threshold);
}

TEST(ViewFile, RefusesANonFiniteNumber) {
  TempDir tmp;
  writeViewFile(tmp / "v.json", unusualSpec(), {}, "s.vdmap");
  std::string text = test::readFile(tmp / "v.json");
  // 1e999 parses as infinity; the camera is null in this file, so give it one.
  text =
      std::regex_replace(text, std::regex(R"("camera": null)"),
                         R"("camera": {"eye": [1e999, 0, 0], "target": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 60})");
  test::writeText(tmp / "inf.json", text);
  EXPECT_EQ(errorOf(tmp / "inf.json"), (tmp / "inf.json").string() + ": camera.eye[0] must be finite");
}

TEST(ViewFile, RefusesAnUnknownKeyAndAValueOutOfRange) {
  TempDir tmp;
  const auto unknown = editedViewFile(tmp, [](nlohmann::json& j) { j["clip"] = 1; });
  EXPECT_EQ(errorOf(unknown).rfind(unknown.string() + ": unknown key 'clip' (valid: vdmap_view, source, view,", 0), 0u)
      << errorOf(unknown);
  const auto level = editedViewFile(tmp, [](nlohmann::json& j) { j["sphere_level"] = 7; });
  EXPECT_NE(errorOf(level).find("sphere_level must be in [0, 3]"), std::string::npos) << errorOf(level);
  const auto colour = editedViewFile(tmp, [](nlohmann::json& j) { j["background"] = "#12345"; });
  EXPECT_NE(errorOf(colour).find("background: '#12345': expected dark, white or #rrggbb"), std::string::npos)
      << errorOf(colour);
  test::writeText(tmp / "bad.json", "{\"vdmap_view\": 1,");
  EXPECT_EQ(errorOf(tmp / "bad.json").rfind((tmp / "bad.json").string() + ": not valid JSON (parse error at line 1", 0),
            0u)
      << errorOf(tmp / "bad.json");
}

TEST(ViewFile, SettingsArgTakesASettingsFileOrAViewFile) {
  TempDir tmp;
  GlobalMapParams thresholds;
  thresholds.merge_distance_m = 0.4;
  writeViewFile(tmp / "v.json", unusualSpec(), thresholds, "s.vdmap");
  EXPECT_EQ(readSettingsArg(tmp / "v.json").thresholds.merge_distance_m, 0.4);
  test::writeText(tmp / "settings.json",
                  R"({"thresholds": {"filter_sigma_factor": 2.5}, "view": {"background": "white"}})");
  gui::Settings base;
  base.thresholds.merge_distance_m = 0.15;  // the session's: kept where the file says nothing
  const gui::Settings s = readSettingsArg(tmp / "settings.json", base);
  EXPECT_EQ(s.thresholds.filter.filter_sigma_factor, 2.5);
  EXPECT_EQ(s.thresholds.merge_distance_m, 0.15);
  EXPECT_EQ(s.background, render::kWhiteBackground);
  // A named file is strict: an error names it (the user's own file only warns).
  test::writeText(tmp / "broken.json", R"({"thresholds": {"filter_sigma_factor": -1}})");
  try {
    readSettingsArg(tmp / "broken.json");
    FAIL() << "a bad value was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((tmp / "broken.json").string() + ": ", 0), 0u) << e.what();
  }
  EXPECT_THROW(readSettingsArg(tmp / "missing.json"), InputError);
}

// The render command of a view, parsed by render's own flags, gives the view back.
TEST(ViewFile, TheRenderCommandParsesBackToTheSameView) {
  render::ViewSpec global;
  global.width = 800;
  global.height = 450;
  global.look_at = render::LookAt{{0.1f, -2.3456789f, 1.f / 3.f}, {0.f, 0.5f, 0.25f}, {0.f, -0.9f, -0.45f}, 47.5f};
  global.fov_y_deg = 47.5f;
  global.color = render::ColorMode::kCount;
  global.background = render::kWhiteBackground;
  global.layers.trajectory = false;
  global.selected_keyframe = 4;
  render::ViewSpec keyframe = unusualSpec();
  keyframe.background = glm::vec3(255, 0, 51) / 255.f;
  render::ViewSpec orbit;
  orbit.orbit = render::Orbit{30.f, 20.f, 4.5f};
  render::ViewSpec upright;  // a user-set up, drawn orthographic
  upright.up_vector = glm::vec3(0.f, -1.f, 0.25f);
  upright.projection = render::Projection::kOrthographic;
  for (const render::ViewSpec& spec : {global, keyframe, orbit, upright}) {
    const std::string command = renderCommand(spec, "/data/s.vdmap");
    ASSERT_EQ(command.rfind("vdmap render /data/s.vdmap ", 0), 0u) << command;
    CLI::App app;
    RenderViewArgs args;
    std::string out, source;
    app.add_option("SOURCE", source);
    app.add_option("--out", out);
    addRenderViewOptions(app, args);
    ASSERT_NO_THROW(app.parse(command.substr(std::string("vdmap render ").size()))) << command;
    EXPECT_EQ(resolveViewSpec(args, std::nullopt).spec, spec) << command;
  }
  EXPECT_EQ(renderCommand(global, "/my maps/s.vdmap", "v.json", "o.png"),
            "vdmap render '/my maps/s.vdmap' --view-file v.json --out o.png");
}

// --- picture stream: view file version 2 (slice, draw none) ---
TEST(ViewFile, Version2RoundTripsTheSliceAndDrawNone) {
  TempDir tmp;
  render::ViewSpec spec;
  spec.slice = {true, 0.25f, 1.75f};
  spec.setDraw(render::DrawMode::kNone);
  writeViewFile(tmp / "v.json", spec, {}, "s.vdmap");
  const nlohmann::json j = nlohmann::json::parse(test::readFile(tmp / "v.json"));
  EXPECT_EQ(j["vdmap_view"], 3);
  EXPECT_EQ(j["slice"], nlohmann::json::array({0.25, 1.75}));
  EXPECT_EQ(j["draw"], "none");
  const render::ViewSpec back = readViewFile(tmp / "v.json");
  EXPECT_EQ(back, spec);
  EXPECT_EQ(back.draw(), render::DrawMode::kNone);
  spec.slice.on = false;
  writeViewFile(tmp / "off.json", spec, {}, "s.vdmap");
  EXPECT_TRUE(nlohmann::json::parse(test::readFile(tmp / "off.json"))["slice"].is_null());
  EXPECT_EQ(readViewFile(tmp / "off.json").slice, render::HeightSlice{});
  // A slice must be [lo, hi] with lo < hi.
  EXPECT_NE(errorOf(editedViewFile(tmp,
                                   [](nlohmann::json& v) {
                                     v["slice"] = {2, 1};
                                   }))
                .find("slice"),
            std::string::npos);
  // --slice and --draw none on the render command line.
  spec.slice.on = true;
  EXPECT_NE(renderCommand(spec, "s.vdmap").find(" --draw none --slice 0.25:1.75"), std::string::npos)
      << renderCommand(spec, "s.vdmap");
}

// Version 3's keys, the camera's new options, erased: what a version 1 or 2 file holds.
void eraseVersion3Keys(nlohmann::json& j) {
  for (const char* key : {"projection", "rotation", "up_vector"}) j.erase(key);
}

TEST(ViewFile, Version1StillReads) {
  TempDir tmp;
  // A version 1 file: no "slice" key (and one is refused there).
  const auto v1 = editedViewFile(tmp, [](nlohmann::json& j) {
    j["vdmap_view"] = 1;
    j.erase("slice");
    eraseVersion3Keys(j);
  });
  EXPECT_EQ(readViewFile(v1), unusualSpec());
  const auto v1_slice = editedViewFile(tmp, [](nlohmann::json& j) {
    j["vdmap_view"] = 1;
    eraseVersion3Keys(j);
  });
  EXPECT_NE(errorOf(v1_slice).find("slice"), std::string::npos) << errorOf(v1_slice);
  const auto v4 = editedViewFile(tmp, [](nlohmann::json& j) { j["vdmap_view"] = 4; });
  EXPECT_NE(errorOf(v4).find("versions 1 to 3"), std::string::npos) << errorOf(v4);
}

// --- view file version 3: projection, rotation, a user-set up ---
TEST(ViewFile, Version3RoundTripsTheProjectionRotationAndUpVector) {
  TempDir tmp;
  render::ViewSpec spec;
  spec.projection = render::Projection::kOrthographic;
  spec.rotation = render::Rotation::kTrackball;
  spec.up_vector = glm::vec3(0.1f, -0.98f, 0.05f);
  spec.look_at = render::LookAt{{1.f, 2.f, 3.f}, {0.f, 0.5f, 0.25f}, {0.3f, -0.9f, 0.1f}, 40.f};
  spec.fov_y_deg = 40.f;
  writeViewFile(tmp / "v.json", spec, {}, "s.vdmap");
  const nlohmann::json j = nlohmann::json::parse(test::readFile(tmp / "v.json"));
  EXPECT_EQ(j["vdmap_view"], 3);
  EXPECT_EQ(j["projection"], "orthographic");
  EXPECT_EQ(j["rotation"], "trackball");
  EXPECT_EQ(j["up_vector"].size(), 3u);
  EXPECT_EQ(readViewFile(tmp / "v.json"), spec);
  // The new keys are optional: a version 2 file (without them) or a version 3 file that leaves
  // them out reads with the defaults.
  const auto v2 = editedViewFile(tmp, [](nlohmann::json& v) {
    v["vdmap_view"] = 2;
    eraseVersion3Keys(v);
  });
  EXPECT_EQ(readViewFile(v2), unusualSpec());
  const auto v3_bare = editedViewFile(tmp, eraseVersion3Keys);
  EXPECT_EQ(readViewFile(v3_bare), unusualSpec());
  // A version 2 file may not hold them; bad values are named.
  const auto v2_ortho = editedViewFile(tmp, [](nlohmann::json& v) { v["vdmap_view"] = 2; });
  EXPECT_NE(errorOf(v2_ortho).find("unknown key"), std::string::npos) << errorOf(v2_ortho);
  const auto bad_projection = editedViewFile(tmp, [](nlohmann::json& v) { v["projection"] = "fisheye"; });
  EXPECT_NE(errorOf(bad_projection).find("projection must be perspective or orthographic, got 'fisheye'"),
            std::string::npos)
      << errorOf(bad_projection);
  const auto zero_up = editedViewFile(tmp, [](nlohmann::json& v) { v["up_vector"] = {0, 0, 0}; });
  EXPECT_NE(errorOf(zero_up).find("up_vector must not be zero"), std::string::npos) << errorOf(zero_up);
  // The render command says it too: --projection, and --up X,Y,Z for a user-set up without a camera.
  spec.look_at.reset();
  const std::string command = renderCommand(spec, "s.vdmap");
  EXPECT_NE(command.find(" --up 0.100000001,-0.980000019,0.0500000007"), std::string::npos) << command;
  EXPECT_NE(command.find(" --projection orthographic"), std::string::npos) << command;
}

}  // namespace
}  // namespace vdmap::app
