// docs/method.md 14. Three passes, each a parallelFor over keyframes writing only its own slot:
// 1. piece: a keyframe's kept cells joined into triangles block by block (a block is the square between
//    the centres of 2 x 2 neighbouring cells), in the keyframe frame; pose-independent.
// 2. cover: every block of every piece against the keyframes whose container may see it (a frustum test
//    on the piece's bounding box); a block is dropped when its centre and its corners each lie on a
//    block of another keyframe, on the same surface, with denser measured points.
// 3. output: the surviving blocks' triangles in the world frame, keyframes in id order.
#include "mapping/mesh/surface_mesh.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "mapping/core/parallel.h"
#include "mapping/mesh/detail/mesh_pieces.h"

namespace vdmap {

void MeshParams::validate() const {
  if (!(max_slope_deg >= 0.0 && max_slope_deg < 90.0))
    throw std::invalid_argument("mesh max slope must be in [0, 90) degrees, got " + std::to_string(max_slope_deg));
  if (!(edge_sigma >= 0.0 && edge_sigma <= 100.0))
    throw std::invalid_argument("mesh edge sigma must be in [0, 100], got " + std::to_string(edge_sigma));
  if (stride < 1 || stride > 16)
    throw std::invalid_argument("mesh stride must be in 1..16, got " + std::to_string(stride));
  if (max_triangles < 1) throw std::invalid_argument("the mesh's triangle limit must be at least 1");
  if (threads < 0 || threads > kMaxThreads)
    throw std::invalid_argument("threads must be in 0.." + std::to_string(kMaxThreads));
}

std::size_t meshEstimate(const KeyframeGraph& graph, const std::vector<std::vector<bool>>& kept, int stride) {
  std::size_t positions = 0;
  for (std::size_t k = 0; k < kept.size() && k < graph.size(); ++k) {
    const KeyframeContainer& c = graph.keyframe(static_cast<int>(k)).container;
    const int grid_cols = (c.cols() + stride - 1) / stride;
    std::vector<bool> seen(static_cast<std::size_t>(grid_cols) * ((c.rows() + stride - 1) / stride), false);
    for (std::size_t i = 0; i < c.size() && i < kept[k].size(); ++i) {
      if (!kept[k][i]) continue;
      const int g = c.cells()[i].grid_index;
      const std::size_t at = static_cast<std::size_t>(g / c.cols() / stride) * grid_cols + (g % c.cols()) / stride;
      positions += seen[at] ? 0 : 1;
      seen[at] = true;
    }
  }
  return 2 * positions;
}

namespace mesh_detail {
namespace {

bool usedBy(const Block& block, std::int32_t vertex) {
  for (int t = 0; t < block.count; ++t)
    for (std::int32_t x : block.triangles[static_cast<std::size_t>(t)])
      if (x == vertex) return true;
  return false;
}

constexpr double kAverageSlope = 1.0;  // tan(45 degrees)

double depthSd(SensorModel model, double z) { return std::sqrt(pixelVariance(model, z).depth_m2); }

// docs/method.md 14: two cells join when their depths differ by at most tan(slope) times their lateral
// distance plus k times the depth noise of both.
bool joined(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double tan_slope, const MeshParams& params) {
  const double lateral = (p.head<2>() / p.z() - q.head<2>() / q.z()).norm() * std::min(p.z(), q.z());
  const double sp = depthSd(params.model, p.z()), sq = depthSd(params.model, q.z());
  return std::abs(p.z() - q.z()) <= tan_slope * lateral + params.edge_sigma * std::sqrt(sp * sp + sq * sq);
}

}  // namespace

Piece buildPiece(const Keyframe& keyframe, const std::vector<bool>& kept, const MeshParams& params) {
  const KeyframeContainer& c = keyframe.container;
  const int S = params.stride;
  const int grid_cols = (c.cols() + S - 1) / S, grid_rows = (c.rows() + S - 1) / S;
  Piece piece;
  piece.cols = grid_cols - 1;
  piece.rows = grid_rows - 1;
  piece.block_px = c.cellSizePx() * S;
  if (piece.cols <= 0 || piece.rows <= 0) return piece;
  const double tan_slope = std::tan(params.max_slope_deg * M_PI / 180.0);
  // The kept cells with a finite mean in front of the camera, by vertex-grid position (S x S cells).
  std::vector<std::vector<const StoredCell*>> members(static_cast<std::size_t>(grid_cols) * grid_rows);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const StoredCell& cell = c.cells()[i];
    if (!kept[i] || !cell.mean.allFinite() || !(cell.mean.z() > 0.0f)) continue;
    const int row = cell.grid_index / c.cols(), col = cell.grid_index % c.cols();
    members[static_cast<std::size_t>(row / S) * grid_cols + col / S].push_back(&cell);
  }
  // One vertex per position: the count-weighted mean of the cells joined with the one of median depth
  // at a slope of at most 45 degrees (a position straddling a depth step or a steep surface keeps the
  // median's side: an average across it would float off both).
  std::vector<std::int32_t> slot(members.size(), -1);
  for (std::size_t g = 0; g < members.size(); ++g) {
    std::vector<const StoredCell*>& m = members[g];
    if (m.empty()) continue;
    std::sort(m.begin(), m.end(), [](const StoredCell* a, const StoredCell* b) {
      return a->mean.z() < b->mean.z() || (a->mean.z() == b->mean.z() && a->grid_index < b->grid_index);
    });
    const Eigen::Vector3d median = m[(m.size() - 1) / 2]->mean.cast<double>();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), color = Eigen::Vector3d::Zero();
    double n = 0;
    for (const StoredCell* cell : m)
      if (joined(median, cell->mean.cast<double>(), kAverageSlope, params)) {
        sum += cell->n * cell->mean.cast<double>();
        color += cell->n * cell->color.cast<double>();
        n += cell->n;
      }
    slot[g] = static_cast<std::int32_t>(piece.points.size());
    piece.support.push_back(n);
    piece.points.push_back(sum / n);
    piece.colors.push_back((color / n).cast<float>());
  }
  if (piece.points.empty()) return piece;
  piece.block_of.assign(static_cast<std::size_t>(piece.cols) * piece.rows, -1);
  for (int r = 0; r < piece.rows; ++r)
    for (int col = 0; col < piece.cols; ++col) {
      const std::size_t g = static_cast<std::size_t>(r) * grid_cols + col;
      // Corners 0 1 / 2 3 (row-major); diagonal 0-3 gives (0 2 3) (0 3 1), diagonal 1-2 (0 2 1) (1 2 3).
      const std::array<std::int32_t, 4> v = {slot[g], slot[g + 1], slot[g + grid_cols], slot[g + grid_cols + 1]};
      if (std::count(v.begin(), v.end(), -1) > 1) continue;
      auto ok = [&](int a, int b) { return joined(piece.points[v[a]], piece.points[v[b]], tan_slope, params); };
      auto valid = [&](int a, int b, int d) {
        return v[a] >= 0 && v[b] >= 0 && v[d] >= 0 && ok(a, b) && ok(b, d) && ok(a, d);
      };
      const std::array<std::array<int, 3>, 4> tris = {{{0, 2, 3}, {0, 3, 1}, {0, 2, 1}, {1, 2, 3}}};
      std::array<bool, 4> good;
      for (int t = 0; t < 4; ++t) good[t] = valid(tris[t][0], tris[t][1], tris[t][2]);
      const int count03 = good[0] + good[1], count12 = good[2] + good[3];
      auto length = [&](int a, int b) {
        return v[a] >= 0 && v[b] >= 0 ? (piece.points[v[a]] - piece.points[v[b]]).norm()
                                      : std::numeric_limits<double>::infinity();
      };
      const bool use12 = count12 > count03 || (count12 == count03 && length(1, 2) < length(0, 3));
      Block block;
      block.index = static_cast<std::int32_t>(static_cast<std::size_t>(r) * piece.cols + col);
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      double area = 0;
      for (int t = use12 ? 2 : 0; t < (use12 ? 4 : 2); ++t) {
        if (!good[t]) continue;
        std::array<std::int32_t, 3> tri = {v[tris[t][0]], v[tris[t][1]], v[tris[t][2]]};
        const Eigen::Vector3d &a = piece.points[tri[0]], &b = piece.points[tri[1]], &d = piece.points[tri[2]];
        const Eigen::Vector3d n = (b - a).cross(d - a);
        if (!(n.norm() > 0.0)) continue;
        if (n.dot(a + b + d) > 0.0) std::swap(tri[1], tri[2]);  // the front faces the keyframe
        centroid += (a + b + d) / 3.0;
        area += 0.5 * n.norm();
        block.z_min = std::min({block.z_min, a.z(), b.z(), d.z()});
        block.z_max = std::max({block.z_max, a.z(), b.z(), d.z()});
        block.triangles[static_cast<std::size_t>(block.count++)] = tri;
      }
      if (block.count == 0) continue;
      block.centroid = centroid / block.count;
      // The points behind the block: its corners' (each vertex stands for one block's area of cells).
      double points = 0;
      for (std::int32_t corner : v)
        if (corner >= 0 && usedBy(block, corner)) {
          points += piece.support[static_cast<std::size_t>(corner)];
          block.corners[static_cast<std::size_t>(block.corner_count++)] = corner;
        }
      // docs/method.md 14: the spacing of the measured points on the block's surface. A keyframe nearer the
      // surface, one that holds more frames of it and one that sees it less obliquely all measured it densely.
      const double block_area = block.count == 2 ? area : 2.0 * area;
      block.spacing = std::sqrt(block_area * block.corner_count / points);
      piece.block_of[static_cast<std::size_t>(block.index)] = static_cast<std::int32_t>(piece.blocks.size());
      piece.blocks.push_back(block);
    }
  return piece;
}

bool covers(const Piece& other, const Keyframe& other_kf, const Eigen::Vector3d& p_W, double spacing, int self,
            const MeshParams& params) {
  const Eigen::Vector3d q = other.T_K_W * p_W;
  if (!(q.z() > 0.0) || other.blocks.empty()) return false;
  const KeyframeContainer& c = other_kf.container;
  const Eigen::Vector2d uv = c.camera().project(q);
  const double s = other.block_px, half = 0.5 * (s - 1.0);
  const double bu = std::floor((uv.x() + c.offsetU() - half) / s), bv = std::floor((uv.y() + c.offsetV() - half) / s);
  if (!(bu >= 0.0 && bv >= 0.0 && bu < other.cols && bv < other.rows)) return false;
  const std::int32_t b = other.block_of[static_cast<std::size_t>(bv) * other.cols + static_cast<std::size_t>(bu)];
  if (b < 0) return false;
  const Block& block = other.blocks[static_cast<std::size_t>(b)];
  const double tol = params.edge_sigma * std::sqrt(2.0) * depthSd(params.model, q.z());
  if (q.z() < block.z_min - tol || q.z() > block.z_max + tol) return false;
  return block.spacing < spacing || (block.spacing == spacing && other_kf.id < self);
}

// Whether keyframe `other`'s container may see any point of the box [lo, hi] (world): false only when
// all eight corners lie behind its camera or beyond one side plane of its container's pyramid.
bool maySee(const Keyframe& other, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const KeyframeContainer& c = other.container;
  const PinholeCamera& cam = c.camera();
  // Container edges in keyframe pixels, as rays' x/z and y/z.
  const double u0 = (-c.offsetU() - 0.5 - cam.cx) / cam.fx,
               u1 = (2.0 * cam.width - c.offsetU() - 0.5 - cam.cx) / cam.fx;
  const double v0 = (-c.offsetV() - 0.5 - cam.cy) / cam.fy,
               v1 = (2.0 * cam.height - c.offsetV() - 0.5 - cam.cy) / cam.fy;
  std::array<bool, 5> all_out;
  all_out.fill(true);
  const Transform T_K_W = other.T_W_K.inverse();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p_W((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                              (corner & 4) ? hi.z() : lo.z());
    const Eigen::Vector3d q = T_K_W * p_W;
    all_out[0] = all_out[0] && q.z() <= 0.0;
    all_out[1] = all_out[1] && q.x() < u0 * q.z();
    all_out[2] = all_out[2] && q.x() > u1 * q.z();
    all_out[3] = all_out[3] && q.y() < v0 * q.z();
    all_out[4] = all_out[4] && q.y() > v1 * q.z();
  }
  return std::none_of(all_out.begin(), all_out.end(), [](bool b) { return b; });
}

std::vector<std::vector<bool>> coveredBlocks(const KeyframeGraph& graph, const std::vector<Piece>& pieces,
                                             const MeshParams& params, bool prune) {
  const std::size_t n = pieces.size();
  std::vector<std::vector<bool>> covered(n);
  parallelFor(params.threads, n, [&](std::size_t a) {
    const Piece& piece = pieces[a];
    covered[a].assign(piece.blocks.size(), false);
    if (piece.blocks.empty() || !params.fuse) return;
    const Keyframe& kf = graph.keyframe(static_cast<int>(a));
    std::vector<int> candidates;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Block& b : piece.blocks) {
      const Eigen::Vector3d p = kf.T_W_K * b.centroid;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    for (std::size_t o = 0; o < n; ++o)
      if (o != a && !pieces[o].blocks.empty() && (!prune || maySee(graph.keyframe(static_cast<int>(o)), lo, hi)))
        candidates.push_back(static_cast<int>(o));
    // The keyframe that covered the last point is asked first (neighbouring blocks are mostly covered
    // by the same one); the answer does not depend on the order.
    std::size_t last = 0;
    auto coveredAt = [&](const Eigen::Vector3d& p_K, double spacing) {
      const Eigen::Vector3d p_W = kf.T_W_K * p_K;
      for (std::size_t j = 0; j < candidates.size(); ++j) {
        const std::size_t at = (last + j) % candidates.size();
        const int o = candidates[at];
        if (covers(pieces[static_cast<std::size_t>(o)], graph.keyframe(o), p_W, spacing, static_cast<int>(a), params)) {
          last = at;
          return true;
        }
      }
      return false;
    };
    // A block is dropped only when its centre and all its corners are covered (by any keyframes): a
    // block covered at its centre alone, where the denser piece ends inside it, would leave a gap.
    for (std::size_t i = 0; i < piece.blocks.size(); ++i) {
      const Block& b = piece.blocks[i];
      bool all = coveredAt(b.centroid, b.spacing);
      for (int j = 0; j < b.corner_count && all; ++j)
        all = coveredAt(piece.points[static_cast<std::size_t>(b.corners[static_cast<std::size_t>(j)])], b.spacing);
      covered[a][i] = all;
    }
  });
  return covered;
}

ColoredTriangleMesh assembleMesh(const KeyframeGraph& graph, const std::vector<Piece>& pieces,
                                 const std::vector<std::vector<bool>>& covered, int threads) {
  const std::size_t n = pieces.size();
  // Per piece: which points the surviving triangles use, and their new numbers.
  std::vector<std::vector<std::int32_t>> renumber(n);
  std::vector<std::size_t> vertex_count(n, 0), triangle_count(n, 0);
  parallelFor(threads, n, [&](std::size_t k) {
    renumber[k].assign(pieces[k].points.size(), -1);
    for (std::size_t i = 0; i < pieces[k].blocks.size(); ++i) {
      if (covered[k][i]) continue;
      const Block& b = pieces[k].blocks[i];
      triangle_count[k] += static_cast<std::size_t>(b.count);
      for (int t = 0; t < b.count; ++t)
        for (std::int32_t v : b.triangles[static_cast<std::size_t>(t)]) renumber[k][static_cast<std::size_t>(v)] = 0;
    }
    std::int32_t next = 0;
    for (std::int32_t& r : renumber[k])
      if (r == 0) r = next++;
    vertex_count[k] = static_cast<std::size_t>(next);
  });
  std::vector<std::size_t> vertex_base(n + 1, 0), triangle_base(n + 1, 0);
  std::partial_sum(vertex_count.begin(), vertex_count.end(), vertex_base.begin() + 1);
  std::partial_sum(triangle_count.begin(), triangle_count.end(), triangle_base.begin() + 1);
  ColoredTriangleMesh mesh;
  mesh.positions.resize(vertex_base[n]);
  mesh.normals.resize(vertex_base[n]);
  mesh.colors.resize(vertex_base[n]);
  mesh.triangles.resize(triangle_base[n]);
  parallelFor(threads, n, [&](std::size_t k) {
    const Piece& piece = pieces[k];
    const Transform& T_W_K = graph.keyframe(static_cast<int>(k)).T_W_K;
    // Normals: area-weighted face normals over the whole piece (covered blocks too, so a cut does not
    // bend them), facing the keyframe.
    std::vector<Eigen::Vector3d> normal(piece.points.size(), Eigen::Vector3d::Zero());
    for (const Block& b : piece.blocks)
      for (int t = 0; t < b.count; ++t) {
        const auto& tri = b.triangles[static_cast<std::size_t>(t)];
        const Eigen::Vector3d face =
            (piece.points[tri[1]] - piece.points[tri[0]]).cross(piece.points[tri[2]] - piece.points[tri[0]]);
        for (std::int32_t v : tri) normal[static_cast<std::size_t>(v)] += face;
      }
    for (std::size_t i = 0; i < piece.points.size(); ++i) {
      const std::int32_t r = renumber[k][i];
      if (r < 0) continue;
      const std::size_t out = vertex_base[k] + static_cast<std::size_t>(r);
      mesh.positions[out] = (T_W_K * piece.points[i]).cast<float>();
      const double len = normal[i].norm();
      const Eigen::Vector3d n_K =
          len > 0.0 ? Eigen::Vector3d(normal[i] / len) : Eigen::Vector3d(-piece.points[i].normalized());
      mesh.normals[out] = (T_W_K.linear() * n_K).cast<float>();
      for (int ch = 0; ch < 3; ++ch)
        mesh.colors[out][static_cast<std::size_t>(ch)] =
            static_cast<std::uint8_t>(std::clamp(std::lround(piece.colors[i](ch)), 0L, 255L));
    }
    std::size_t t_out = triangle_base[k];
    for (std::size_t i = 0; i < piece.blocks.size(); ++i) {
      if (covered[k][i]) continue;
      const Block& b = piece.blocks[i];
      for (int t = 0; t < b.count; ++t) {
        std::array<std::uint32_t, 3>& tri = mesh.triangles[t_out++];
        for (int j = 0; j < 3; ++j)
          tri[static_cast<std::size_t>(j)] = static_cast<std::uint32_t>(
              vertex_base[k] + static_cast<std::size_t>(
                                   renumber[k][static_cast<std::size_t>(b.triangles[static_cast<std::size_t>(t)][j])]));
      }
    }
  });
  return mesh;
}

ColoredTriangleMesh buildMesh(const KeyframeGraph& graph, const std::vector<std::vector<bool>>& kept,
                              const MeshParams& params, MeshStats* stats, bool prune) {
  params.validate();
  if (kept.size() != graph.size()) throw std::invalid_argument("buildSurfaceMesh: kept does not fit the graph");
  for (std::size_t k = 0; k < kept.size(); ++k)
    if (kept[k].size() != graph.keyframe(static_cast<int>(k)).container.size())
      throw std::invalid_argument("buildSurfaceMesh: kept does not fit keyframe " + std::to_string(k));
  const std::size_t estimate = meshEstimate(graph, kept, params.stride);
  if (estimate > params.max_triangles)
    throw std::length_error("the mesh would have up to " + std::to_string(estimate) +
                            " triangles, above the limit of " + std::to_string(params.max_triangles));
  const auto start = std::chrono::steady_clock::now();
  std::vector<Piece> pieces(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t k) {
    pieces[k] = buildPiece(graph.keyframe(static_cast<int>(k)), kept[k], params);
    pieces[k].T_K_W = graph.keyframe(static_cast<int>(k)).T_W_K.inverse();
  });
  const std::vector<std::vector<bool>> covered = coveredBlocks(graph, pieces, params, prune);
  ColoredTriangleMesh mesh = assembleMesh(graph, pieces, covered, params.threads);
  if (stats) {
    *stats = {};
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      stats->keyframes += pieces[k].blocks.empty() ? 0 : 1;
      for (std::size_t i = 0; i < pieces[k].blocks.size(); ++i) {
        stats->piece_triangles += static_cast<std::size_t>(pieces[k].blocks[i].count);
        if (covered[k][i]) stats->covered_triangles += static_cast<std::size_t>(pieces[k].blocks[i].count);
      }
    }
    stats->ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  return mesh;
}

}  // namespace mesh_detail

ColoredTriangleMesh buildSurfaceMesh(const KeyframeGraph& graph, const std::vector<std::vector<bool>>& kept,
                                     const MeshParams& params, MeshStats* stats) {
  return mesh_detail::buildMesh(graph, kept, params, stats, true);
}

ColoredTriangleMesh buildSurfaceMesh(const KeyframeGraph& graph, const GlobalMap& global, MeshParams params,
                                     const GlobalMapParams& global_params, MeshStats* stats) {
  params.model = global_params.filter.model;
  return buildSurfaceMesh(graph, global.kept, params, stats);
}

}  // namespace vdmap
