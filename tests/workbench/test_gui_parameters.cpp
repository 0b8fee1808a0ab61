// The parameter table (mapping/pipeline/parameters.h, app/cli/parameter_table.h) and the four ways a
// value reaches it: `vdmap map` options (CLI11), settings.json, `vdmap gui --set` and the
// workbench's sliders. For every parameter, values at and beyond its bounds are accepted or
// refused by all four alike, the bounds are those its validate() enforces, and the slider's span
// lies within them.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/cli/parameter_table.h"
#include "app/view/settings.h"
#include "app/workbench/workbench.h"
#include "tests/support/test_util.h"

namespace vdmap::app {
namespace {

using gui::Settings;

// A value as text in each channel's own syntax.
std::string text(const Parameter& p, double v) { return formatValue(p, v); }

// The value `p` has in `settings`.
double valueIn(const Parameter& p, const Settings& s) { return p.get(ParameterValues{s.mapper, s.thresholds}); }

bool acceptedByValidate(const Parameter& p, double v) {
  ParameterValues params;
  p.set(params, v);
  try {
    validate(params);
    return true;
  } catch (const std::invalid_argument&) {
    return false;
  }
}

// vdmap map's options, parsed in-process and then validated together as runMap does before any
// work; returns whether the value was taken (and checks it landed in the parameters).
bool acceptedByCli(const Parameter& p, const std::string& value) {
  CLI::App app;
  ParameterValues params;
  addParameterOptions(app, params);
  try {
    std::vector<std::string> args = {value, std::string(p.flag)};  // CLI11 takes them reversed
    app.parse(args);
    validate(params);
  } catch (const std::exception&) {
    return false;
  }
  EXPECT_EQ(text(p, p.get(params)), value) << p.key;
  return true;
}

bool acceptedBySettingsFile(const Parameter& p, const std::string& value, const test::TempDir& dir) {
  nlohmann::json j;
  const nlohmann::json parsed = nlohmann::json::parse(value, nullptr, false);
  j[p.live ? "thresholds" : "rerun"][std::string(p.key)] = parsed.is_discarded() ? nlohmann::json(value) : parsed;
  test::writeText(dir / "settings.json", j.dump());
  std::string warning;
  const Settings s = gui::loadSettings(dir / "settings.json", &warning);
  if (!warning.empty()) {
    // The parameter, or the rule that ties it to another (validate(): "depth range must ...").
    EXPECT_TRUE(warning.find(std::string(p.key)) != std::string::npos ||
                warning.find("depth range") != std::string::npos)
        << warning;
    return false;
  }
  EXPECT_EQ(text(p, valueIn(p, s)), value) << p.key;
  return true;
}

bool acceptedBySet(const Parameter& p, const std::string& value) {
  Settings s;
  try {
    gui::applySetting(s, std::string(p.key) + "=" + value);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(std::string(p.key)), std::string::npos) << e.what();
    return false;
  }
  EXPECT_EQ(text(p, valueIn(p, s)), value) << p.key;
  return true;
}

bool acceptedBySlider(const Parameter& p, double v) {
  gui::Workbench bench{Settings{}};
  const bool ok = bench.parameters().edit(p, v);
  EXPECT_EQ(ok, p.get(bench.ui().params) == v) << p.key;
  if (!ok) {
    EXPECT_EQ(bench.ui().status.kind, gui::StatusLine::Kind::kError) << p.key;
  }
  return ok;
}

TEST(ParameterTable, EveryValueIsAcceptedOrRefusedAlikeByCliSettingsSetAndSlider) {
  test::TempDir dir;
  for (const Parameter& p : parameters()) {
    SCOPED_TRACE(std::string(p.key));
    std::vector<double> probes = {p.slider_lo, p.slider_hi, p.get(ParameterValues{})};
    const double step = p.kind == Parameter::Kind::kInt ? 1.0 : 1e-3;
    for (double bound : {p.lo, p.hi})
      if (std::isfinite(bound)) probes.insert(probes.end(), {bound, bound - step, bound + step});
    if (p.kind == Parameter::Kind::kInt) probes.push_back(p.slider_lo + 0.5);
    if (p.kind == Parameter::Kind::kBool) probes = {0, 1};
    if (p.kind == Parameter::Kind::kChoice) probes = {p.lo, p.hi, p.hi + 1};
    for (const double v : probes) {
      bool in_table = true;
      try {
        checkValue(p, v);
      } catch (const std::invalid_argument&) {
        in_table = false;
      }
      const bool ok = in_table && acceptedByValidate(p, v);
      const std::string value = text(p, v);
      SCOPED_TRACE(value);
      if (p.kind != Parameter::Kind::kBool) {  // a bool's flag takes no value (CliFlagsOfBooleansFlipTheDefault)
        EXPECT_EQ(acceptedByCli(p, value), ok);
      }
      EXPECT_EQ(acceptedBySettingsFile(p, value, dir), ok);
      EXPECT_EQ(acceptedBySet(p, value), ok);
      EXPECT_EQ(acceptedBySlider(p, v), ok);
    }
  }
}

TEST(ParameterTable, BoundsAreThoseOfValidateAndSlidersLieWithinThem) {
  for (const Parameter& p : parameters()) {
    SCOPED_TRACE(std::string(p.key));
    EXPECT_FALSE(p.help.empty());
    EXPECT_FALSE(p.label.empty());
    EXPECT_FALSE(p.flag.empty());
    if (p.slider) {  // an advanced parameter has no slider, so no span
      EXPECT_LE(p.lo, p.slider_lo);
      EXPECT_GE(p.hi, p.slider_hi);
      EXPECT_TRUE(acceptedByValidate(p, p.slider_lo));
      EXPECT_TRUE(acceptedByValidate(p, p.slider_hi));
    }
    EXPECT_NO_THROW(checkValue(p, p.get(ParameterValues{}))) << "the default is valid";
    if (p.kind == Parameter::Kind::kBool || p.kind == Parameter::Kind::kChoice) continue;
    // Just outside a finite bound validate() refuses; at a closed bound it accepts.
    const double step = p.kind == Parameter::Kind::kInt ? 1.0 : 1e-9;
    if (std::isfinite(p.lo)) {
      EXPECT_FALSE(acceptedByValidate(p, p.lo - step)) << "validate() takes less than the table's lower bound";
      EXPECT_EQ(acceptedByValidate(p, p.lo), !p.lo_open) << "validate() and the table disagree at the lower bound";
    }
    if (std::isfinite(p.hi)) {
      EXPECT_FALSE(acceptedByValidate(p, p.hi + step)) << "validate() takes more than the table's upper bound";
      if (!p.hi_open) {
        EXPECT_TRUE(acceptedByValidate(p, p.hi)) << "validate() refuses the table's upper bound";
      }
    }
  }
}

TEST(ParameterTable, BadTextGivesAClearMessage) {
  Settings s;
  try {
    gui::applySetting(s, "min_points=abc");
    FAIL() << "taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "--set 'min_points=abc': min_points: expected an integer, got 'abc'");
  }
  EXPECT_THROW(parseValue(*findParameter("cell_size"), "5.5"), std::invalid_argument);
  EXPECT_THROW(parseValue(*findParameter("merge_distance"), "0.2m"), std::invalid_argument);
  EXPECT_THROW(parseValue(*findParameter("sensor_model"), "kinect"), std::invalid_argument);
  EXPECT_EQ(parseValue(*findParameter("occlusion_removal"), "false"), 0.0);
  try {
    checkValue(*findParameter("tau"), 2.0);
    FAIL() << "taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "tau must be within 0..1, got 2");
  }
  // Every settings key is a key of the table or of the view section (none is spelled twice).
  for (const Parameter& p : parameters()) EXPECT_EQ(findParameter(p.key), &p);
}

// The workbench's sliders are every parameter but the advanced ones, in the table's order; the
// advanced ones still reach the settings file, --set and `vdmap map`.
TEST(ParameterTable, TheWorkbenchShowsEveryParameterButTheAdvancedOnes) {
  std::vector<const Parameter*> sliders;
  for (const Parameter& p : parameters())
    if (p.slider) sliders.push_back(&p);
  ASSERT_EQ(parameterTable().size(), sliders.size()) << "an advanced parameter comes before a slider";
  for (std::size_t i = 0; i < sliders.size(); ++i) EXPECT_EQ(&parameterTable()[i], sliders[i]);
  EXPECT_LT(parameterTable().size(), parameters().size());

  Settings s;
  gui::applySetting(s, "lowe_ratio=0.7");
  EXPECT_EQ(s.mapper.keyframes.covisibility.lowe_ratio, 0.7);
  EXPECT_TRUE(gui::rerunParamsDiffer(s, Settings{}));
  EXPECT_NE(gui::settingKeyList().find("prefilter_max_distance"), std::string::npos) << gui::settingKeyList();
  CLI::App app;
  ParameterValues params;
  addParameterOptions(app, params);
  std::vector<std::string> args = {"12", "--max-hamming", "0", "--min-frame-features"};
  app.parse(args);
  EXPECT_EQ(params.mapper.keyframes.covisibility.max_hamming, 12);
  EXPECT_EQ(params.mapper.keyframes.min_frame_features, 0);
}

TEST(ParameterTable, CliFlagsOfBooleansFlipTheDefault) {
  CLI::App app;
  ParameterValues params;
  addParameterOptions(app, params);
  std::vector<std::string> args = {"0.3", "--merge-distance", "--no-occlusion-removal", "--no-prefilter"};
  app.parse(args);
  EXPECT_FALSE(params.mapper.keyframes.prefilter.enabled);
  EXPECT_FALSE(params.global.occlusion_removal);
  EXPECT_DOUBLE_EQ(params.global.merge_distance_m, 0.3);
}

}  // namespace
}  // namespace vdmap::app
