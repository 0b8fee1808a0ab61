#pragma once
// The query slice (docs/workbench.md "Queries"): a plane through the map coloured by what
// QueryMap (docs/method.md 13) answers at its samples, as voxblox draws its ESDF slice: occupied /
// free / unknown, or the distance to the nearest surface. Sampled on the CPU (the query map's own
// threads), drawn as a depth-tested textured quad (QuerySliceRenderer). Distinct from the height
// slice (HeightSlice, `--slice LO:HI`), which keeps the map's ellipsoids between two heights.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "mapping/query/query_map.h"
#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/view_camera.h"

namespace vdmap::render {

class ShaderProgram;

/// Which plane: across the map's up axis (the height frame's: offset = height above its floor),
/// or across a world axis (offset = that coordinate).
enum class QuerySliceAxis { kUp, kX, kY, kZ };
enum class QuerySliceColor { kOccupancy, kDistance };

struct QuerySliceSpec {
  QuerySliceAxis axis = QuerySliceAxis::kUp;
  double offset_m = 1.0;
  QuerySliceColor color = QuerySliceColor::kOccupancy;
  double max_distance_m = 0.5;  ///< kDistance: the colour ramp's top (viridis 0..max; farther is yellow)
  int samples = 256;            ///< along the plane's longer side over QueryMap::seenBounds
  bool operator==(const QuerySliceSpec&) const = default;
};

/// "up", "x", "y", "z" / "occupancy", "distance".
const char* querySliceAxisName(QuerySliceAxis axis);
const char* querySliceColorName(QuerySliceColor color);
/// "AXIS=VALUE" (axis up, x, y or z; value in metres); throws std::invalid_argument naming the form.
QuerySliceSpec parseQuerySlice(const std::string& text);
QuerySliceColor parseQuerySliceColor(const std::string& name);

/// The sampled rectangle: sample (i, j) (column i, row j) is at origin + (i + 0.5) du + (j + 0.5) dv.
struct QuerySlicePlane {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero(), du = Eigen::Vector3d::Zero(), dv = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0;  ///< normal . p on the plane
  int width = 0, height = 0;
  bool empty() const { return width <= 0 || height <= 0; }
  Eigen::Vector3d sample(int i, int j) const { return origin + (i + 0.5) * du + (j + 0.5) * dv; }
};

/// The plane of `spec` cut to the rectangle that holds the box [lo, hi] projected onto it;
/// empty when lo > hi (nothing seen). `height`: the map's up axis and floor (kUp).
QuerySlicePlane querySlicePlane(const QuerySliceSpec& spec, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                const HeightFrame& height);

/// The colours: free green, occupied red, unknown translucent grey (occupancy); viridis over
/// 0..max_distance_m, unknown grey (distance).
inline constexpr std::array<std::uint8_t, 4> kSliceFree{40, 170, 70, 170}, kSliceOccupied{215, 40, 35, 230},
    kSliceUnknown{128, 128, 128, 70};

struct QuerySliceImage {
  QuerySliceSpec spec;
  QuerySlicePlane plane;
  cv::Mat rgba;  ///< CV_8UC4, plane.height rows (row j = samples j) x plane.width
  std::size_t occupied = 0, free = 0, unknown = 0;
  double compute_ms = 0;
};

/// A box (lo, hi), world frame.
using QuerySliceBox = std::pair<Eigen::Vector3d, Eigen::Vector3d>;

/// Samples `map` over the plane of `spec` (QueryMap::classify, and QueryMap::distance for
/// kDistance) on the map's threads; deterministic. The plane spans QueryMap::seenBounds, or
/// `fallback` when nothing is seen (a map file: no keyframes; then the distance colours every
/// sample, since nothing can be seen free). Nothing to span gives an empty image.
QuerySliceImage computeQuerySlice(const QueryMap& map, const QuerySliceSpec& spec, const HeightFrame& height,
                                  const std::optional<QuerySliceBox>& fallback = std::nullopt);

/// Where the ray from `origin` along `direction` meets the plane (t > 0), if it does.
std::optional<Eigen::Vector3d> intersectPlane(const QuerySlicePlane& plane, const Eigen::Vector3d& origin,
                                              const Eigen::Vector3d& direction);

/// Draws a QuerySliceImage as a textured quad in the world: depth-tested against what is drawn
/// before it (the map), blended by its alpha, not writing depth. Use with its context current.
class QuerySliceRenderer {
 public:
  explicit QuerySliceRenderer(const Gl& gl);
  ~QuerySliceRenderer();
  QuerySliceRenderer(const QuerySliceRenderer&) = delete;
  QuerySliceRenderer& operator=(const QuerySliceRenderer&) = delete;
  /// Uploads the image (null or empty: draws nothing).
  void set(const QuerySliceImage* image);
  void draw(const ViewCamera& view) const;
  bool empty() const { return plane_.empty(); }

 private:
  const Gl* gl_;
  std::unique_ptr<ShaderProgram> program_;
  VertexArray vao_;
  GLuint texture_ = 0;
  QuerySlicePlane plane_;
};

}  // namespace vdmap::render
