#include "app/query_files/query_io.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "app/query_files/spilled_median.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/core/message_text.h"
#include "mapping/core/timing.h"
#include "mapping/files/ply_reader.h"
#include "mapping/io/text_list.h"
#include "mapping/io/trajectory_io.h"

namespace vdmap::app {
namespace {

namespace fs = std::filesystem;

constexpr const char* kOpNames[] = {"classify", "distance", "collide", "ray", "grid", "octomap"};

// What one record of `op` holds, for messages.
const char* recordColumns(QueryOp op) {
  switch (op) {
    case QueryOp::kCollide: return "x y z r [body]";
    case QueryOp::kRay: return "ox oy oz dx dy dz [max_range]";
    default: return "x y z";
  }
}

// "No surface" (+inf) in the answers: the largest float, so that no output holds a non-finite
// value. Records lie within kMaxPoseDistanceM, so every real distance is far below it.
double finiteAnswer(double v) { return std::isfinite(v) ? v : std::numeric_limits<float>::max(); }

// Checks and stores one record's values (already finite numbers, named `names`); `fail` throws
// the error for this record with a message.
template <typename Fail>
void addRecord(QueryOp op, const std::vector<double>& v, const std::vector<std::string>& names, double max_range_m,
               QueryInput* input, const Fail& fail) {
  // Coordinates (and radii, directions, ranges) as poses: within 10 km, where the float outputs
  // keep a millimetre and every distance stays finite.
  const std::size_t lengths = op == QueryOp::kCollide ? 4 : v.size();  // not the body number
  for (std::size_t i = 0; i < std::min(lengths, v.size()); ++i)
    if (std::abs(v[i]) > kMaxPoseDistanceM)
      fail(names[i] + " is " + shortNumber(v[i]) + ": query records lie within " +
           std::to_string(static_cast<int>(kMaxPoseDistanceM)) + " m of the origin");
  const Eigen::Vector3d p(v[0], v[1], v[2]);
  switch (op) {
    case QueryOp::kCollide: {
      if (!(v[3] > 0)) fail("the radius must be > 0, got " + shortNumber(v[3]));
      int body = 0;
      if (v.size() > 4) {
        if (v[4] != std::floor(v[4]) || std::abs(v[4]) > 2147483647.0)
          fail("the body must be a whole number, got " + shortNumber(v[4]));
        body = static_cast<int>(v[4]);
      }
      input->spheres.push_back({p, v[3], body});
      return;
    }
    case QueryOp::kRay: {
      const Eigen::Vector3d d(v[3], v[4], v[5]);
      if (!(d.norm() > 0) || !std::isfinite(d.norm())) fail("the direction dx dy dz is zero (expected a length > 0)");
      const double range = v.size() > 6 ? v[6] : max_range_m;
      if (!(range > 0)) fail("max_range must be > 0, got " + shortNumber(range));
      input->rays.push_back({p, d, range});
      return;
    }
    default: input->points.push_back(p);
  }
}

InputError noRecords(const fs::path& file, QueryOp op) {
  return InputError(file.string(), std::string("has no records (expected lines of ") + recordColumns(op) + ")");
}

std::pair<std::size_t, std::size_t> columnCounts(QueryOp op) {
  switch (op) {
    case QueryOp::kCollide: return {4, 5};
    case QueryOp::kRay: return {6, 7};
    default: return {3, 3};
  }
}

}  // namespace

struct QueryRecordReader::State {
  fs::path file;
  QueryOp op;
  double max_range_m;
  std::vector<double> values;
  // A text file: the stream, the line last read and its fields.
  std::ifstream text;
  int line = 0;
  std::string buffer;
  std::vector<std::string> tokens;
  // A PLY: its vertices, the columns read, the vertex next read.
  std::unique_ptr<PlyVertexReader> ply;
  std::vector<int> columns;
  std::vector<std::string> names;
  std::size_t vertex = 0;

  bool nextText(QueryInput* input);
  bool nextPly(QueryInput* input);
};

bool QueryRecordReader::State::nextText(QueryInput* input) {
  const auto [least, most] = columnCounts(op);
  // parseListNumber's messages name the column ("x is not finite ('nan')").
  static const std::vector<std::string> kNames[3] = {
      {"x", "y", "z"}, {"x", "y", "z", "r", "body"}, {"ox", "oy", "oz", "dx", "dy", "dz", "max_range"}};
  const std::vector<std::string>& column_names = kNames[op == QueryOp::kCollide ? 1 : op == QueryOp::kRay ? 2 : 0];
  while (std::getline(text, buffer)) {
    ++line;
    if (!buffer.empty() && buffer.back() == '\r') buffer.pop_back();  // a CRLF file: not part of the line shown
    tokens = listWords(buffer);
    if (tokens.empty()) continue;
    if (tokens.size() < least || tokens.size() > most)
      throw InputError(file.string(), line,
                       std::string("expected ") + recordColumns(op) + " (--op " + queryOpName(op) + "), got " +
                           counted(static_cast<long long>(tokens.size()), "field") + ": " + printable(buffer));
    values.clear();
    for (std::size_t i = 0; i < tokens.size(); ++i)
      values.push_back(parseListNumber(tokens[i], file, line, column_names[i].c_str()));
    addRecord(op, values, column_names, max_range_m, input,
              [&](const std::string& what) { throw InputError(file.string(), line, what); });
    return true;
  }
  if (text.bad()) throw InputError(file.string(), "cannot be read");
  return false;
}

bool QueryRecordReader::State::nextPly(QueryInput* input) {
  if (!ply->next()) return false;
  const std::size_t i = vertex++;
  const auto fail = [&](const std::string& what) {
    throw InputError(file.string(), "vertex " + std::to_string(i) + ": " + what);
  };
  values.clear();
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const double v = ply->row()[static_cast<std::size_t>(columns[k])];
    if (!std::isfinite(v)) fail(names[k] + " is not finite (" + shortNumber(v) + ")");
    values.push_back(v);
  }
  addRecord(op, values, names, max_range_m, input, fail);
  return true;
}

QueryRecordReader::QueryRecordReader(const fs::path& file, QueryOp op, double max_range_m)
    : state_(std::make_unique<State>()) {
  if (!queryOpReadsPoints(op)) throw std::logic_error("QueryRecordReader: --op reads no points");
  if (!fs::exists(file)) throw InputError(file.string(), "no such file (--points)");
  if (fs::is_directory(file)) throw InputError(file.string(), "is a folder, not a file (--points)");
  State& s = *state_;
  s.file = file, s.op = op, s.max_range_m = max_range_m;
  const std::string ext = file.extension().string();
  if (ext == ".txt") {
    s.text.open(file, std::ios::binary);
    if (!s.text) throw InputError(file.string(), "cannot open (missing or unreadable)");
    return;
  }
  if (ext != ".ply")
    throw InputError(file.string(), "--points reads .txt (columns) or .ply (vertices), not '" + ext + "'");
  s.ply = std::make_unique<PlyVertexReader>(file);
  std::vector<const char*> wanted = {"x", "y", "z"};
  std::vector<const char*> optional;
  if (op == QueryOp::kCollide) wanted.push_back("radius"), optional.push_back("body");
  if (op == QueryOp::kRay) wanted.insert(wanted.end(), {"nx", "ny", "nz"}), optional.push_back("max_range");
  for (const char* name : wanted) {
    const int c = s.ply->column(name);
    if (c < 0)
      throw InputError(file.string(), std::string("the vertex element has no property '") + name + "' (--op " +
                                          queryOpName(op) + " reads " + recordColumns(op) +
                                          (op == QueryOp::kCollide ? ": x y z radius [body]" : "") +
                                          (op == QueryOp::kRay ? ": x y z nx ny nz [max_range]" : "") + ")");
    s.columns.push_back(c);
  }
  for (const char* name : optional)
    if (const int c = s.ply->column(name); c >= 0) s.columns.push_back(c);
  for (const int c : s.columns) s.names.push_back(s.ply->names()[static_cast<std::size_t>(c)]);
}

QueryRecordReader::~QueryRecordReader() = default;

bool QueryRecordReader::next(std::size_t max, QueryInput* batch) {
  *batch = QueryInput{};
  State& s = *state_;
  while (batch->size() < max && (s.ply ? s.nextPly(batch) : s.nextText(batch))) {
  }
  return batch->size() > 0;
}

std::size_t countQueryRecords(const fs::path& file, QueryOp op, double max_range_m) {
  QueryRecordReader reader(file, op, max_range_m);
  QueryInput batch;
  std::size_t records = 0;
  while (reader.next(kQueryBatch, &batch)) records += batch.size();
  if (records == 0) throw noRecords(file, op);
  return records;
}

namespace {

// Binary little-endian values appended to a PLY body.
struct PlyBody {
  std::string bytes;
  template <typename T>
  void put(T v) {
    char raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    bytes.append(raw, sizeof(T));
  }
  void put3(const Eigen::Vector3d& v) {
    for (int k = 0; k < 3; ++k) put(static_cast<float>(v[k]));
  }
  void putDistance(double v) { put(static_cast<float>(finiteAnswer(v))); }
  void rgb(std::uint8_t r, std::uint8_t g, std::uint8_t b) { put(r), put(g), put(b); }
};

void classColour(Occupancy state, PlyBody* body) {
  switch (state) {
    case Occupancy::kOccupied: return body->rgb(220, 40, 40);
    case Occupancy::kFree: return body->rgb(40, 190, 70);
    case Occupancy::kUnknown: return body->rgb(150, 150, 150);
  }
}

}  // namespace

const char* queryOpName(QueryOp op) { return kOpNames[static_cast<int>(op)]; }

QueryOp parseQueryOp(const std::string& name) {
  for (int i = 0; i < 6; ++i)
    if (name == kOpNames[i]) return static_cast<QueryOp>(i);
  throw std::invalid_argument("unknown query '" + name +
                              "' (expected classify, distance, collide, ray, grid or octomap)");
}

QueryInput readQueryInput(const fs::path& file, QueryOp op, double max_range_m) {
  QueryRecordReader reader(file, op, max_range_m);
  QueryInput input;
  if (!reader.next(std::numeric_limits<std::size_t>::max(), &input)) throw noRecords(file, op);
  return input;
}

std::string queryAnswersText(QueryOp op, const QueryInput& input, const QueryAnswers& a) {
  std::string out;
  char line[512];
  switch (op) {
    case QueryOp::kClassify:
      out.reserve(a.classes.size() * 24);
      for (const Classification& c : a.classes) {
        std::snprintf(line, sizeof line, "%s %.9g %d %d\n", occupancyName(c.state), static_cast<double>(c.p_occupied),
                      c.keyframe, c.ellipsoid);
        out += line;
      }
      break;
    case QueryOp::kDistance:
      out.reserve(a.distances.size() * 48);
      for (const DistanceResult& d : a.distances) {
        std::snprintf(line, sizeof line, "%.9g %.9g %.9g %.9g\n", finiteAnswer(d.distance_m), d.gradient.x(),
                      d.gradient.y(), d.gradient.z());
        out += line;
      }
      break;
    case QueryOp::kCollide:
      for (const BodyCollision& b : a.bodies) {
        std::snprintf(line, sizeof line, "%d %d %d %.9g %d\n", b.body, b.collides ? 1 : 0, b.touches_unknown ? 1 : 0,
                      finiteAnswer(b.clearance_m), b.sphere);
        out += line;
      }
      break;
    case QueryOp::kRay:
      out.reserve(a.hits.size() * 64);
      for (const RayHit& h : a.hits) {
        if (!h.hit) {
          out += "miss\n";
          continue;
        }
        std::snprintf(line, sizeof line, "hit %.9g %.9g %.9g %.9g %.9g %.9g %.9g %d\n", h.t_m, h.point_W.x(),
                      h.point_W.y(), h.point_W.z(), h.normal_W.x(), h.normal_W.y(), h.normal_W.z(), h.ellipsoid);
        out += line;
      }
      break;
    default: throw std::logic_error("queryAnswersText: no records for this op");
  }
  (void)input;
  return out;
}

namespace {

// The PLY's header for `records` vertices of `op`'s answers.
std::string answersPlyHeader(QueryOp op, std::size_t records) {
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment vdmap query --op " +
                       std::string(queryOpName(op)) + "\nelement vertex " + std::to_string(records) +
                       "\nproperty float x\nproperty float y\nproperty float z\n";
  switch (op) {
    case QueryOp::kClassify:
      header += "property uchar class\nproperty float p\nproperty int keyframe\nproperty int ellipsoid\n";
      break;
    case QueryOp::kDistance:
      header += "property float distance\nproperty float gx\nproperty float gy\nproperty float gz\n";
      break;
    case QueryOp::kCollide:
      header += "property float radius\nproperty int body\nproperty uchar collides\nproperty uchar touches_unknown\n"
                "property float clearance\n";
      break;
    case QueryOp::kRay:
      header += "property float nx\nproperty float ny\nproperty float nz\nproperty uchar hit\nproperty float t\n"
                "property float hx\nproperty float hy\nproperty float hz\n";
      break;
    default: throw std::logic_error("answersPlyHeader: no records for this op");
  }
  return header + "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
}

// The PLY's vertices of the records `input` (collide: `a.bodies` holds every body's answer).
std::string answersPlyBody(QueryOp op, const QueryInput& input, const QueryAnswers& a) {
  PlyBody body;
  switch (op) {
    case QueryOp::kClassify:
      for (std::size_t i = 0; i < input.points.size(); ++i) {
        const Classification& c = a.classes[i];
        body.put3(input.points[i]);
        body.put(static_cast<std::uint8_t>(c.state));
        body.put(c.p_occupied);
        body.put(c.keyframe);
        body.put(c.ellipsoid);
        classColour(c.state, &body);
      }
      break;
    case QueryOp::kDistance:
      for (std::size_t i = 0; i < input.points.size(); ++i) {
        const DistanceResult& d = a.distances[i];
        body.put3(input.points[i]);
        body.putDistance(d.distance_m);
        body.put3(d.gradient);
        // Red at a surface to blue at 1 m and beyond.
        const double s = std::min(1.0, std::max(0.0, d.distance_m));
        body.rgb(static_cast<std::uint8_t>(230 * (1 - s) + 20), 40, static_cast<std::uint8_t>(230 * s + 20));
      }
      break;
    case QueryOp::kCollide:
      for (const Sphere& s : input.spheres) {
        // One answer per body, in ascending body number.
        const auto it = std::lower_bound(a.bodies.begin(), a.bodies.end(), s.body,
                                         [](const BodyCollision& c, int body) { return c.body < body; });
        const BodyCollision* b = it != a.bodies.end() && it->body == s.body ? &*it : nullptr;
        if (!b) throw std::logic_error("answersPlyBody: a sphere's body has no answer");
        body.put3(s.centre_W);
        body.put(static_cast<float>(s.radius_m));
        body.put(static_cast<std::int32_t>(s.body));
        body.put(static_cast<std::uint8_t>(b->collides));
        body.put(static_cast<std::uint8_t>(b->touches_unknown));
        body.putDistance(b->clearance_m);
        if (b->collides) body.rgb(220, 40, 40);
        else if (b->touches_unknown) body.rgb(240, 150, 30);
        else body.rgb(40, 190, 70);
      }
      break;
    case QueryOp::kRay:
      for (std::size_t i = 0; i < input.rays.size(); ++i) {
        const RayHit& h = a.hits[i];
        body.put3(input.rays[i].origin_W);
        body.put3(input.rays[i].direction_W);
        body.put(static_cast<std::uint8_t>(h.hit));
        body.putDistance(h.t_m);
        body.put3(h.point_W);
        if (h.hit) body.rgb(220, 40, 40);
        else body.rgb(150, 150, 150);
      }
      break;
    default: throw std::logic_error("answersPlyBody: no records for this op");
  }
  return std::move(body.bytes);
}

// Folds one batch's bodies (spheres counted from `first`) into `bodies`, as collide() over all
// the spheres at once folds them: the least clearance, the first sphere that gave it.
void foldBodies(const std::vector<BodyCollision>& batch, std::size_t first, std::map<int, BodyCollision>* bodies) {
  for (const BodyCollision& b : batch) {
    const auto [it, added] = bodies->try_emplace(b.body, b);
    BodyCollision& all = it->second;
    if (added) {
      if (all.sphere >= 0) all.sphere += static_cast<int>(first);
      continue;
    }
    all.collides = all.collides || b.collides;
    all.touches_unknown = all.touches_unknown || b.touches_unknown;
    if (b.clearance_m < all.clearance_m)
      all.clearance_m = b.clearance_m, all.sphere = b.sphere + static_cast<int>(first), all.closest_W = b.closest_W;
  }
}

// JSON has no infinity: null stands for "no surface".
nlohmann::json finiteOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(rounded6(v)) : nlohmann::json(nullptr);
}

}  // namespace

double rounded6(double v) { return std::isfinite(v) ? std::round(v * 1e6) / 1e6 : v; }

nlohmann::json answerQueryRecords(const QueryMap& map, QueryOp op, const fs::path& points, std::size_t records,
                                  const fs::path& out, const PointQueryOptions& options,
                                  const std::function<void(std::size_t, std::size_t)>& progress) {
  const bool ply = out.extension() == ".ply";
  double ms = 0;  // asking the map only, not reading or writing
  std::size_t counts[3] = {0, 0, 0}, inside = 0, beyond = 0, hits = 0;
  double min_distance = INFINITY;
  SpilledMedian medians;  // distances, or the hits' ranges
  std::map<int, BodyCollision> bodies;
  QueryAnswers answers;
  QueryInput batch;
  // Every record read again, in batches; `f(batch, first)` for each.
  const auto eachBatch = [&](const auto& f) {
    QueryRecordReader reader(points, op, options.max_range_m);
    std::size_t done = 0;
    while (reader.next(options.batch, &batch)) {
      f(done);
      done += batch.size();
    }
    if (done != records) throw InputError(points.string(), "changed while it was read");
  };
  const auto ask = [&](std::size_t first) {
    const auto start = std::chrono::steady_clock::now();
    const std::size_t n = batch.size();
    switch (op) {
      case QueryOp::kClassify:
        answers.classes.resize(n);
        if (options.keyframe >= 0) map.classifyInKeyframe(options.keyframe, batch.points, answers.classes);
        else map.classify(batch.points, answers.classes);
        break;
      case QueryOp::kDistance:
        answers.distances.resize(n);
        map.distance(batch.points, answers.distances, options.max_distance_m);
        break;
      case QueryOp::kCollide: foldBodies(map.collide(batch.spheres, options.clearance_m), first, &bodies); break;
      case QueryOp::kRay:
        answers.hits.resize(n);
        map.castRays(batch.rays, answers.hits);
        break;
      default: throw std::logic_error("answerQueryRecords: no records for this op");
    }
    ms += msSince(start);
    for (const Classification& c : answers.classes) ++counts[static_cast<int>(c.state)];
    for (const DistanceResult& r : answers.distances) {
      medians.add(r.distance_m);
      min_distance = std::min(min_distance, r.distance_m);
      inside += r.distance_m == 0;
      beyond += !std::isfinite(r.distance_m) || r.distance_m >= options.max_distance_m;
    }
    for (const RayHit& h : answers.hits)
      if (h.hit) medians.add(h.t_m), ++hits;
    if (progress) progress(first + n, records);
  };
  writeFileAtomically(out, [&](const ByteSink& sink) {
    if (ply) sink(answersPlyHeader(op, records));
    if (op != QueryOp::kCollide) {
      eachBatch([&](std::size_t first) {
        ask(first);
        sink(ply ? answersPlyBody(op, batch, answers) : queryAnswersText(op, batch, answers));
      });
      return;
    }
    // A body's answer needs all its spheres: ask them all, then write.
    eachBatch(ask);
    for (auto& [number, body] : bodies) answers.bodies.push_back(body);
    if (!ply) return sink(queryAnswersText(op, batch, answers));
    eachBatch([&](std::size_t) { sink(answersPlyBody(op, batch, answers)); });
  });

  nlohmann::json summary;
  summary["records"] = records;
  summary["query_ms"] = rounded6(ms);
  summary["records_per_s"] = ms > 0 ? std::round(1e3 * static_cast<double>(records) / ms) : 0.0;
  switch (op) {
    case QueryOp::kClassify:
      summary["occupied"] = counts[static_cast<int>(Occupancy::kOccupied)];
      summary["free"] = counts[static_cast<int>(Occupancy::kFree)];
      summary["unknown"] = counts[static_cast<int>(Occupancy::kUnknown)];
      if (options.keyframe >= 0) summary["keyframe"] = options.keyframe;
      break;
    case QueryOp::kDistance:
      summary["min_m"] = finiteOrNull(min_distance);
      summary["median_m"] = finiteOrNull(medians.median());
      summary["inside"] = inside;
      summary["beyond"] = beyond;
      break;
    case QueryOp::kCollide: {
      std::size_t collide = 0, unknown = 0;
      double clearance = INFINITY;
      for (const BodyCollision& b : answers.bodies) {
        collide += b.collides;
        unknown += b.touches_unknown;
        clearance = std::min(clearance, b.clearance_m);
      }
      summary["bodies"] = answers.bodies.size();
      summary["colliding"] = collide;
      summary["touching_unknown"] = unknown;
      summary["min_clearance_m"] = finiteOrNull(clearance);
      break;
    }
    case QueryOp::kRay:
      summary["hits"] = hits;
      summary["misses"] = records - hits;
      summary["median_t_m"] = hits == 0 ? nlohmann::json(nullptr) : nlohmann::json(rounded6(medians.median()));
      break;
    default: break;
  }
  return summary;
}

}  // namespace vdmap::app
