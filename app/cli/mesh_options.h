#pragma once
// The surface mesh's options (docs/method.md 14), registered once for every verb that meshes:
// `vdmap mesh`, `vdmap map --mesh` and `vdmap render --layers mesh`.
#include <cstddef>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "mapping/mesh/surface_mesh.h"

namespace vdmap::app {

/// The options' ranges (the settings file's mesh keys take the same).
inline constexpr double kMeshMaxSlopeDeg = 89.9, kMeshMaxEdgeSigma = 100.0;
inline constexpr int kMeshMaxStride = 16;

/// The mesh options as given; unset: not given, `base` (the defaults, or settings under them) stands.
struct MeshOptions {
  std::optional<double> max_slope_deg, edge_sigma;
  std::optional<int> stride;
  bool no_fuse = false;
  std::optional<std::size_t> max_triangles;
  /// `base` with the options given over it.
  MeshParams over(MeshParams base) const;
};

/// The options that give `params` over the defaults (" --mesh-stride 3 --mesh-no-fuse"; "" for the
/// defaults), as a printed command spells them. The sensor model and threads are no options.
std::string meshFlags(const MeshParams& params);

/// Registers --mesh-max-slope, --mesh-edge-sigma, --mesh-stride, --mesh-no-fuse and --max-triangles
/// on `verb`, writing into `options` (which must outlive the parse); ranges are checked while parsing.
void addMeshOptions(CLI::App& verb, MeshOptions& options);

}  // namespace vdmap::app
