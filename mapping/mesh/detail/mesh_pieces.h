#pragma once
// The mesh's passes (surface_mesh.cpp), exposed for tests: one keyframe's piece, the cover test and
// the mesh with or without the frustum pruning of the cover test's candidates.
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "mapping/mesh/surface_mesh.h"

namespace vdmap::mesh_detail {

/// The square between the centres of 2 x 2 neighbouring cells, with its one or two triangles.
struct Block {
  std::int32_t index = -1;  ///< row * Piece::cols + col; the block of cells (row, col) .. (row + 1, col + 1)
  int count = 0;            ///< triangles
  std::array<std::array<std::int32_t, 3>, 2> triangles{};  ///< Piece::points indices, front facing the keyframe
  double z_min = std::numeric_limits<double>::infinity(), z_max = -std::numeric_limits<double>::infinity();
  /// The spacing of the measured points on the block's surface (m): sqrt(its area / the points per
  /// corner). Smaller is better supported.
  double spacing = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< keyframe frame
  int corner_count = 0;                                ///< corners the triangles use
  std::array<std::int32_t, 4> corners{};               ///< their Piece::points indices
};

/// One keyframe's mesh in its own frame.
struct Piece {
  int cols = 0, rows = 0;               ///< blocks per row and column: the vertex grid's minus one
  int block_px = 0;                     ///< container pixels between neighbouring vertex positions (cell size x stride)
  std::vector<Eigen::Vector3d> points;  ///< per vertex position, its kept cells' mean (keyframe frame)
  std::vector<Eigen::Vector3f> colors;
  std::vector<double> support;              ///< per vertex position, the points of its cells (the count weights' sum)
  std::vector<Block> blocks;                ///< in block order
  std::vector<std::int32_t> block_of;       ///< per block index: its place in blocks, or -1
  Transform T_K_W = Transform::Identity();  ///< the keyframe's current pose, inverted (the cover test's)
};

Piece buildPiece(const Keyframe& keyframe, const std::vector<bool>& kept, const MeshParams& params);

/// Whether `other` (keyframe `other_kf`, other.T_K_W its pose) has, where world point p_W falls in its container, a block on
/// the same surface (its depth range widened by the depth noise) with a smaller point spacing than `spacing`
/// (ties: the lower keyframe id than `self` wins).
bool covers(const Piece& other, const Keyframe& other_kf, const Eigen::Vector3d& p_W, double spacing, int self,
            const MeshParams& params);

/// buildSurfaceMesh; prune = false tries every keyframe in the cover test (the reference).
ColoredTriangleMesh buildMesh(const KeyframeGraph& graph, const std::vector<std::vector<bool>>& kept,
                              const MeshParams& params, MeshStats* stats, bool prune);

}  // namespace vdmap::mesh_detail
