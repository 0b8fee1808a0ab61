#pragma once
// The files of `vdmap query` (docs/cli.md "query"): the points, spheres or rays it reads (text
// columns or a PLY's vertices) and the answers it writes (text lines or a PLY), one record per
// input in input order.
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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

/// Records read, answered and written at a time by answerQueryRecords (what memory holds).
constexpr std::size_t kQueryBatch = 65536;

/// Reads --points for `op` by its extension a batch of records at a time, so that a file of any
/// size takes the memory of one batch: `.txt` (whitespace columns; '#' comments and blank lines
/// skipped) classify/distance `x y z`, collide `x y z r [body]`, ray `ox oy oz dx dy dz
/// [max_range]`; `.ply` (any PLY's vertex element): x y z, + radius [body] (collide), + nx ny nz
/// [max_range] (ray: the direction). A ray without its own max_range gets `max_range_m`. Throws
/// InputError "FILE:LINE: ..." (text) or "FILE: vertex N: ..." (PLY; N from 0) when it reaches
/// a wrong column count, a value that is not a finite number, a value other than the body
/// beyond kMaxPoseDistanceM (so every answer is a finite float), a radius <= 0, a body that is
/// not a whole number, a zero direction or a max_range <= 0; "FILE: ..." on construction for a
/// missing file, a missing property or another extension.
class QueryRecordReader {
 public:
  QueryRecordReader(const std::filesystem::path& file, QueryOp op, double max_range_m);
  ~QueryRecordReader();
  /// Replaces `*batch` with the next records, at most `max` of them; false when none were left.
  bool next(std::size_t max, QueryInput* batch);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Reads and checks every record of --points (QueryRecordReader's errors, and "FILE: has no
/// records") in the memory of one batch; returns how many there are.
std::size_t countQueryRecords(const std::filesystem::path& file, QueryOp op, double max_range_m);

/// Every record of --points at once (QueryRecordReader's errors, and "FILE: has no records").
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

/// What the point ops ask besides their records (docs/cli.md "query").
struct PointQueryOptions {
  int keyframe = -1;                 ///< classify in this keyframe alone (-1: the whole map)
  double clearance_m = 0;            ///< collide
  double max_range_m = 8;            ///< ray: the range of rays without their own
  double max_distance_m = INFINITY;  ///< distance: stop looking past it
  std::size_t batch = kQueryBatch;   ///< records read, answered and written at a time
};

/// `v` rounded to 1e-6 (the summary's figures); a non-finite value as it is.
double rounded6(double v);

/// Answers the `records` records of `points` (countQueryRecords, so that they are known good)
/// and writes the answers to `out` atomically, by its extension: the text output above, or a
/// binary little-endian PLY of the input's vertices (x y z float; + radius, body for spheres;
/// + nx ny nz for rays) with the answers (classify: class uchar 0 unknown 1 free 2 occupied, p
/// float, keyframe, ellipsoid int; distance: distance, gx gy gz float; collide: collides,
/// touches_unknown uchar and the body's clearance float per sphere; ray: hit uchar, t, hx hy hz
/// float) and red green blue uchar: occupied / colliding / hit red, free / clear green, unknown
/// / miss grey, a clear body touching unknown space orange, distances from red (0) to blue (1 m
/// and more). Reads, asks and writes `options.batch` records at a time, so memory does not grow
/// with the records (collide holds one answer per body and reads the file twice for a PLY); the
/// bytes do not depend on the batch. `progress(done, records)` after each batch asked. Returns
/// the summary's figures (docs/cli.md): records, query_ms (asking only), records_per_s and the
/// op's counts, minimum and median.
nlohmann::json answerQueryRecords(const QueryMap& map, QueryOp op, const std::filesystem::path& points,
                                  std::size_t records, const std::filesystem::path& out,
                                  const PointQueryOptions& options,
                                  const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace vdmap::app
