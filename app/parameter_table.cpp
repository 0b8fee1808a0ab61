#include "app/parameter_table.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace vdmap::app {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr const char* kSensorModels[] = {"nguyen2012", "belter2018"};
using K = Parameter::Kind;

// Accessors: one captureless lambda pair per parameter.
#define ACCESS(member)                                                            \
  .get = [](const ParameterValues& p) { return static_cast<double>(p.member); },   \
  .set = [](ParameterValues& p, double v) { p.member = static_cast<decltype(p.member)>(v); }

const Parameter kTable[] = {
    // Live: the global map (SPEC sections 4 and 6).
    {.key = "sensor_model", .flag = "--sensor-model", .label = "sensor model", .unit = "",
     .help = "The noise model giving each point's expected covariance (SPEC 3): nguyen2012, the per-pixel Kinect "
             "model of Nguyen et al. 2012; belter2018, the authors' feature-point model. The filter compares "
             "every ellipsoid with it.",
     .kind = K::kChoice, .live = true, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1,
     .get = [](const ParameterValues& p) { return static_cast<double>(p.global.filter.model); },
     .set = [](ParameterValues& p, double v) { p.global.filter.model = static_cast<SensorModel>(static_cast<int>(v)); },
     .choices = kSensorModels},
    {.key = "filter_sigma_factor", .flag = "--filter-sigma-factor", .label = "filter sigma factor k", .unit = "",
     .help = "k (SPEC 4): an ellipsoid is kept when its largest standard deviation is at most k times the one the "
             "sensor model expects at its pixel and depth (cell footprint added). Smaller k keeps fewer, thinner "
             "ellipsoids.",
     .kind = K::kReal, .live = true, .lo = 0, .hi = kInf, .lo_open = true, .slider_lo = 0.5, .slider_hi = 10,
     ACCESS(global.filter.filter_sigma_factor)},
    {.key = "min_points", .flag = "--min-points", .label = "min points", .unit = "",
     .help = "An ellipsoid built from fewer depth points than this is not kept (SPEC 4).",
     .kind = K::kInt, .live = true, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 100,
     ACCESS(global.filter.min_points)},
    {.key = "tau_group", .flag = "--tau-group", .label = "merge group tau", .unit = "",
     .help = "tau_group (SPEC 6.1): a keyframe joins a merge group's centre when their covisibility edge weight "
             "(the share of features re-observed) is at least this. Ellipsoids merge only within a group.",
     .kind = K::kReal, .live = true, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, ACCESS(global.tau_group)},
    {.key = "merge_distance", .flag = "--merge-distance", .label = "merge distance h", .unit = "m",
     .help = "h (SPEC 6.2): radius of the flat mean-shift kernel that joins ellipsoids of one group falling into "
             "one container cell; joined ones become one ellipsoid by moment matching.",
     .kind = K::kReal, .live = true, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 1,
     ACCESS(global.merge_distance_m)},
    {.key = "occlusion_removal", .flag = "--no-occlusion-removal", .label = "occlusion removal", .unit = "",
     .help = "SPEC 6.3: seen from each keyframe, an ellipsoid is removed when it lies in front of a more precise "
             "one (the ray to that one passes within Mahalanobis distance 2 of it).",
     .kind = K::kBool, .live = true, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, ACCESS(global.occlusion_removal)},
    {.key = "occlusion_distance", .flag = "--occlusion-distance", .label = "occlusion distance", .unit = "m",
     .help = "SPEC 6.3: besides its graph neighbours, a viewpoint's occlusion group holds every keyframe within "
             "this distance whose optical axis is within the occlusion angle of its own.",
     .kind = K::kReal, .live = true, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 2,
     ACCESS(global.occlusion_distance_m)},
    {.key = "occlusion_angle", .flag = "--occlusion-angle", .label = "occlusion angle", .unit = "deg",
     .help = "SPEC 6.3: the largest angle between optical axes for a nearby keyframe to join a viewpoint's "
             "occlusion group.",
     .kind = K::kReal, .live = true, .lo = 0, .hi = 180, .slider_lo = 0, .slider_hi = 180,
     ACCESS(global.occlusion_angle_deg)},
    {.key = "fuse_across_groups", .flag = "--no-fusion", .label = "fusion across groups", .unit = "",
     .help = "SPEC 6.5: after occlusion removal, ellipsoids of different merge groups that are copies of one "
             "surface become one (moment matching), so the map grows with the area seen, not with revisits. "
             "Off: the paper's map, one copy per group.",
     .kind = K::kBool, .live = true, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, ACCESS(global.fuse_across_groups)},
    {.key = "fusion_max_distance", .flag = "--fusion-max-distance", .label = "fusion distance", .unit = "",
     .help = "SPEC 6.5: two ellipsoids of different groups are copies of one surface when their Bhattacharyya "
             "distance (offset of the means relative to their spread, plus the difference of their shapes) is at "
             "most this and their means lie within 1.5 median standard deviations along every axis.",
     .kind = K::kReal, .live = true, .lo = 0, .hi = 10, .slider_lo = 0, .slider_hi = 3,
     ACCESS(global.fusion_max_distance)},
    // Re-run: keyframes and local maps (SPEC sections 2 and 5).
    {.key = "cell_size", .flag = "--cell-size", .label = "cell size s", .unit = "px",
     .help = "s (SPEC 2): side of a container cell in keyframe pixels; each cell holds one ellipsoid, so near "
             "surfaces get small ellipsoids and far ones large. At most the image's smaller side.",
     .kind = K::kInt, .lo = 1, .hi = kInf, .slider_lo = 1, .slider_hi = 32, ACCESS(mapper.local_map.cell_size_px)},
    {.key = "min_depth", .flag = "--min-depth", .label = "min depth", .unit = "m",
     .help = "Depth measurements nearer than this are ignored (SPEC 1); below max depth.",
     .kind = K::kReal, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 2, ACCESS(mapper.local_map.depth_range.min_m)},
    {.key = "max_depth", .flag = "--max-depth", .label = "max depth", .unit = "m",
     .help = "Depth measurements farther than this are ignored (SPEC 1); above min depth.",
     .kind = K::kReal, .lo = 0, .hi = kInf, .lo_open = true, .hi_open = true, .slider_lo = 1, .slider_hi = 10,
     ACCESS(mapper.local_map.depth_range.max_m)},
    {.key = "orb_features", .flag = "--orb-features", .label = "ORB features", .unit = "",
     .help = "ORB features detected per frame for the covisibility decision (SPEC 5).",
     .kind = K::kInt, .lo = 1, .hi = kInf, .slider_lo = 100, .slider_hi = 4000, ACCESS(mapper.features.orb_features)},
    {.key = "tau", .flag = "--tau", .label = "keyframe tau", .unit = "",
     .help = "tau (SPEC 5): a frame updates the current keyframe while it re-observes at least this share of the "
             "keyframe's features; below it a revisit is searched, else the frame starts a new keyframe.",
     .kind = K::kReal, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, ACCESS(mapper.keyframes.tau)},
    {.key = "tau_edge", .flag = "--tau-edge", .label = "edge tau", .unit = "",
     .help = "tau_edge (SPEC 5): a new keyframe gets a covisibility edge to each keyframe it re-observes at least "
             "this share of; the edge to the previous keyframe is always kept, whatever its weight.",
     .kind = K::kReal, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, ACCESS(mapper.keyframes.tau_edge)},
    {.key = "keyframe_every", .flag = "--keyframe-every", .label = "keyframe every", .unit = "frames",
     .help = "0: keyframes by covisibility (SPEC 5); N > 0: every N-th frame starts a keyframe (a fixed schedule, "
             "for comparisons).",
     .kind = K::kInt, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 30, ACCESS(mapper.keyframe_every)},
    {.key = "prefilter", .flag = "--no-prefilter", .label = "pose pre-filter", .unit = "",
     .help = "The loop-closure and edge searches skip keyframes more than 3 m away or turned more than 90 degrees "
             "(SPEC 5); off: every keyframe is matched.",
     .kind = K::kBool, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, ACCESS(mapper.keyframes.prefilter.enabled)},
};
#undef ACCESS

std::string number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

}  // namespace

bool ParameterValues::operator==(const ParameterValues& other) const {
  for (const Parameter& p : parameterTable())
    if (p.get(*this) != p.get(other)) return false;
  return true;
}

std::span<const Parameter> parameterTable() { return kTable; }

const Parameter* findParameter(std::string_view key) {
  for (const Parameter& p : kTable)
    if (p.key == key) return &p;
  return nullptr;
}

std::string validityText(const Parameter& p) {
  if (p.kind == K::kBool) return "true or false";
  if (p.kind == K::kChoice) {
    std::string names;
    for (std::size_t i = 0; i < p.choices.size(); ++i)
      names += (i == 0 ? "" : i + 1 == p.choices.size() ? " or " : ", ") + std::string(p.choices[i]);
    return names;
  }
  const bool has_lo = std::isfinite(p.lo), has_hi = std::isfinite(p.hi);
  const std::string unit = p.unit.empty() ? "" : " " + std::string(p.unit);
  if (has_lo && has_hi && !p.lo_open && !p.hi_open) return "within " + number(p.lo) + ".." + number(p.hi) + unit;
  std::string text;
  if (has_lo) text = (p.lo_open ? "> " : ">= ") + number(p.lo) + unit;
  if (has_hi) text += (text.empty() ? "" : " and ") + std::string(p.hi_open ? "< " : "<= ") + number(p.hi) + unit;
  return text;
}

std::string formatValue(const Parameter& p, double value) {
  if (p.kind == K::kBool) return value != 0 ? "true" : "false";
  if (p.kind == K::kChoice) {
    const auto i = static_cast<std::size_t>(value);
    return i < p.choices.size() ? p.choices[i] : number(value);
  }
  return number(value);
}

double parseValue(const Parameter& p, std::string_view text) {
  const std::string s(text);
  const auto fail = [&](const std::string& expected) -> double {
    throw std::invalid_argument(std::string(p.key) + ": expected " + expected + ", got '" + s + "'");
  };
  switch (p.kind) {
    case K::kBool:
      if (s == "true" || s == "1" || s == "on") return 1;
      if (s == "false" || s == "0" || s == "off") return 0;
      return fail("true or false");
    case K::kChoice:
      for (std::size_t i = 0; i < p.choices.size(); ++i)
        if (s == p.choices[i]) return static_cast<double>(i);
      return fail(validityText(p));
    case K::kInt:
    case K::kReal: {
      std::size_t used = 0;
      double v = 0;
      try {
        v = std::stod(s, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      while (used < s.size() && std::isspace(static_cast<unsigned char>(s[used]))) ++used;
      if (s.empty() || used != s.size()) return fail(p.kind == K::kInt ? "an integer" : "a number");
      if (p.kind == K::kInt && v != std::floor(v)) return fail("an integer");
      return v;
    }
  }
  return fail("a value");
}

void checkValue(const Parameter& p, double value) {
  const bool integer_ok = p.kind == K::kReal || value == std::floor(value);
  const bool in_range = std::isfinite(value) && (p.lo_open ? value > p.lo : value >= p.lo) &&
                        (p.hi_open ? value < p.hi : value <= p.hi);
  if (!in_range || !integer_ok)
    throw std::invalid_argument(std::string(p.key) + " must be " + validityText(p) + ", got " + formatValue(p, value));
}

void setFromText(const Parameter& p, ParameterValues& params, std::string_view text) {
  const double v = parseValue(p, text);
  checkValue(p, v);
  p.set(params, v);
}

void validate(const ParameterValues& params) {
  params.mapper.validate();
  params.global.validate();
}

void addParameterOptions(CLI::App& verb, ParameterValues& params) {
  const ParameterValues defaults = params;
  for (const Parameter& p : kTable) {
    if (p.flag.empty()) continue;
    const std::string flag(p.flag);
    if (p.kind == K::kBool) {
      const std::string help = std::string(p.help) + (p.get(defaults) != 0 ? " [on by default; this flag turns it off]"
                                                                              : " [off by default; this flag turns it on]");
      // The flag flips the default (--no-occlusion-removal turns a default-on step off).
      verb.add_flag_callback(flag, [&params, &p, defaults] { p.set(params, p.get(defaults) != 0 ? 0 : 1); }, help);
      continue;
    }
    const std::string help = std::string(p.help) + " [" + validityText(p) + "]";
    verb.add_option_function<std::string>(
            flag,
            [&params, &p, flag](const std::string& text) {
              try {
                setFromText(p, params, text);
              } catch (const std::invalid_argument& e) {
                throw std::invalid_argument(flag + ": " + e.what());
              }
            },
            help)
        ->default_str(formatValue(p, p.get(defaults)))
        ->type_name(p.kind == K::kChoice ? "NAME" : p.kind == K::kInt ? "INT" : "NUMBER");
  }
}

}  // namespace vdmap::app
