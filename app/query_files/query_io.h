#pragma once
// The files of `vdmap query` (docs/cli.md "query"): the points, spheres or rays it reads (text
// columns or a PLY's vertices) and the answers it writes (text lines or a PLY), one record per
// input in input order.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "mapping/query/query_map.h"

namespace vdmap::app {

enum class QueryOp { kClassify, kDistance, kCollide, kRay, kGrid, kOctomap };
/// "classify", "distance", "collide", "ray", "grid", "octomap".
const char* queryOpName(QueryOp op);
/// Throws std::invalid_argument for another name.
QueryOp parseQueryOp(const std::string& name);
/// The ops that read --points (classify, distance, collide, ray).
inline bool queryOpReadsPoints(QueryOp op) { return op != QueryOp::kGrid && op != QueryOp::kOctomap; }

/// What --points holds, by op: points (classify, distance), spheres (collide) or rays (ray).
struct QueryInput {
  std::vector<Eigen::Vector3d> points;
  std::vector<Sphere> spheres;
  std::vector<Ray> rays;
  std::size_t size() const { return points.size() + spheres.size() + rays.size(); }
};

/// Reads --points for `op` by its extension: `.txt` (whitespace columns; '#' comments and blank
/// lines skipped) classify/distance `x y z`, collide `x y z r [body]`, ray `ox oy oz dx dy dz
/// [max_range]`; `.ply` (any PLY's vertex element): x y z, + radius [body] (collide), + nx ny nz
/// [max_range] (ray: the direction). A ray without its own max_range gets `max_range_m`. Throws
/// InputError "FILE:LINE: ..." (text) or "FILE: vertex N: ..." (PLY; N from 0) for a wrong column
/// count, a value that is not a finite number, a value other than the body beyond
/// kMaxPoseDistanceM (so every answer is a finite float), a radius <= 0, a body that is not a whole number,
/// a zero direction or a max_range <= 0; "FILE: ..." for no records, a missing property or another
/// extension.
QueryInput readQueryInput(const std::filesystem::path& file, QueryOp op, double max_range_m);

/// The answers, one vector filled per op.
struct QueryAnswers {
  std::vector<Classification> classes;    ///< classify
  std::vector<DistanceResult> distances;  ///< distance
  std::vector<BodyCollision> bodies;      ///< collide: one per body, ascending body number
  std::vector<RayHit> hits;               ///< ray
};

/// The text output (%.9g): classify `CLASS p keyframe ellipsoid`; distance `d gx gy gz` (`3.40282347e+38
/// 0 0 0`, the largest float, when no surface is near enough); collide one line per body `body
/// collides touches_unknown clearance sphere` (0/1 flags; the same largest float for no surface); ray `hit t x y z nx ny nz ellipsoid` or `miss`.
std::string queryAnswersText(QueryOp op, const QueryInput& input, const QueryAnswers& answers);

/// The PLY output (binary little endian): the input's vertices (x y z float; + radius, body for
/// spheres; + nx ny nz for rays) with the answers (classify: class uchar 0 unknown 1 free
/// 2 occupied, p float, keyframe, ellipsoid int; distance: distance, gx gy gz float; collide:
/// collides, touches_unknown uchar and the body's clearance float per sphere; ray: hit uchar, t,
/// hx hy hz float) and red green blue uchar: occupied / colliding / hit red, free / clear green,
/// unknown / miss grey, a clear body touching unknown space orange, distances from red (0) to
/// blue (1 m and more).
std::string queryAnswersPly(QueryOp op, const QueryInput& input, const QueryAnswers& answers);

/// Writes the answers by `file`'s extension (.txt or .ply) atomically.
void writeQueryAnswers(const std::filesystem::path& file, QueryOp op, const QueryInput& input,
                       const QueryAnswers& answers);

}  // namespace vdmap::app
