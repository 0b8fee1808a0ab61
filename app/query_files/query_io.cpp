#include "app/query_files/query_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/core/message_text.h"
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

std::pair<std::size_t, std::size_t> columnCounts(QueryOp op) {
  switch (op) {
    case QueryOp::kCollide: return {4, 5};
    case QueryOp::kRay: return {6, 7};
    default: return {3, 3};
  }
}

QueryInput readText(const fs::path& file, QueryOp op, double max_range_m) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot open (missing or unreadable)");
  const auto [least, most] = columnCounts(op);
  QueryInput input;
  std::string text;
  std::vector<double> values;
  // parseListNumber's messages name the column ("x is not finite ('nan')").
  static const std::vector<std::string> kNames[3] = {
      {"x", "y", "z"}, {"x", "y", "z", "r", "body"}, {"ox", "oy", "oz", "dx", "dy", "dz", "max_range"}};
  const std::vector<std::string>& names = kNames[op == QueryOp::kCollide ? 1 : op == QueryOp::kRay ? 2 : 0];
  for (int line = 1; std::getline(in, text); ++line) {
    if (!text.empty() && text.back() == '\r') text.pop_back();  // a CRLF file: not part of the line shown
    const std::vector<std::string> tokens = listWords(text);
    if (tokens.empty()) continue;
    if (tokens.size() < least || tokens.size() > most)
      throw InputError(file.string(), line,
                       std::string("expected ") + recordColumns(op) + " (--op " + queryOpName(op) + "), got " +
                           counted(static_cast<long long>(tokens.size()), "field") + ": " + printable(text));
    values.clear();
    for (std::size_t i = 0; i < tokens.size(); ++i) {
      values.push_back(parseListNumber(tokens[i], file, line, names[i].c_str()));
    }
    addRecord(op, values, names, max_range_m, &input,
              [&](const std::string& what) { throw InputError(file.string(), line, what); });
  }
  if (in.bad()) throw InputError(file.string(), "cannot be read");
  return input;
}

QueryInput readPly(const fs::path& file, QueryOp op, double max_range_m) {
  const PlyVertexTable table = readPlyVertices(file);
  std::vector<const char*> wanted = {"x", "y", "z"};
  std::vector<const char*> optional;
  if (op == QueryOp::kCollide) wanted.push_back("radius"), optional.push_back("body");
  if (op == QueryOp::kRay) wanted.insert(wanted.end(), {"nx", "ny", "nz"}), optional.push_back("max_range");
  std::vector<int> columns;
  for (const char* name : wanted) {
    const int c = table.column(name);
    if (c < 0)
      throw InputError(file.string(), std::string("the vertex element has no property '") + name + "' (--op " +
                                          queryOpName(op) + " reads " + recordColumns(op) +
                                          (op == QueryOp::kCollide ? ": x y z radius [body]" : "") +
                                          (op == QueryOp::kRay ? ": x y z nx ny nz [max_range]" : "") + ")");
    columns.push_back(c);
  }
  for (const char* name : optional)
    if (const int c = table.column(name); c >= 0) columns.push_back(c);
  std::vector<std::string> names;
  for (const int c : columns) names.push_back(table.names[static_cast<std::size_t>(c)]);
  QueryInput input;
  std::vector<double> values;
  for (std::size_t i = 0; i < table.count; ++i) {
    const auto fail = [&](const std::string& what) {
      throw InputError(file.string(), "vertex " + std::to_string(i) + ": " + what);
    };
    values.clear();
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const double v = table.at(i, columns[k]);
      if (!std::isfinite(v)) fail(names[k] + " is not finite (" + shortNumber(v) + ")");
      values.push_back(v);
    }
    addRecord(op, values, names, max_range_m, &input, fail);
  }
  return input;
}

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
  if (!queryOpReadsPoints(op)) throw std::logic_error("readQueryInput: --op reads no points");
  if (!fs::exists(file)) throw InputError(file.string(), "no such file (--points)");
  if (fs::is_directory(file)) throw InputError(file.string(), "is a folder, not a file (--points)");
  const std::string ext = file.extension().string();
  QueryInput input;
  if (ext == ".txt") input = readText(file, op, max_range_m);
  else if (ext == ".ply") input = readPly(file, op, max_range_m);
  else throw InputError(file.string(), "--points reads .txt (columns) or .ply (vertices), not '" + ext + "'");
  if (input.size() == 0)
    throw InputError(file.string(), std::string("has no records (expected lines of ") + recordColumns(op) + ")");
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

std::string queryAnswersPly(QueryOp op, const QueryInput& input, const QueryAnswers& a) {
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment vdmap query --op " +
                       std::string(queryOpName(op)) + "\nelement vertex " + std::to_string(input.size()) +
                       "\nproperty float x\nproperty float y\nproperty float z\n";
  PlyBody body;
  switch (op) {
    case QueryOp::kClassify:
      header += "property uchar class\nproperty float p\nproperty int keyframe\nproperty int ellipsoid\n";
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
      header += "property float distance\nproperty float gx\nproperty float gy\nproperty float gz\n";
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
    case QueryOp::kCollide: {
      header += "property float radius\nproperty int body\nproperty uchar collides\nproperty uchar touches_unknown\n"
                "property float clearance\n";
      for (const Sphere& s : input.spheres) {
        // One answer per body, in ascending body number.
        const auto it = std::lower_bound(a.bodies.begin(), a.bodies.end(), s.body,
                                         [](const BodyCollision& c, int body) { return c.body < body; });
        const BodyCollision* b = it != a.bodies.end() && it->body == s.body ? &*it : nullptr;
        if (!b) throw std::logic_error("queryAnswersPly: a sphere's body has no answer");
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
    }
    case QueryOp::kRay:
      header += "property float nx\nproperty float ny\nproperty float nz\nproperty uchar hit\nproperty float t\n"
                "property float hx\nproperty float hy\nproperty float hz\n";
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
    default: throw std::logic_error("queryAnswersPly: no records for this op");
  }
  header += "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  return header + body.bytes;
}

void writeQueryAnswers(const fs::path& file, QueryOp op, const QueryInput& input, const QueryAnswers& answers) {
  const std::string ext = file.extension().string();
  if (ext == ".ply") writeFileAtomically(file, queryAnswersPly(op, input, answers));
  else writeFileAtomically(file, queryAnswersText(op, input, answers));
}

}  // namespace vdmap::app
