#pragma once
// The global map's parameters as rows of the parameter table (mapping/core/parameter.h): the live
// ones, which shape only the global map built from the local maps (docs/parameters.md).
#include <span>

#include "mapping/core/parameter.h"
#include "mapping/global_map/global_map.h"

namespace vdmap {

/// Every user-set field of GlobalMapParams (all but threads), in the workbench's order.
std::span<const ParameterRow<GlobalMapParams>> globalMapParameters();

}  // namespace vdmap
