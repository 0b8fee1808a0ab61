#pragma once
// What a path given to the workbench or `vdmap render --map` holds, and the map files read whole
// into one static map: a `vdmap map` output folder, an ellipsoid or point PLY, an OctoMap
// (docs/cli.md "What vdmap gui and render open"). Sequences and sessions are opened elsewhere.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "mapping/core/types.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/keyframe/covisibility_graph.h"
#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap {

/// The kinds detectMapFile tells apart.
enum class MapFileKind {
  kSequence,      ///< a sequence of any kind (mapping/sequence/sequence.h: a folder layout, a bag, an MCAP)
  kMapFolder,     ///< a folder with global_ellipsoids.ply (`vdmap map` output)
  kSession,       ///< a .vdmap file (saved session)
  kEllipsoidPly,  ///< a PLY whose vertices carry covariance fields (cxx ... czz)
  kPointPly,      ///< a PLY whose vertices have x y z but no covariance
  kOctomap,       ///< an OctoMap .bt (binary) or .ot file
  kViewFile,      ///< a JSON view file (`vdmap_view` key)
};

/// A short name for messages and the file browser: "sequence", "map folder", "session",
/// "ellipsoid PLY", "point PLY", "OctoMap", "view file".
const char* mapFileKindName(MapFileKind kind);

/// What `path` holds, by its layout, extension and (for PLY and JSON) its header. Reads at most
/// the header of a file. Throws InputError naming the path when it does not exist or is none of
/// the kinds (the message lists them).
MapFileKind detectMapFile(const std::filesystem::path& path);

/// A map read whole from a map file: ellipsoids (world frame), and what a map folder adds.
/// Nothing in it can be rebuilt: it has no local maps.
struct StaticMap {
  MapFileKind kind = MapFileKind::kMapFolder;
  std::filesystem::path path;
  std::vector<Ellipsoid> ellipsoids;    ///< world frame; colour 0..255; keyframe -1 when unknown
  std::vector<StampedPose> keyframes;   ///< T_W_K by keyframe id (map folder's keyframes.txt)
  std::vector<CovisibilityEdge> edges;  ///< map folder's graph.txt
  std::vector<StampedPose> trajectory;  ///< T_W_C per mapped frame (map folder's trajectory.txt)
  /// Point PLY: the isotropic standard deviation given to every point (m); OctoMap: the leaf
  /// resolution of the finest level (m); 0 otherwise.
  double sigma_m = 0;
  std::size_t source_elements = 0;  ///< vertices of a PLY, occupied leaves of an OctoMap
  std::string stats_json;           ///< a map folder's stats.json text ("" when none)
  /// The colours are a height ramp the reader gave them (an OctoMap without colours), not the file's.
  bool height_colors = false;
};

/// The camera preset whose shape a map file's keyframe frustums are drawn in: a map folder
/// stores no intrinsics, and `vdmap map` of a TUM sequence would have this one.
inline constexpr const char* kStaticMapCamera = "tum-default";

/// Reads a map folder, ellipsoid PLY, point PLY or OctoMap into a StaticMap:
/// - map folder: global_ellipsoids.ply, keyframes.txt, trajectory.txt and graph.txt when present,
///   stats.json's text;
/// - ellipsoid PLY: as exported (docs/method.md 11);
/// - point PLY: each point an isotropic ellipsoid, sigma = half the median nearest-neighbour
///   spacing, colour from red green blue when present (else grey);
/// - OctoMap: each occupied leaf an ellipsoid at its centre with Sigma = size^2/12 I (the
///   covariance of a uniform cube), coloured by height.
/// Throws InputError naming the file for anything else, a file that does not parse, or one with
/// no ellipsoids, points or occupied leaves.
StaticMap loadStaticMap(const std::filesystem::path& path);

/// The local maps of a `vdmap map` folder: local_maps.ply's ellipsoids (the cells the filter kept) put
/// back into the containers of their keyframes (keyframes.txt's poses; stats.json's camera and cell
/// size), each into the cell its mean projects to. Every cell of the result is one the map kept; the
/// sensor model of stats.json goes to *model when given. Throws InputError naming the file that is
/// missing or does not fit (a folder of a version without stats.json's camera cannot be read this way).
KeyframeGraph readMapFolderLocalMaps(const std::filesystem::path& dir, SensorModel* model = nullptr);

/// One entry of a folder as a file browser lists it.
struct FolderEntry {
  std::filesystem::path path;
  bool folder = false;
  /// What it opens as; nullopt for a plain folder (to enter) or a file vdmap does not open.
  std::optional<MapFileKind> kind;
};

/// The entries of `dir`, folders first, each group by name (case-insensitive); hidden entries
/// (a leading '.') are left out. A folder's kind is a sequence or map folder by its layout; a
/// file's by detectMapFile (a PLY's or JSON's header only). Throws InputError naming `dir` when
/// it cannot be listed.
std::vector<FolderEntry> listFolder(const std::filesystem::path& dir);

/// The median over `points` of the distance to each one's nearest other point (m; 0 for fewer
/// than two points or all at one place). Deterministic; O(n log n) with a sorted cell grid.
double medianNearestNeighbourSpacing(const std::vector<Eigen::Vector3d>& points);

}  // namespace vdmap
