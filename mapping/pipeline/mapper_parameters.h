#pragma once
// The Mapper's parameters as rows of the parameter table (mapping/core/parameter.h): the re-run
// ones, which shape the keyframes and local maps (docs/parameters.md).
#include <span>

#include "mapping/core/parameter.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap {

/// Every user-set field of MapperParams but the pose source (the input's, --poses): the ones
/// with a slider first, in the workbench's order, then the advanced ones.
std::span<const ParameterRow<MapperParams>> mapperParameters();

}  // namespace vdmap
