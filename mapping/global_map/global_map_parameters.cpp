#include "mapping/global_map/global_map_parameters.h"

#include <limits>
#include <stdexcept>
#include <string>

#include "mapping/core/parallel.h"

namespace vdmap {
namespace {

constexpr const char* kSensorModels[] = {"nguyen2012", "belter2018"};
using K = ParameterSpec::Kind;
#define ACCESS(member) VDMAP_PARAMETER_ACCESS(GlobalMapParams, member)

// Rows are laid out by hand: a parameter's fields read as one record.
// clang-format off
constexpr ParameterRow<GlobalMapParams> kGlobalMapRows[] = {
    {.spec = {.key = "sensor_model", .flag = "--sensor-model", .label = "sensor model", .unit = "",
              .help = "The noise model giving each point's expected covariance (docs/method.md 3): nguyen2012, the "
                      "per-pixel Kinect model of Nguyen et al. 2012; belter2018, the authors' feature-point model. "
                      "The filter compares every ellipsoid with it.",
              .kind = K::kChoice, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, .choices = kSensorModels},
     .get = [](const GlobalMapParams& p) { return static_cast<double>(p.filter.model); },
     .set = [](GlobalMapParams& p, double v) { p.filter.model = static_cast<SensorModel>(static_cast<int>(v)); }},
    {.spec = {.key = "filter_sigma_factor", .flag = "--filter-sigma-factor", .label = "filter sigma factor k",
              .unit = "",
              .help = "k (docs/method.md 4): an ellipsoid is kept when its largest standard deviation is at most k "
                      "times the one the sensor model expects at its pixel and depth (cell footprint added). Smaller "
                      "k keeps fewer, thinner ellipsoids.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .lo_open = true, .slider_lo = 0.5, .slider_hi = 10},
     ACCESS(filter.filter_sigma_factor)},
    {.spec = {.key = "min_points", .flag = "--min-points", .label = "min points", .unit = "",
              .help = "An ellipsoid built from fewer depth points than this is not kept (docs/method.md 4).",
              .kind = K::kInt, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 100},
     ACCESS(filter.min_points)},
    {.spec = {.key = "tau_group", .flag = "--tau-group", .label = "merge group tau", .unit = "",
              .help = "tau_group (docs/method.md 6.1): a keyframe joins a merge group's centre when their "
                      "covisibility edge weight (the share of features re-observed) is at least this. Ellipsoids "
                      "merge only within a group.",
              .kind = K::kReal, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1},
     ACCESS(tau_group)},
    {.spec = {.key = "merge_distance", .flag = "--merge-distance", .label = "merge distance h", .unit = "m",
              .help = "h (docs/method.md 6.2): radius of the flat mean-shift kernel that joins ellipsoids of one "
                      "group falling into one container cell; joined ones become one ellipsoid by moment matching.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 1},
     ACCESS(merge_distance_m)},
    {.spec = {.key = "occlusion_removal", .flag = "--no-occlusion-removal", .label = "occlusion removal", .unit = "",
              .help = "Occlusion removal (docs/method.md 6.3): seen from each keyframe, an ellipsoid is removed when "
                      "it lies in front of a more precise one (the ray to that one passes within Mahalanobis "
                      "distance 2 of it).",
              .kind = K::kBool, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1},
     ACCESS(occlusion_removal)},
    {.spec = {.key = "occlusion_distance", .flag = "--occlusion-distance", .label = "occlusion distance", .unit = "m",
              .help = "Occlusion removal (docs/method.md 6.3): besides its graph neighbours, a viewpoint's occlusion "
                      "group holds every keyframe within this distance whose optical axis is within the occlusion "
                      "angle of its own.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 2,
              .enabled_by = "occlusion_removal"},
     ACCESS(occlusion_distance_m)},
    {.spec = {.key = "occlusion_angle", .flag = "--occlusion-angle", .label = "occlusion angle", .unit = "deg",
              .help = "Occlusion removal (docs/method.md 6.3): the largest angle between optical axes for a nearby "
                      "keyframe to join a viewpoint's occlusion group.",
              .kind = K::kReal, .lo = 0, .hi = 180, .slider_lo = 0, .slider_hi = 180,
              .enabled_by = "occlusion_removal"},
     ACCESS(occlusion_angle_deg)},
    {.spec = {.key = "fuse_across_groups", .flag = "--no-fusion", .label = "fusion across groups", .unit = "",
              .help = "Fusion across groups (docs/method.md 7): after occlusion removal, ellipsoids of different "
                      "merge groups that are copies of one surface become one (moment matching), so the map grows "
                      "with the area seen, not with revisits. Off: the paper's map, one copy per group.",
              .kind = K::kBool, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1},
     ACCESS(fuse_across_groups)},
    {.spec = {.key = "fusion_max_distance", .flag = "--fusion-max-distance", .label = "fusion distance", .unit = "",
              .help = "Fusion across groups (docs/method.md 7): two ellipsoids of different groups are copies of "
                      "one surface when their Bhattacharyya distance (offset of the means relative to their spread, "
                      "plus the difference of their shapes) is at most this and their means lie within 1.5 median "
                      "standard deviations along every axis.",
              .kind = K::kReal, .lo = 0, .hi = 10, .slider_lo = 0, .slider_hi = 3,
              .enabled_by = "fuse_across_groups"},
     ACCESS(fusion_max_distance)},
};
// clang-format on
#undef ACCESS

}  // namespace

std::span<const ParameterRow<GlobalMapParams>> globalMapParameters() { return kGlobalMapRows; }

void GlobalMapParams::validate() const {
  checkRanges(globalMapParameters(), *this);
  // The thread count is no parameter of the table: it changes how fast a map is built, not the map.
  if (threads < 0 || threads > kMaxThreads)
    throw std::invalid_argument("threads must be within 0.." + std::to_string(kMaxThreads));
}

}  // namespace vdmap
