// The parameter table (mapping/pipeline/parameters.h): what is derived from its declarations (the
// structs' validate(), equality, enable rules, the session file's fields, docs/parameters.md) sees
// every parameter, and the generated page is the one committed.
#include <cctype>
#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "mapping/pipeline/parameters.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

// A valid value of `p` other than its value in `values`.
double anotherValue(const Parameter& p, const ParameterValues& values) {
  const double v = p.get(values);
  if (p.kind == Parameter::Kind::kBool || p.kind == Parameter::Kind::kChoice) return v == p.lo ? p.hi : p.lo;
  for (const double candidate : {v + 1, v - 1, v / 2, p.lo, p.hi})
    if (candidate != v && inRange(p, candidate)) return candidate;
  ADD_FAILURE() << p.key << ": no other valid value than " << v;
  return v;
}

std::string message(const ParameterValues& values) {
  try {
    validate(values);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Parameters, EqualitySeesEveryParameter) {
  ParameterValues a, b;
  EXPECT_TRUE(a == b);
  b.mapper.keyframes.covisibility.lowe_ratio = 0.7;
  EXPECT_FALSE(a == b) << "lowe_ratio";
  for (const Parameter& p : parameters()) {
    ParameterValues changed;
    p.set(changed, anotherValue(p, changed));
    EXPECT_FALSE(changed == ParameterValues{}) << p.key;
  }
  // The pose source and the thread count are no parameters of the table.
  b = a;
  b.mapper.poses = PoseSource::kTrack;
  b.global.threads = 3;
  EXPECT_TRUE(a == b);
}

TEST(Parameters, WhyDisabledNamesTheSwitchThatIsOff) {
  ParameterValues values;
  for (const Parameter& p : parameters()) EXPECT_EQ(whyDisabled(p, values), "") << p.key << ": every switch is on";
  values.global.occlusion_removal = false;
  values.global.fuse_across_groups = false;
  values.mapper.keyframes.prefilter.enabled = false;
  const auto why = [&values](const char* key) { return whyDisabled(*findParameter(key), values); };
  EXPECT_EQ(why("occlusion_distance"), "Occlusion removal is off: this has no effect.");
  EXPECT_EQ(why("occlusion_angle"), "Occlusion removal is off: this has no effect.");
  EXPECT_EQ(why("fusion_max_distance"), "Fusion across groups is off: this has no effect.");
  EXPECT_EQ(why("prefilter_max_distance"), "Pose pre-filter is off: this has no effect.");
  EXPECT_EQ(why("prefilter_max_angle"), "Pose pre-filter is off: this has no effect.");
  EXPECT_EQ(why("merge_distance"), "");
  EXPECT_EQ(why("occlusion_removal"), "") << "a switch is never disabled by itself";
  // A rule names a switch of the same struct (a live parameter depends on a live one).
  for (const Parameter& p : parameters()) {
    if (p.enabled_by.empty()) continue;
    const Parameter* rule = findParameter(p.enabled_by);
    ASSERT_NE(rule, nullptr) << p.key;
    EXPECT_EQ(rule->kind, Parameter::Kind::kBool) << p.key;
    EXPECT_EQ(rule->live, p.live) << p.key;
  }
}

// validate() checks every parameter's range from the table, and the rules between parameters.
TEST(Parameters, ValidateChecksTheTablesRanges) {
  for (const Parameter& p : parameters()) {
    ParameterValues values;
    EXPECT_EQ(message(values), "");
    if (p.kind == Parameter::Kind::kBool) continue;  // no value of a bool is out of range
    p.set(values, p.kind == Parameter::Kind::kChoice ? p.hi + 1 : std::isfinite(p.lo) ? p.lo - 1 : p.hi + 1);
    EXPECT_NE(message(values).find(" must be "), std::string::npos) << p.key << ": " << message(values);
  }
  ParameterValues values;
  values.mapper.keyframes.covisibility.lowe_ratio = 0;
  EXPECT_EQ(message(values), "lowe_ratio must be > 0 and <= 1");
  values = {};
  values.mapper.keyframes.tau_edge = 1.5;
  EXPECT_EQ(message(values), "tau and tau_edge must be within 0..1");
  values = {};
  values.mapper.local_map.depth_range = {2.0, 1.0};
  EXPECT_EQ(message(values), "depth range must satisfy 0 <= min < max");
  values = {};
  values.global.threads = -1;
  EXPECT_EQ(message(values), "threads must be within 0..256");
  values.global.threads = 257;  // 65537 crashed in TBB's allocator
  EXPECT_EQ(message(values), "threads must be within 0..256");
  values.global.threads = 256;
  EXPECT_EQ(message(values), "");
}

// Each parameter is stored once in a session's PARM section, with a storage type that holds it.
TEST(Parameters, TheSessionFileStoresEveryParameterOnce) {
  std::set<const Parameter*> stored;
  for (const bool live : {false, true})
    for (const StoredParameter& s : storedParameters(live)) {
      SCOPED_TRACE(s.name);
      EXPECT_TRUE(stored.insert(s.parameter).second) << "stored twice";
      EXPECT_EQ(s.parameter->live, live);
      using Type = StoredParameter::Type;
      switch (s.parameter->kind) {
        case Parameter::Kind::kInt: EXPECT_EQ(s.type, Type::kI32); break;
        case Parameter::Kind::kReal: EXPECT_EQ(s.type, Type::kF64); break;
        case Parameter::Kind::kBool: EXPECT_EQ(s.type, Type::kBool); break;
        case Parameter::Kind::kChoice: EXPECT_EQ(s.type, Type::kU32); break;
      }
    }
  EXPECT_EQ(stored.size(), parameters().size()) << "a parameter of the table is not stored in sessions";
}

// Help texts are the users': they cite docs/method.md, never the internal specification.
TEST(Parameters, HelpTextsCiteTheMethod) {
  for (const Parameter& p : parameters()) {
    EXPECT_EQ(p.help.find("SPEC"), std::string_view::npos) << p.key;
    EXPECT_FALSE(p.help.empty()) << p.key;
    EXPECT_TRUE(std::islower(static_cast<unsigned char>(p.key[0]))) << p.key;
  }
}

TEST(Parameters, DocsPageIsTheGeneratedOne) {
  const auto r = test::runVdmap("params --markdown");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string committed = test::readFile(std::string(VDMAP_SOURCE_DIR) + "/docs/parameters.md");
  EXPECT_TRUE(r.out == committed) << "docs/parameters.md is not what the parameter table gives; regenerate it with\n  "
                                  << VDMAP_BINARY << " params --markdown > " << VDMAP_SOURCE_DIR
                                  << "/docs/parameters.md";
  for (const Parameter& p : parameters()) {
    EXPECT_NE(r.out.find("| `" + std::string(p.key) + "` | `" + std::string(p.flag) + "` |"), std::string::npos)
        << p.key;
  }
  const auto plain = test::runVdmap("params");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  for (const Parameter& p : parameters()) {
    EXPECT_NE(plain.out.find("  " + std::string(p.key) + " = "), std::string::npos) << p.key;
    EXPECT_NE(plain.out.find(std::string(p.flag)), std::string::npos) << p.key;
  }
}

}  // namespace
}  // namespace vdmap
