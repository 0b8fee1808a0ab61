#pragma once
// A triangle mesh of the surfaces the local maps saw (docs/method.md 14): each keyframe's kept cells
// meshed as the 2.5-D surface they are over its image plane, depth edges left open, and the pieces
// fused by keeping, where keyframes saw the same surface, the triangles of the keyframe that measured it
// most densely.
#include <cstddef>
#include <vector>

#include "mapping/files/ply_reader.h"
#include "mapping/global_map/global_map.h"
#include "mapping/keyframe/keyframe_graph.h"

namespace vdmap {

/// The mesh's parameters (docs/parameters.md: `vdmap mesh`'s options).
struct MeshParams {
  /// Neighbouring cells are joined when their depths differ by at most tan(max_slope_deg) times their
  /// lateral distance plus edge_sigma times the sensor's depth noise: a surface turned further from
  /// the camera than this, or a depth step, is left open.
  double max_slope_deg = 60.0;
  double edge_sigma = 3.0;
  /// Vertices sit on a grid of stride x stride cells: each is the count-weighted mean of the kept cells
  /// there (those joined with the one of median depth). 1: one vertex per cell (docs/method.md 14: on
  /// Replica half the 95th percentile of the error of 2, and more of steep surfaces and edges).
  int stride = 1;
  /// Sensor model whose depth noise the gates use (the global map's filter's).
  SensorModel model = SensorModel::kNguyen2012;
  /// Fuse the keyframes' pieces (drop a block that keyframes with denser measured points cover); false keeps
  /// every piece.
  bool fuse = true;
  /// A mesh estimated larger than this (triangles) is refused before any work (meshEstimate).
  std::size_t max_triangles = 30'000'000;
  int threads = 0;  ///< 0: all cores. The mesh does not depend on it.
  /// Throws std::invalid_argument naming the first value out of range.
  void validate() const;
  bool operator==(const MeshParams&) const = default;
};

/// The mesh's figures.
struct MeshStats {
  std::size_t keyframes = 0;          ///< keyframes with a piece
  std::size_t piece_triangles = 0;    ///< triangles of all pieces before fusion
  std::size_t covered_triangles = 0;  ///< dropped because keyframes with denser points cover them
  double ms = 0;                      ///< wall time
};

/// About this many triangles come out of `kept` at `stride`: two per vertex position holding a kept
/// cell (what a full grid gives, less its border). What the size limit compares; counting is all it
/// does. `kept` must fit the graph (as buildSurfaceMesh checks).
std::size_t meshEstimate(const KeyframeGraph& graph, const std::vector<std::vector<bool>>& kept, int stride);

/// The mesh of `graph`'s local maps at the keyframes' current poses, with the cells `kept` keeps
/// (GlobalMap::kept, or keptCells per keyframe): world frame, metres; a colour and a unit normal per
/// vertex (pointing to the keyframe that saw it). Deterministic: the same for any thread count.
/// Throws std::invalid_argument when kept does not fit the graph, std::length_error (its message gives
/// the estimate) when meshEstimate is above params.max_triangles, before any work. An empty map gives an
/// empty mesh.
ColoredTriangleMesh buildSurfaceMesh(const KeyframeGraph& graph, const std::vector<std::vector<bool>>& kept,
                                     const MeshParams& params, MeshStats* stats = nullptr);

/// buildSurfaceMesh with the cells `global` keeps and its filter's sensor model.
ColoredTriangleMesh buildSurfaceMesh(const KeyframeGraph& graph, const GlobalMap& global, MeshParams params,
                                     const GlobalMapParams& global_params, MeshStats* stats = nullptr);

}  // namespace vdmap
