#pragma once
// A 2-D occupancy grid of a height band of the view-dependent map, in the format of ROS
// map_server (docs/method.md 13; docs/cli.md "query"): NAME.pgm (P5, 8 bit, row 0 = the largest
// second grid coordinate) and NAME.yaml. Occupied, free and unknown come from QueryMap, not from
// a voxel map: a column is occupied when a surface comes into its band, else free when some
// keyframe saw part of the band free, else unknown.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mapping/files/octomap_export.h"
#include "mapping/query/query_map.h"

namespace vdmap {

/// The axis a grid's band is measured along. The grid's two axes (u, v) are the right-handed pair
/// with u x v = up: +z (x, y), -z (x, -y), +y (z, x), -y (x, z), +x (y, z), -x (z, y).
enum class UpAxis : std::uint8_t { kPlusZ, kMinusZ, kPlusY, kMinusY, kPlusX, kMinusX };

/// "+z", "-z", ... ; parseUpAxis throws std::invalid_argument for any other text.
const char* upAxisName(UpAxis up);
UpAxis parseUpAxis(const std::string& text);

/// The band "LO:HI" (two finite numbers, LO < HI); throws std::invalid_argument saying what was expected.
std::pair<double, double> parseGridBand(const std::string& text);

/// The unit vectors (u, v, up) of a grid whose band runs along `up` (world frame).
void gridAxes(UpAxis up, Eigen::Vector3d* u, Eigen::Vector3d* v, Eigen::Vector3d* w);

struct OccupancyGridSpec {
  double resolution_m = 0.05;  ///< cell side
  double band_lo_m = 0.0;      ///< the band along `up` (world coordinate along that axis)
  double band_hi_m = 2.0;
  UpAxis up = UpAxis::kPlusZ;
  /// Throws std::invalid_argument for a resolution that is not > 0 and finite, or a band with
  /// lo >= hi or a non-finite end.
  void validate() const;
};

/// The values map_saver writes (trinary mode).
inline constexpr std::uint8_t kGridOccupied = 0;
inline constexpr std::uint8_t kGridFree = 254;
inline constexpr std::uint8_t kGridUnknown = 205;

/// Most cells a grid may have (a resolution far too fine for the map's extent is refused).
inline constexpr std::size_t kMaxGridCells = std::size_t{1} << 28;
/// Most points a grid may ask the map about (cells x sub-boxes per cell; a few minutes of queries).
inline constexpr double kMaxGridSamples = 268435456.0;  // 2^28

/// Where a grid lies: computed from the map's seen box alone, before any query.
struct OccupancyGridLayout {
  int width = 0, height = 0;
  Eigen::Vector2d origin_m{0, 0};
  double band_lo_m = 0, band_hi_m = 0;  ///< the band clipped to the map's extent along up
  double seen_lo_m = 0, seen_hi_m = 0;  ///< that extent, widened to multiples of the resolution
  bool clipped = false;                 ///< the band reached beyond the extent
  int layers = 0;                       ///< sub-boxes along the band
  double samples = 0;                   ///< distance samples: width x height x 4 x layers
};

/// The layout of `spec`'s grid over `map`: the band is clipped to the seen box's extent along up
/// (widened outward to multiples of the resolution), so a huge band costs what the map holds.
/// Throws std::invalid_argument for a bad spec, an empty map, a band outside that extent, more
/// than kMaxGridCells cells or kMaxGridSamples samples (each one line with the estimate and
/// what to change).
OccupancyGridLayout layOutOccupancyGrid(const QueryMap& map, const OccupancyGridSpec& spec);

/// "--band 0:1e30 clipped to the map's -0.05:1.95 m" when `layout` clipped the band, else "".
std::string gridBandClipNote(const OccupancyGridSpec& spec, const OccupancyGridLayout& layout, const char* option);

struct OccupancyGrid {
  int width = 0, height = 0;  ///< cells along u and v
  double resolution_m = 0;
  Eigen::Vector2d origin_m{0, 0};  ///< (u, v) of the lower-left corner of cell (column 0, last row)
  UpAxis up = UpAxis::kPlusZ;
  std::vector<std::uint8_t> cells;  ///< height x width, row 0 = largest v (the image's top row)
  std::size_t occupied = 0, free = 0, unknown = 0;
  std::size_t samples = 0;  ///< points QueryMap was asked about
};

/// The column rule: each cell's column box [u, u + res] x [v, v + res] x [lo, hi] is cut into
/// 2 x 2 x n sub-boxes (n so that they are at most min(2 cm, res / 2) tall); a sub-box whose
/// centre is within its half-diagonal of a surface (QueryMap::distance) makes the cell occupied
/// (the sphere around it covers the box, so no surface in the band is missed); else the cell is
/// free when some sub-box centre is classified free; else unknown. The grid covers
/// QueryMap::seenBounds, its origin a multiple of the resolution, over the band clipped to it
/// (layOutOccupancyGrid, whose errors it throws).
/// `progress` is called after each row with (rows done, rows).
OccupancyGrid computeOccupancyGrid(const QueryMap& map, const OccupancyGridSpec& spec,
                                   const ExportProgress& progress = {});

/// Writes `grid` as NAME.pgm and NAME.yaml (`yaml_file` is NAME.yaml; the image beside it), each
/// atomically, the image first. Throws std::runtime_error naming a file that cannot be written.
void writeOccupancyGrid(const std::filesystem::path& yaml_file, const OccupancyGrid& grid);

/// The P5 image and the YAML text writeOccupancyGrid writes (`image_name`: the yaml's `image:`).
std::string occupancyGridPgm(const OccupancyGrid& grid);
std::string occupancyGridYaml(const OccupancyGrid& grid, const std::string& image_name);

}  // namespace vdmap
