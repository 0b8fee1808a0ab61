#include "app/cli/mesh_options.h"

#include <string>

namespace vdmap::app {

MeshParams MeshOptions::over(MeshParams base) const {
  base.max_slope_deg = max_slope_deg.value_or(base.max_slope_deg);
  base.edge_sigma = edge_sigma.value_or(base.edge_sigma);
  base.stride = stride.value_or(base.stride);
  base.fuse = base.fuse && !no_fuse;
  base.max_triangles = max_triangles.value_or(base.max_triangles);
  return base;
}

std::string meshFlags(const MeshParams& params) {
  const MeshParams d;
  std::string flags;
  if (params.max_slope_deg != d.max_slope_deg)
    flags += " --mesh-max-slope " + CLI::detail::to_string(params.max_slope_deg);
  if (params.edge_sigma != d.edge_sigma) flags += " --mesh-edge-sigma " + CLI::detail::to_string(params.edge_sigma);
  if (params.stride != d.stride) flags += " --mesh-stride " + std::to_string(params.stride);
  if (!params.fuse) flags += " --mesh-no-fuse";
  if (params.max_triangles != d.max_triangles) flags += " --max-triangles " + std::to_string(params.max_triangles);
  return flags;
}

void addMeshOptions(CLI::App& verb, MeshOptions& options) {
  const MeshParams defaults;
  verb.add_option("--mesh-max-slope", options.max_slope_deg,
                  "degrees: neighbouring cells are joined while the surface between them is turned at most this "
                  "far from the camera (plus the depth noise); steeper, and depth steps, stay open")
      ->check(CLI::Range(0.0, kMeshMaxSlopeDeg))
      ->default_str(CLI::detail::to_string(defaults.max_slope_deg));
  verb.add_option("--mesh-edge-sigma", options.edge_sigma,
                  "the depth noise (in sensor-model standard deviations) a join and the fusion allow")
      ->check(CLI::Range(0.0, kMeshMaxEdgeSigma))
      ->default_str(CLI::detail::to_string(defaults.edge_sigma));
  verb.add_option("--mesh-stride", options.stride,
                  "vertices on a grid of this many cells each way, each the mean of its kept cells (1: one per cell)")
      ->check(CLI::Range(1, kMeshMaxStride))
      ->default_str(CLI::detail::to_string(defaults.stride));
  verb.add_flag("--mesh-no-fuse", options.no_fuse, "keep every keyframe's piece whole (overlapping copies stay)");
  verb.add_option("--max-triangles", options.max_triangles,
                  "refuse, before any work, a mesh estimated above this many triangles")
      ->check(CLI::Range(std::size_t{1}, std::size_t{2'000'000'000}))
      ->default_str(CLI::detail::to_string(defaults.max_triangles));
}

}  // namespace vdmap::app
