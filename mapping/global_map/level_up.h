#pragma once
// The up direction of a map from its geometry alone, for maps without cameras (a map PLY, an
// OctoMap): rooms are built of level floors, tables and counters and of upright walls.
#include <optional>
#include <span>
#include <string>

#include <Eigen/Core>

#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap {

/// What levelUp found: the up direction (world frame, unit) and the room's three plane
/// directions it was chosen from, with the share of flat patches each holds.
struct LevelUp {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  ///< columns: the plane normals, most patches first
  Eigen::Vector3d share = Eigen::Vector3d::Zero();     ///< of the flat patches, along each column
  int up_column = 2;                                   ///< the column `up` lies along
  std::size_t patches = 0;                             ///< flat patches found
};

/// The up direction of `map` from its flat patches (docs/workbench.md "Up axis"): the normals of
/// locally flat neighbourhoods of the ellipsoid means (PCA within 12 cm) give the room's three
/// perpendicular plane directions (the most common normal, then the most common one at right
/// angles to it); of these, up is the one whose planes lie lowest in the map (floors, tables
/// and counters below the middle of the map's height, walls spread across it), pointing from
/// them into the map. Deterministic; nullopt when fewer than 30 flat patches are found.
std::optional<LevelUp> levelUp(std::span<const Ellipsoid> map);

}  // namespace vdmap
