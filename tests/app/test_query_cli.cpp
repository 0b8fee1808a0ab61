// vdmap query end to end on a tiny session of the built-in scene: every op round-trips text and
// PLY and gives the library's answers (QueryMap on the same session); bad records are one error
// line naming the line; the occupancy grid and the .bt parse back and follow their rules against
// a plain per-point reference; corrected poses move the answers; an empty map answers unknown.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <octomap/OcTree.h>

#include "app/query_files/query_io.h"
#include "app/query_files/spilled_median.h"
#include "mapping/core/error.h"
#include "mapping/core/timing.h"
#include "mapping/files/occupancy_grid.h"
#include "mapping/files/ply_reader.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "tests/support/test_util.h"

namespace vdmap::test {
namespace {

using app::QueryOp;

std::string q(const fs::path& p) {
  std::string quoted(1, '\'');
  quoted += p.string();
  quoted += '\'';
  return quoted;
}

// The tiny session (3 keyframes of the built-in walk, 16 px cells), made once.
struct Fixture {
  TempDir dir;
  fs::path session;
  fs::path keyframes;  // the map folder's keyframes.txt (T_W_K per keyframe timestamp)
  Fixture() {
    const RunResult s = runVdmap("synth --builtin --builtin-frames 8 --out " + q(dir / "bi"));
    if (s.exit_code != 0) throw std::runtime_error("synth: " + s.err);
    session = dir / "s.vdmap";
    const RunResult m = runVdmap("map " + q(dir / "bi") + " --frames 0:3 --cell-size 16 --out " + q(dir / "m") +
                                 " --save " + q(session));
    if (m.exit_code != 0) throw std::runtime_error("map: " + m.err);
    keyframes = dir / "m" / "keyframes.txt";
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

// The library's QueryMap on a session, built as vdmap query builds it (the session's own
// global-map parameters; --keyframe-poses applied first when given).
QueryMap libraryMap(const fs::path& session, const fs::path& poses = {}) {
  SessionDecodeOptions decode;
  decode.decode_images = false;
  Session s = loadSession(session, decode);
  if (!poses.empty()) applyTrajectoryFile(s.graph, poses);
  if (s.graph.size() == 0) return QueryMap();
  const GlobalMap global = buildGlobalMap(s.graph, s.info.global);
  return QueryMap::build(s.graph, global, QueryParams{});
}
const QueryMap& tinyMap() {
  static const QueryMap map = libraryMap(fixture().session);
  return map;
}

// Points near surfaces (global means), spread over the seen box, and far outside it.
std::vector<Eigen::Vector3d> testPoints() {
  const QueryMap& map = tinyMap();
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  std::mt19937 rng(36);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 240; ++i) points.push_back(lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng))));
  // Points on surfaces: the first hits of rays from the box's centre.
  std::vector<Ray> rays;
  for (int i = 0; i < 60; ++i) {
    Ray r;
    r.origin_W = 0.5 * (lo + hi);
    r.direction_W = Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    rays.push_back(r);
  }
  std::vector<RayHit> hits(rays.size());
  map.castRays(rays, hits);
  for (const RayHit& h : hits)
    if (h.hit) points.push_back(h.point_W);
  points.push_back({100, 100, 100});
  points.push_back({-50, 3, 2});
  return points;
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

void writePointsTxt(const fs::path& file, const std::vector<Eigen::Vector3d>& points) {
  std::string text = "# x y z\n\n";
  for (const Eigen::Vector3d& p : points) text += number(p.x()) + " " + number(p.y()) + "\t" + number(p.z()) + "\n";
  writeText(file, text);
}

// An ascii PLY of `rows` under the property names `names` (all double).
void writePly(const fs::path& file, const std::vector<std::string>& names,
              const std::vector<std::vector<double>>& rows) {
  std::string text = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(rows.size()) + "\n";
  for (const std::string& n : names) text += "property double " + n + "\n";
  text += "end_header\n";
  for (const auto& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) {
      if (i) text += ' ';
      text += number(row[i]);
    }
    text += "\n";
  }
  writeText(file, text);
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

app::QueryAnswers libraryAnswers(const QueryMap& map, QueryOp op, const app::QueryInput& input, int keyframe = -1,
                                 double clearance = 0) {
  app::QueryAnswers a;
  switch (op) {
    case QueryOp::kClassify:
      a.classes.resize(input.points.size());
      if (keyframe >= 0) map.classifyInKeyframe(keyframe, input.points, a.classes);
      else map.classify(input.points, a.classes);
      break;
    case QueryOp::kDistance:
      a.distances.resize(input.points.size());
      map.distance(input.points, a.distances);
      break;
    case QueryOp::kCollide: a.bodies = map.collide(input.spheres, clearance); break;
    case QueryOp::kRay:
      a.hits.resize(input.rays.size());
      map.castRays(input.rays, a.hits);
      break;
    default: break;
  }
  return a;
}

// Records of every op as text and PLY rows.
struct OpInput {
  QueryOp op;
  std::string txt;
  std::vector<std::string> ply_names;
  std::vector<std::vector<double>> ply_rows;
};

std::vector<OpInput> opInputs() {
  const std::vector<Eigen::Vector3d> points = testPoints();
  std::vector<OpInput> ops;
  for (const QueryOp op : {QueryOp::kClassify, QueryOp::kDistance}) {
    OpInput in{op, "", {"x", "y", "z"}, {}};
    for (const Eigen::Vector3d& p : points) {
      in.txt += number(p.x()) + " " + number(p.y()) + " " + number(p.z()) + "\n";
      in.ply_rows.push_back({p.x(), p.y(), p.z()});
    }
    ops.push_back(in);
  }
  OpInput collide{QueryOp::kCollide, "", {"x", "y", "z", "radius", "body"}, {}};
  for (std::size_t i = 0; i < points.size(); i += 3) {
    const double r = 0.02 + 0.01 * static_cast<double>(i % 7);
    const int body = static_cast<int>(i / 30);
    collide.txt += number(points[i].x()) + " " + number(points[i].y()) + " " + number(points[i].z()) + " " + number(r) +
                   " " + std::to_string(body) + "\n";
    collide.ply_rows.push_back({points[i].x(), points[i].y(), points[i].z(), r, static_cast<double>(body)});
  }
  ops.push_back(collide);
  OpInput ray{QueryOp::kRay, "", {"x", "y", "z", "nx", "ny", "nz"}, {}};
  Eigen::Vector3d lo, hi;
  tinyMap().seenBounds(&lo, &hi);
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d d = points[i] - centre;
    if (d.norm() < 1e-3) continue;
    ray.txt += number(centre.x()) + " " + number(centre.y()) + " " + number(centre.z()) + " " + number(d.x()) + " " +
               number(d.y()) + " " + number(d.z()) + "\n";
    ray.ply_rows.push_back({centre.x(), centre.y(), centre.z(), d.x(), d.y(), d.z()});
  }
  ops.push_back(ray);
  return ops;
}

TEST(QueryCli, EveryOpRoundTripsTextAndPlyWithTheLibrarysAnswers) {
  const Fixture& f = fixture();
  TempDir tmp;
  for (const OpInput& in : opInputs()) {
    const std::string op = app::queryOpName(in.op);
    SCOPED_TRACE(op);
    writeText(tmp / (op + ".txt"), in.txt);
    writePly(tmp / (op + ".ply"), in.ply_names, in.ply_rows);
    const app::QueryInput from_txt = app::readQueryInput(tmp / (op + ".txt"), in.op, 8.0);
    const app::QueryInput from_ply = app::readQueryInput(tmp / (op + ".ply"), in.op, 8.0);
    ASSERT_EQ(from_txt.size(), in.ply_rows.size());
    ASSERT_EQ(from_ply.size(), in.ply_rows.size());
    const std::string expected = app::queryAnswersText(in.op, from_txt, libraryAnswers(tinyMap(), in.op, from_txt));
    EXPECT_EQ(expected, app::queryAnswersText(in.op, from_ply, libraryAnswers(tinyMap(), in.op, from_ply)))
        << "the same records from text and PLY";
    for (const char* input_ext : {".txt", ".ply"})
      for (const char* out_ext : {".txt", ".ply"}) {
        const fs::path out = tmp / ("out-" + op + input_ext + out_ext);
        const RunResult r = runVdmap("query " + q(f.session) + " --op " + op + " --points " +
                                     q(tmp / (op + input_ext)) + " --out " + q(out));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        EXPECT_EQ(r.err, "");
        EXPECT_NE(r.out.find(" -> " + out.string()), std::string::npos) << r.out;
        if (std::string(out_ext) == ".txt") {
          EXPECT_EQ(readFile(out), expected) << input_ext;
          continue;
        }
        const PlyVertexTable table = readPlyVertices(out);
        const std::size_t records = in.op == QueryOp::kCollide ? from_txt.spheres.size() : from_txt.size();
        ASSERT_EQ(table.count, records);
        for (const char* column : {"x", "y", "z", "red", "green", "blue"}) EXPECT_GE(table.column(column), 0) << column;
        const app::QueryAnswers a = libraryAnswers(tinyMap(), in.op, from_txt);
        for (std::size_t i = 0; i < table.count; ++i) {
          for (double v :
               {table.at(i, table.column("x")), table.at(i, table.column("y")), table.at(i, table.column("z"))})
            EXPECT_TRUE(std::isfinite(v));
          switch (in.op) {
            case QueryOp::kClassify:
              EXPECT_EQ(table.at(i, table.column("class")), static_cast<double>(a.classes[i].state)) << i;
              EXPECT_EQ(static_cast<float>(table.at(i, table.column("p"))), a.classes[i].p_occupied) << i;
              break;
            case QueryOp::kDistance: {
              const double d = table.at(i, table.column("distance"));
              if (std::isfinite(a.distances[i].distance_m))
                EXPECT_EQ(static_cast<float>(d), static_cast<float>(a.distances[i].distance_m)) << i;
              else EXPECT_EQ(static_cast<float>(d), std::numeric_limits<float>::max()) << i;
              break;
            }
            case QueryOp::kRay:
              EXPECT_EQ(table.at(i, table.column("hit")), a.hits[i].hit ? 1.0 : 0.0) << i;
              if (a.hits[i].hit) {
                EXPECT_EQ(static_cast<float>(table.at(i, table.column("t"))), static_cast<float>(a.hits[i].t_m));
              }
              break;
            case QueryOp::kCollide: {
              const int body = static_cast<int>(table.at(i, table.column("body")));
              const auto b = std::find_if(a.bodies.begin(), a.bodies.end(),
                                          [&](const BodyCollision& c) { return c.body == body; });
              ASSERT_NE(b, a.bodies.end());
              EXPECT_EQ(table.at(i, table.column("collides")), b->collides ? 1.0 : 0.0);
              break;
            }
            default: break;
          }
        }
      }
  }
}

// Records are read, asked and written a batch at a time: batches of any size, splitting bodies
// and ending anywhere, write the bytes and summary of one batch holding the whole file.
TEST(QueryCli, BatchesOfAnySizeWriteTheSameBytes) {
  TempDir tmp;
  for (const OpInput& in : opInputs()) {
    const std::string op = app::queryOpName(in.op);
    writeText(tmp / (op + ".txt"), in.txt);
    writePly(tmp / (op + ".ply"), in.ply_names, in.ply_rows);
    const std::size_t n = in.ply_rows.size();
    for (const char* input_ext : {".txt", ".ply"})
      for (const char* out_ext : {".txt", ".ply"}) {
        const fs::path points = tmp / (op + input_ext);
        ASSERT_EQ(app::countQueryRecords(points, in.op, 8.0), n);
        std::string whole;
        nlohmann::json whole_summary;
        for (const std::size_t batch : {n, std::size_t{1}, std::size_t{2}, std::size_t{7}, n - 1, n + 1}) {
          SCOPED_TRACE(op + input_ext + out_ext + " in batches of " + std::to_string(batch));
          app::PointQueryOptions options;
          options.batch = batch;
          options.clearance_m = 0.05;
          std::size_t last = 0, calls = 0;
          const fs::path out = tmp / ("out" + std::string(out_ext));
          nlohmann::json summary = app::answerQueryRecords(tinyMap(), in.op, points, n, out, options,
                                                           [&](std::size_t done, std::size_t total) {
                                                             EXPECT_EQ(total, n);
                                                             EXPECT_EQ(done, std::min(n, last + batch));
                                                             last = done, ++calls;
                                                           });
          EXPECT_EQ(last, n);
          EXPECT_EQ(calls, (n + batch - 1) / batch);
          summary.erase("query_ms");
          summary.erase("records_per_s");
          if (batch == n) {
            whole = readFile(out), whole_summary = summary;
            continue;
          }
          EXPECT_EQ(readFile(out), whole);
          EXPECT_EQ(summary, whole_summary);
        }
        if (std::string(out_ext) == ".txt") {
          const app::QueryInput all = app::readQueryInput(points, in.op, 8.0);
          EXPECT_EQ(whole, app::queryAnswersText(in.op, all, libraryAnswers(tinyMap(), in.op, all, -1, 0.05)));
        }
      }
  }
}

// The summary's median over more values than memory holds: the same as median() of them all.
TEST(QueryCli, SpilledMedianIsTheMedian) {
  std::mt19937 rng(46);
  std::uniform_real_distribution<double> u(-2, 2);
  for (const std::size_t n : {1, 2, 3, 10, 11, 1000, 1001}) {
    std::vector<double> values;
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t kind = i % 9;
      values.push_back(kind == 0 ? 0.0 : kind == 1 ? INFINITY : kind == 2 ? -INFINITY : kind == 3 ? 0.25 : u(rng));
    }
    for (const std::size_t memory : {1, 3, 64, 100000}) {
      app::SpilledMedian m(memory);
      for (const double v : values) m.add(v);
      EXPECT_EQ(m.size(), n);
      const double expected = median(values), got = m.median();
      EXPECT_TRUE(expected == got || (std::isnan(expected) && std::isnan(got))) << n << " values, " << memory;
    }
  }
  EXPECT_EQ(app::SpilledMedian(2).median(), 0.0);
}

// The answers are not trivial on this map: every class occurs, distances vary, rays hit.
TEST(QueryCli, TheTinyMapGivesEveryKindOfAnswer) {
  const std::vector<Eigen::Vector3d> points = testPoints();
  std::vector<Classification> c(points.size());
  tinyMap().classify(points, c);
  int counts[3] = {0, 0, 0};
  for (const Classification& x : c) ++counts[static_cast<int>(x.state)];
  EXPECT_GT(counts[0], 0);
  EXPECT_GT(counts[1], 0);
  EXPECT_GT(counts[2], 0);
}

TEST(QueryCli, SummaryAsJsonCountsEveryPoint) {
  const Fixture& f = fixture();
  TempDir tmp;
  const std::vector<Eigen::Vector3d> points = testPoints();
  writePointsTxt(tmp / "p.txt", points);
  const RunResult r = runVdmap("query " + q(f.session) + " --op classify --points " + q(tmp / "p.txt") + " --out " +
                               q(tmp / "c.txt") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["records"].get<std::size_t>(), points.size());
  EXPECT_EQ(j["occupied"].get<std::size_t>() + j["free"].get<std::size_t>() + j["unknown"].get<std::size_t>(),
            points.size());
  EXPECT_EQ(j["keyframes"], 3);
  const auto plain =
      runVdmap("query " + q(f.session) + " --op distance --points " + q(tmp / "p.txt") + " --out " + q(tmp / "d.txt"));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_NE(plain.out.find("distance of " + std::to_string(points.size()) + " points: min "), std::string::npos)
      << plain.out;
}

// The summary line prints lengths to the millimetre, every digit (a length was cut to 8
// characters: 17318.605 m read "17318.60 m"), and counts agree with their nouns.
TEST(QueryCli, SummaryPrintsWholeLengthsAndCountedNouns) {
  const Fixture& f = fixture();
  TempDir tmp;
  writeText(tmp / "far.txt", "9999 9999 9999\n");
  const std::string asked =
      "query " + q(f.session) + " --op distance --points " + q(tmp / "far.txt") + " --out " + q(tmp / "d.txt");
  const RunResult json = runVdmap(asked + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const double median_m = nlohmann::json::parse(json.out)["median_m"].get<double>();
  ASSERT_GT(median_m, 1e4);
  char metres[32];
  std::snprintf(metres, sizeof metres, "%.9g m", std::round(median_m * 1e3) / 1e3);
  const RunResult plain = runVdmap(asked);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_NE(plain.out.find(std::string("distance of 1 point: min ") + metres + ", median " + metres), std::string::npos)
      << plain.out;

  writeText(tmp / "spheres.txt", "0 0 1 0.1 1\n0 0 2 0.1 2\n");
  const RunResult collide = runVdmap("query " + q(f.session) + " --op collide --points " + q(tmp / "spheres.txt") +
                                     " --out " + q(tmp / "c.txt"));
  ASSERT_EQ(collide.exit_code, 0) << collide.err;
  EXPECT_NE(collide.out.find("collide 2 spheres in 2 bodies:"), std::string::npos) << collide.out;
  writeText(tmp / "ray.txt", "0 0 1 1 0 0\n");
  const RunResult ray =
      runVdmap("query " + q(f.session) + " --op ray --points " + q(tmp / "ray.txt") + " --out " + q(tmp / "r.txt"));
  ASSERT_EQ(ray.exit_code, 0) << ray.err;
  EXPECT_TRUE(std::regex_search(ray.out, std::regex("^ray 1 ray: (1 hit, 0 misses|0 hits, 1 miss),"))) << ray.out;
}

TEST(QueryCli, OneAndTwoThreadsWriteTheSameBytes) {
  const Fixture& f = fixture();
  TempDir tmp;
  writePointsTxt(tmp / "p.txt", testPoints());
  for (const char* op : {"classify", "distance"}) {
    std::string outputs[2];
    for (int threads = 1; threads <= 2; ++threads) {
      const fs::path out = tmp / (std::string(op) + std::to_string(threads) + ".txt");
      const RunResult r = runVdmap("query " + q(f.session) + " --op " + op + " --points " + q(tmp / "p.txt") +
                                   " --threads " + std::to_string(threads) + " --out " + q(out));
      ASSERT_EQ(r.exit_code, 0) << r.err;
      outputs[threads - 1] = readFile(out);
    }
    EXPECT_EQ(outputs[0], outputs[1]) << op;
    EXPECT_FALSE(outputs[0].empty());
  }
}

TEST(QueryCli, KeyframeClassifiesInThatKeyframeAlone) {
  const Fixture& f = fixture();
  TempDir tmp;
  const std::vector<Eigen::Vector3d> points = testPoints();
  writePointsTxt(tmp / "p.txt", points);
  const app::QueryInput input = app::readQueryInput(tmp / "p.txt", QueryOp::kClassify, 8.0);
  for (int k = 0; k < 3; ++k) {
    const RunResult r = runVdmap("query " + q(f.session) + " --op classify --keyframe " + std::to_string(k) +
                                 " --points " + q(tmp / "p.txt") + " --out " + q(tmp / "k.txt"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(readFile(tmp / "k.txt"), app::queryAnswersText(QueryOp::kClassify, input,
                                                             libraryAnswers(tinyMap(), QueryOp::kClassify, input, k)));
  }
  const RunResult bad = runVdmap("query " + q(f.session) + " --op classify --keyframe 3 --points " + q(tmp / "p.txt") +
                                 " --out " + q(tmp / "bad.txt"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("--keyframe 3: the session has 3 keyframes (0..2)"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(tmp / "bad.txt"));
}

// A bad record is one error line naming the file and line (vertex for a PLY), exit 1, no output.
TEST(QueryCli, NanOnLine17IsOneErrorNamingTheLine) {
  const Fixture& f = fixture();
  TempDir tmp;
  std::string text = "# x y z\n";
  for (int line = 2; line <= 20; ++line) text += line == 17 ? "0.5 nan 1\n" : "0.5 0.25 1\n";
  writeText(tmp / "pts.txt", text);
  const RunResult r = runVdmap("query " + q(f.session) + " --op classify --points " + q(tmp / "pts.txt") + " --out " +
                               q(tmp / "out.txt"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "vdmap query: error: " + (tmp / "pts.txt").string() + ":17: y is not finite ('nan')\n");
  EXPECT_FALSE(fs::exists(tmp / "out.txt"));
  // A PLY: the reader refuses a non-finite value itself (one line naming the file); a record
  // that is wrong for the op names its vertex (from 0).
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 20\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float radius\nend_header\n";
  for (int v = 0; v < 20; ++v)
    for (const float c : {0.5f, 0.25f, 1.0f, v == 16 ? 0.0f : 0.1f})
      ply.append(reinterpret_cast<const char*>(&c), sizeof c);
  writeText(tmp / "pts.ply", ply);
  const RunResult p = runVdmap("query " + q(f.session) + " --op collide --points " + q(tmp / "pts.ply") + " --out " +
                               q(tmp / "out.ply"));
  EXPECT_EQ(p.exit_code, 1);
  EXPECT_EQ(p.err,
            "vdmap query: error: " + (tmp / "pts.ply").string() + ": vertex 16: the radius must be > 0, got 0\n");
  // Errors are found in file order: the last vertex's infinity alone.
  const float inf = INFINITY, good = 0.1f;
  ply.replace(ply.size() - 4 - 3 * 16, 4, reinterpret_cast<const char*>(&good), 4);  // vertex 16's radius
  ply.replace(ply.size() - 4, 4, reinterpret_cast<const char*>(&inf), 4);
  writeText(tmp / "pts.ply", ply);
  const RunResult n = runVdmap("query " + q(f.session) + " --op collide --points " + q(tmp / "pts.ply") + " --out " +
                               q(tmp / "out.ply"));
  EXPECT_EQ(n.exit_code, 1);
  EXPECT_EQ(n.err, "vdmap query: error: " + (tmp / "pts.ply").string() +
                       ": element data has a value that is not finite (NaN or infinity)\n");
  EXPECT_FALSE(fs::exists(tmp / "out.ply"));
}

TEST(QueryCli, RecordsAreCheckedPerOp) {
  TempDir tmp;
  const auto error = [&tmp](const std::string& text, QueryOp op) {
    writeText(tmp / "r.txt", text);
    try {
      app::readQueryInput(tmp / "r.txt", op, 8.0);
    } catch (const InputError& e) {
      return std::string(e.what()).substr((tmp / "r.txt").string().size());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("1 2 3\n1 2\n", QueryOp::kClassify), ":2: expected x y z (--op classify), got 2 fields: '1 2'");
  // A comment after the columns is a comment, not a field.
  EXPECT_EQ(error("1 2 3 # a note\n1 2 # x y\n", QueryOp::kClassify),
            ":2: expected x y z (--op classify), got 2 fields: '1 2 # x y'");
  EXPECT_EQ(error("1 2 3\r\n1 2\r\n", QueryOp::kClassify), ":2: expected x y z (--op classify), got 2 fields: '1 2'");
  EXPECT_EQ(error("1 2 3 0.1 0\n1 2 3 0 1\n", QueryOp::kCollide), ":2: the radius must be > 0, got 0");
  EXPECT_EQ(error("1 2 3 0.1 0.5\n", QueryOp::kCollide), ":1: the body must be a whole number, got 0.5");
  EXPECT_EQ(error("0 0 0 0 0 0\n", QueryOp::kRay), ":1: the direction dx dy dz is zero (expected a length > 0)");
  EXPECT_EQ(error("0 0 0 0 0 1 -2\n", QueryOp::kRay), ":1: max_range must be > 0, got -2");
  EXPECT_EQ(error("# only a comment\n\n", QueryOp::kDistance), ": has no records (expected lines of x y z)");
  EXPECT_EQ(error("1 2 x\n", QueryOp::kDistance), ":1: expected a number for z, got 'x'");
  // Good records: bodies, per-ray ranges, CRLF line ends.
  writeText(tmp / "ok.txt", "0 0 0 0 0 2 3.5\r\n1 1 1 1 0 0\r\n");
  const app::QueryInput rays = app::readQueryInput(tmp / "ok.txt", QueryOp::kRay, 8.0);
  ASSERT_EQ(rays.rays.size(), 2u);
  EXPECT_EQ(rays.rays[0].max_range_m, 3.5);
  EXPECT_EQ(rays.rays[1].max_range_m, 8.0);
}

// The ROS map_server files parse back; every cell follows the column rule, checked point by
// point against the map (the plain reference: one sample at a time).
TEST(QueryCli, GridParsesBackAndFollowsTheColumnRule) {
  const Fixture& f = fixture();
  TempDir tmp;
  const double res = 0.5;
  const RunResult r =
      runVdmap("query " + q(f.session) + " --op grid --resolution 0.5 --band 0.3:0.9 --out " + q(tmp / "map.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string yaml = readFile(tmp / "map.yaml");
  EXPECT_NE(yaml.find("\nimage: map.pgm\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("\nmode: trinary\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("\nresolution: 0.5\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"), std::string::npos) << yaml;
  double x0 = NAN, y0 = NAN;
  ASSERT_EQ(std::sscanf(yaml.substr(yaml.find("origin: [")).c_str(), "origin: [%lf, %lf, 0.0]", &x0, &y0), 2) << yaml;
  EXPECT_NEAR(x0 / res, std::round(x0 / res), 1e-9);
  const std::string pgm = readFile(tmp / "map.pgm");
  std::istringstream in(pgm);
  std::string magic, comment;
  int width = 0, height = 0, maxval = 0;
  in >> magic;
  in.ignore(1);
  std::getline(in, comment);
  in >> width >> height >> maxval;
  in.ignore(1);
  ASSERT_EQ(magic, "P5");
  ASSERT_EQ(maxval, 255);
  ASSERT_GT(width, 2);
  ASSERT_GT(height, 2);
  const std::string cells = pgm.substr(static_cast<std::size_t>(in.tellg()));
  ASSERT_EQ(cells.size(), static_cast<std::size_t>(width) * height);
  int counts[256] = {};
  for (const char c : cells) ++counts[static_cast<std::uint8_t>(c)];
  EXPECT_EQ(counts[0] + counts[205] + counts[254], width * height) << "values other than 0, 205, 254";
  EXPECT_GT(counts[0], 0);
  EXPECT_GT(counts[254], 0);
  // The extent covers the seen box.
  Eigen::Vector3d lo, hi;
  tinyMap().seenBounds(&lo, &hi);
  EXPECT_LE(x0, lo.x());
  EXPECT_LE(y0, lo.y());
  EXPECT_GE(x0 + width * res, hi.x());
  EXPECT_GE(y0 + height * res, hi.y());
  // Reference: the same sub-box centres asked one at a time.
  const int layers = static_cast<int>(std::ceil(0.6 / 0.02 - 1e-9));
  const double hz = 0.6 / layers, half_diagonal = 0.5 * std::sqrt(2 * 0.25 * 0.25 + hz * hz);
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) {
      const int j = height - 1 - row;
      bool occupied = false, free = false;
      for (int s = 0; s < 4; ++s)
        for (int l = 0; l < layers; ++l) {
          const Eigen::Vector3d p(x0 + (col + 0.25 + 0.5 * (s & 1)) * res, y0 + (j + 0.25 + 0.5 * (s >> 1)) * res,
                                  0.3 + (l + 0.5) * hz);
          DistanceResult d;
          tinyMap().distance({&p, 1}, {&d, 1});
          occupied = occupied || d.distance_m <= half_diagonal;
          Classification c;
          tinyMap().classify({&p, 1}, {&c, 1});
          free = free || c.state == Occupancy::kFree;
        }
      const int expected = occupied ? 0 : free ? 254 : 205;
      ASSERT_EQ(static_cast<std::uint8_t>(cells[static_cast<std::size_t>(row) * width + col]), expected)
          << "row " << row << " column " << col;
    }
  // Another up axis: the band along -z is the same slab seen from below (x, -y).
  const RunResult down = runVdmap("query " + q(f.session) +
                                  " --op grid --resolution 0.5 --band -0.9:-0.3 --up -z --out " + q(tmp / "down.yaml"));
  ASSERT_EQ(down.exit_code, 0) << down.err;
  EXPECT_NE(readFile(tmp / "down.yaml").find("up -z, grid x = world +x, grid y = world -y"), std::string::npos);
  const std::string flipped = readFile(tmp / "down.pgm");
  EXPECT_EQ(flipped.size(), pgm.size());
}

// A band beyond the map is clipped to its extent along up (a note on stderr): the grid is the one
// of that extent, at its cost; vdmap map --grid-band clips alike.
TEST(QueryCli, AHugeBandIsClippedToTheMap) {
  const Fixture& f = fixture();
  TempDir tmp;
  const RunResult huge =
      runVdmap("query " + q(f.session) + " --op grid --resolution 0.5 --band -1e30:1e30 --out " + q(tmp / "h.yaml"));
  ASSERT_EQ(huge.exit_code, 0) << huge.err;
  const std::string lead = "vdmap query: note: --band -1e+30:1e+30 clipped to the map's ";
  ASSERT_NE(huge.err.find(lead), std::string::npos) << huge.err;
  const std::string extent = huge.err.substr(huge.err.find(lead) + lead.size());
  const std::string band = extent.substr(0, extent.find(' '));
  const RunResult own =
      runVdmap("query " + q(f.session) + " --op grid --resolution 0.5 --band " + band + " --out " + q(tmp / "o.yaml"));
  ASSERT_EQ(own.exit_code, 0) << own.err;
  EXPECT_EQ(own.err.find("clipped"), std::string::npos) << own.err;
  EXPECT_EQ(readFile(tmp / "h.pgm"), readFile(tmp / "o.pgm"));
  const RunResult m = runVdmap("map " + q(f.dir / "bi") +
                               " --frames 0:3 --cell-size 16 --grid 0.5 --grid-band -1e30:1e30 --out " + q(tmp / "m"));
  ASSERT_EQ(m.exit_code, 0) << m.err;
  EXPECT_NE(m.err.find("vdmap map: note: --grid-band -1e+30:1e+30 clipped to the map's " + band), std::string::npos)
      << m.err;
  EXPECT_EQ(readFile(tmp / "m" / "grid.pgm"), readFile(tmp / "o.pgm"));
}

// vdmap map --grid writes the grid vdmap query --op grid gives of its session, into DIR.
TEST(QueryCli, MapGridIsTheQuerysGrid) {
  const Fixture& f = fixture();
  TempDir tmp;
  const RunResult m = runVdmap("map " + q(f.dir / "bi") +
                               " --frames 0:3 --cell-size 16 --grid 0.5 --grid-band 0.3:0.9 --out " + q(tmp / "m"));
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const RunResult r =
      runVdmap("query " + q(f.session) + " --op grid --resolution 0.5 --band 0.3:0.9 --out " + q(tmp / "q.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readFile(tmp / "m" / "grid.pgm"), readFile(tmp / "q.pgm"));
  EXPECT_NE(readFile(tmp / "m" / "grid.yaml").find("image: grid.pgm\n"), std::string::npos);
  const RunResult no_band = runVdmap("map " + q(f.dir / "bi") + " --grid 0.5 --out " + q(tmp / "n"));
  EXPECT_EQ(no_band.exit_code, 107) << no_band.err;
  EXPECT_FALSE(fs::exists(tmp / "n"));
}

// The .bt loads with liboctomap; at voxel centres farther than the half-diagonal from any surface
// its search says what classify says (free: a free node, unknown: no node); nearer: occupied.
TEST(QueryCli, OctomapLoadsAndAgreesWithClassify) {
  const Fixture& f = fixture();
  TempDir tmp;
  const double res = 0.25;
  const RunResult r =
      runVdmap("query " + q(f.session) + " --op octomap --resolution 0.25 --out " + q(tmp / "m.bt") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary((tmp / "m.bt").string()));
  EXPECT_EQ(tree.getResolution(), res);
  Eigen::Vector3d lo, hi;
  tinyMap().seenBounds(&lo, &hi);
  const double half_diagonal = res * std::sqrt(3.0) / 2;
  std::size_t checked[3] = {0, 0, 0};
  for (double x = lo.x(); x <= hi.x(); x += res)
    for (double y = lo.y(); y <= hi.y(); y += res)
      for (double z = lo.z(); z <= hi.z(); z += res) {
        const octomap::point3d c = tree.keyToCoord(tree.coordToKey(octomap::point3d(x, y, z)));
        const Eigen::Vector3d p(c.x(), c.y(), c.z());
        DistanceResult d;
        tinyMap().distance({&p, 1}, {&d, 1});
        Classification cls;
        tinyMap().classify({&p, 1}, {&cls, 1});
        const octomap::OcTreeNode* node = tree.search(c);
        if (d.distance_m <= half_diagonal) {
          ASSERT_TRUE(node && tree.isNodeOccupied(node)) << p.transpose();
          ++checked[2];
        } else if (cls.state == Occupancy::kFree) {
          ASSERT_TRUE(node && !tree.isNodeOccupied(node)) << p.transpose();
          ++checked[1];
        } else {
          EXPECT_EQ(node, nullptr) << p.transpose();
          ++checked[0];
        }
      }
  EXPECT_GT(checked[0], 0u);
  EXPECT_GT(checked[1], 0u);
  EXPECT_GT(checked[2], 0u);
  EXPECT_GT(summary["leaves"].get<std::size_t>(), 0u);
}

// Corrected keyframe poses (TUM, by timestamp) move the answers: what the CLI answers is the
// library's map at those poses, and it differs from the map at the saved poses.
TEST(QueryCli, KeyframePosesMoveTheAnswers) {
  const Fixture& f = fixture();
  TempDir tmp;
  std::string moved;
  for (const std::string& line : lines(readFile(f.keyframes))) {
    if (line.empty() || line[0] == '#') continue;
    double t, x, y, z, qx, qy, qz, qw;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf %lf %lf %lf %lf %lf %lf %lf", &t, &x, &y, &z, &qx, &qy, &qz, &qw), 8);
    char text[256];
    std::snprintf(text, sizeof text, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", t, x + 0.3, y, z, qx, qy, qz, qw);
    moved += text;
  }
  writeText(tmp / "poses.txt", moved);
  const std::vector<Eigen::Vector3d> points = testPoints();
  writePointsTxt(tmp / "p.txt", points);
  const app::QueryInput input = app::readQueryInput(tmp / "p.txt", QueryOp::kDistance, 8.0);
  const QueryMap moved_map = libraryMap(f.session, tmp / "poses.txt");
  for (const QueryOp op : {QueryOp::kClassify, QueryOp::kDistance}) {
    const std::string name = app::queryOpName(op);
    const RunResult r =
        runVdmap("query " + q(f.session) + " --op " + name + " --keyframe-poses " + q(tmp / "poses.txt") +
                 " --points " + q(tmp / "p.txt") + " --out " + q(tmp / "moved.txt"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string answers = readFile(tmp / "moved.txt");
    EXPECT_EQ(answers, app::queryAnswersText(op, input, libraryAnswers(moved_map, op, input))) << name;
    EXPECT_NE(answers, app::queryAnswersText(op, input, libraryAnswers(tinyMap(), op, input))) << name;
  }
  // Rays from the first keyframe's corrected centre hit what the unmoved map hits 0.3 m to the left.
  std::vector<Ray> rays(1), shifted(1);
  rays[0].origin_W = Eigen::Vector3d(1.2 + 0.3, 0, 1.35);
  rays[0].direction_W = Eigen::Vector3d(-1, 0.1, -0.2);
  shifted[0] = rays[0];
  shifted[0].origin_W.x() -= 0.3;
  std::vector<RayHit> a(1), b(1);
  moved_map.castRays(rays, a);
  tinyMap().castRays(shifted, b);
  ASSERT_TRUE(a[0].hit && b[0].hit);
  EXPECT_NEAR(a[0].t_m, b[0].t_m, 0.05);
}

// A session without keyframes: every point unknown, no surface, rays miss, bodies touch unknown.
TEST(QueryCli, AnEmptyMapAnswersUnknown) {
  TempDir tmp;
  const PinholeCamera camera{160, 120, 131.25, 131.25, 79.5, 59.5, 5000.0};
  const Mapper mapper(camera, MapperParams{});
  saveSession(tmp / "empty.vdmap", mapper.graph(), sessionInfo(mapper, {}));
  writeText(tmp / "p.txt", "0 0 0\n1 2 3\n");
  writeText(tmp / "s.txt", "0 0 0 0.1 0\n1 2 3 0.2 1\n");
  writeText(tmp / "r.txt", "0 0 0 0 0 1\n");
  const auto run = [&](const std::string& op, const std::string& points) {
    const RunResult r = runVdmap("query " + q(tmp / "empty.vdmap") + " --op " + op + " --points " + q(tmp / points) +
                                 " --out " + q(tmp / "o.txt"));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return readFile(tmp / "o.txt");
  };
  EXPECT_EQ(run("classify", "p.txt"), "unknown 0.5 -1 -1\nunknown 0.5 -1 -1\n");
  // No output holds a non-finite value: "no surface" is the largest float.
  EXPECT_EQ(run("distance", "p.txt"), "3.40282347e+38 0 0 0\n3.40282347e+38 0 0 0\n");
  EXPECT_EQ(run("ray", "r.txt"), "miss\n");
  EXPECT_EQ(run("collide", "s.txt"), "0 0 1 3.40282347e+38 -1\n1 0 1 3.40282347e+38 -1\n");
  const RunResult grid =
      runVdmap("query " + q(tmp / "empty.vdmap") + " --op grid --band 0:1 --out " + q(tmp / "g.yaml"));
  EXPECT_EQ(grid.exit_code, 1);
  EXPECT_NE(grid.err.find("the map sees nothing"), std::string::npos) << grid.err;
  EXPECT_FALSE(fs::exists(tmp / "g.yaml"));
  EXPECT_FALSE(fs::exists(tmp / "g.pgm"));
}

TEST(QueryCli, AMapFolderIsNotASession) {
  const Fixture& f = fixture();
  TempDir tmp;
  writeText(tmp / "p.txt", "0 0 0\n");
  const RunResult r = runVdmap("query " + q(f.dir / "m") + " --op classify --points " + q(tmp / "p.txt") + " --out " +
                               q(tmp / "o.txt"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("not a session: vdmap query reads a session file"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace vdmap::test
