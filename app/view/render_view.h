#pragma once
// `vdmap render`'s view flags (also a suite view's keys) and the view they resolve to, with the
// settings and view files under them. What is drawn is a RenderSource (render_source.h).
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/cli/mesh_options.h"
#include "app/view/settings.h"
#include "mapping/global_map/global_map.h"
#include "render/view_spec.h"

namespace vdmap::app {

/// The view flags of `vdmap render` as given (text, checked while parsing, resolved by
/// resolveViewSpec). Empty / unset: not given, the lower layers of the precedence apply.
struct RenderViewArgs {
  std::string view;                               ///< --view global|keyframe:K|container:K (empty: global)
  std::string size;                               ///< --size WxH
  std::string color;                              ///< --color MODE
  std::string background;                         ///< --background dark|white|#rrggbb
  std::string layers;                             ///< --layers LIST|none
  std::string mesh_style;                         ///< --mesh-style shaded|colour|wireframe
  MeshOptions mesh;                               ///< --mesh-max-slope, --mesh-stride, ...
  std::string up;                                 ///< --up data|+z|+y|-y|X,Y,Z (with --look-at: the image's up)
  std::string projection;                         ///< --projection perspective|orthographic
  std::string draw;                               ///< --draw ellipsoids|centres|none
  std::string slice;                              ///< --slice LO:HI
  std::string look_at;                            ///< --look-at EX,EY,EZ,TX,TY,TZ
  std::string orbit;                              ///< --orbit AZ,EL[,DIST]
  std::string view_file;                          ///< --view-file V.json
  std::string settings;                           ///< --settings FILE (settings.json or view file: thresholds)
  std::vector<std::string> set;                   ///< --set KEY=VALUE
  std::optional<float> fov, sigma, points_below;  ///< --fov, --sigma, --points-below
  std::optional<int> sphere_level, select;        ///< --sphere-level, --select K
  bool grid = false;                              ///< --grid (container view's cell grid; as --layers +grid)
};

/// Parses --size WIDTHxHEIGHT (each side 1..kMaxImageSide); throws std::invalid_argument.
std::pair<int, int> parseViewSize(const std::string& text);

/// Registers the view flags on `verb` (or a suite view's parser), writing into `args` (which
/// must outlive the parse). Syntax and ranges are checked while parsing.
void addRenderViewOptions(CLI::App& verb, RenderViewArgs& args);

/// The settings and view a render uses, with the precedence defaults < `session_thresholds` <
/// --settings < --view-file (view only) < flags and --set. `source` says which applied:
/// "defaults", "the session's thresholds", "FILE" or "FILE over the session's thresholds".
struct ResolvedView {
  render::ViewSpec spec;
  GlobalMapParams thresholds;
  MapperParams mapper;  ///< what a sequence is mapped with (--settings' and --set's re-run keys)
  MeshParams mesh;      ///< how the mesh layer is made (the settings' mesh keys, then the --mesh-* flags)
  std::string settings_source;
};
ResolvedView resolveViewSpec(const RenderViewArgs& args, const std::optional<GlobalMapParams>& session_thresholds);

}  // namespace vdmap::app
