#include "mapping/pipeline/mapper_parameters.h"

#include <limits>
#include <stdexcept>

namespace vdmap {
namespace {

using K = ParameterSpec::Kind;
#define ACCESS(member) VDMAP_PARAMETER_ACCESS(MapperParams, member)

// Rows are laid out by hand: a parameter's fields read as one record.
// clang-format off
constexpr ParameterRow<MapperParams> kMapperRows[] = {
    {.spec = {.key = "cell_size", .flag = "--cell-size", .label = "cell size s", .unit = "px",
              .help = "s (docs/method.md 2): side of a container cell in keyframe pixels; each cell holds one "
                      "ellipsoid, so near surfaces get small ellipsoids and far ones large. At most the image's "
                      "smaller side.",
              .kind = K::kInt, .lo = 1, .hi = kInf, .slider_lo = 1, .slider_hi = 32},
     ACCESS(local_map.cell_size_px)},
    {.spec = {.key = "min_depth", .flag = "--min-depth", .label = "min depth", .unit = "m",
              .help = "Depth measurements nearer than this are ignored (docs/method.md 1); below max depth.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 2},
     ACCESS(local_map.depth_range.min_m)},
    {.spec = {.key = "max_depth", .flag = "--max-depth", .label = "max depth", .unit = "m",
              .help = "Depth measurements farther than this are ignored (docs/method.md 1); above min depth.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .lo_open = true, .hi_open = true, .slider_lo = 1,
              .slider_hi = 10},
     ACCESS(local_map.depth_range.max_m)},
    {.spec = {.key = "orb_features", .flag = "--orb-features", .label = "ORB features", .unit = "",
              .help = "ORB features detected per frame for the covisibility decision (docs/method.md 5).",
              .kind = K::kInt, .lo = 1, .hi = kInf, .slider_lo = 100, .slider_hi = 4000},
     ACCESS(features.orb_features)},
    {.spec = {.key = "tau", .flag = "--tau", .label = "keyframe tau", .unit = "",
              .help = "tau (docs/method.md 5): a frame updates the current keyframe while it re-observes at least "
                      "this share of the keyframe's features; below it a revisit is searched, else the frame starts "
                      "a new keyframe.",
              .kind = K::kReal, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, .range_name = "tau and tau_edge"},
     ACCESS(keyframes.tau)},
    {.spec = {.key = "tau_edge", .flag = "--tau-edge", .label = "edge tau", .unit = "",
              .help = "tau_edge (docs/method.md 5): a new keyframe gets a covisibility edge to each keyframe it "
                      "re-observes at least this share of; the edge to the previous keyframe is always kept, "
                      "whatever its weight.",
              .kind = K::kReal, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1, .range_name = "tau and tau_edge"},
     ACCESS(keyframes.tau_edge)},
    {.spec = {.key = "keyframe_every", .flag = "--keyframe-every", .label = "keyframe every", .unit = "frames",
              .help = "0: keyframes by covisibility (docs/method.md 5); N > 0: every N-th frame starts a keyframe "
                      "(a fixed schedule, for comparisons).",
              .kind = K::kInt, .lo = 0, .hi = kInf, .slider_lo = 0, .slider_hi = 30},
     ACCESS(keyframe_every)},
    {.spec = {.key = "prefilter", .flag = "--no-prefilter", .label = "pose pre-filter", .unit = "",
              .help = "The loop-closure and edge searches skip keyframes farther away than the pre-filter distance "
                      "or turned by more than the pre-filter angle (docs/method.md 5); off: every keyframe is "
                      "matched.",
              .kind = K::kBool, .lo = 0, .hi = 1, .slider_lo = 0, .slider_hi = 1},
     ACCESS(keyframes.prefilter.enabled)},
    // Advanced: no slider.
    {.spec = {.key = "prefilter_max_distance", .flag = "--prefilter-max-distance", .label = "pre-filter distance",
              .unit = "m",
              .help = "Pose pre-filter (docs/method.md 5): the searches skip a keyframe whose camera centre is "
                      "farther than this from the frame's.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .slider = false, .enabled_by = "prefilter"},
     ACCESS(keyframes.prefilter.max_distance_m)},
    {.spec = {.key = "prefilter_max_angle", .flag = "--prefilter-max-angle", .label = "pre-filter angle",
              .unit = "deg",
              .help = "Pose pre-filter (docs/method.md 5): the searches skip a keyframe whose optical axis is turned "
                      "by more than this from the frame's.",
              .kind = K::kReal, .lo = 0, .hi = kInf, .slider = false, .enabled_by = "prefilter"},
     ACCESS(keyframes.prefilter.max_angle_deg)},
    {.spec = {.key = "min_frame_features", .flag = "--min-frame-features", .label = "min frame features",
              .unit = "",
              .help = "A frame with fewer ORB keypoints than this (a textureless view) cannot be judged by "
                      "covisibility (docs/method.md 5): it updates the current keyframe when the pose pre-filter "
                      "accepts that keyframe, else it starts a new one, so a blank wall does not spawn a keyframe "
                      "per frame.",
              .kind = K::kInt, .lo = 0, .hi = kInf, .slider = false},
     ACCESS(keyframes.min_frame_features)},
    {.spec = {.key = "max_hamming", .flag = "--max-hamming", .label = "max Hamming distance", .unit = "",
              .help = "Covisibility (docs/method.md 5): an ORB descriptor matches another only when their Hamming "
                      "distance (of 256 bits) is at most this.",
              .kind = K::kInt, .lo = 0, .hi = kInf, .slider = false},
     ACCESS(keyframes.covisibility.max_hamming)},
    {.spec = {.key = "lowe_ratio", .flag = "--lowe-ratio", .label = "Lowe ratio", .unit = "",
              .help = "Covisibility (docs/method.md 5): Lowe's ratio test; a match's descriptor distance must be "
                      "below this times the second best's.",
              .kind = K::kReal, .lo = 0, .hi = 1, .lo_open = true, .slider = false},
     ACCESS(keyframes.covisibility.lowe_ratio)},
    {.spec = {.key = "max_reprojection", .flag = "--max-reprojection", .label = "max reprojection", .unit = "px",
              .help = "Covisibility (docs/method.md 5): a keypoint with depth, carried into the frame by the two "
                      "poses, must find its match within this distance of where it lands (a pose-consistency "
                      "check).",
              .kind = K::kReal, .lo = 0, .hi = kInf, .slider = false},
     ACCESS(keyframes.covisibility.max_reprojection_px)},
};
// clang-format on
#undef ACCESS

}  // namespace

std::span<const ParameterRow<MapperParams>> mapperParameters() { return kMapperRows; }

void MapperParams::validate() const {
  checkRanges(mapperParameters(), *this);
  // The rules between parameters, which no range of one expresses.
  if (!(local_map.depth_range.min_m < local_map.depth_range.max_m))
    throw std::invalid_argument("depth range must satisfy 0 <= min < max");
}

}  // namespace vdmap
