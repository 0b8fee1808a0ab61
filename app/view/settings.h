#pragma once
// The workbench's persisted settings: thresholds, re-run parameters, view options, window size
// and the last sequence, stored as JSON in $XDG_CONFIG_HOME/vdmap/settings.json. Parsing lives
// here (app/), the parameter structs stay in mapping/.
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "mapping/global_map/global_map.h"
#include "mapping/mesh/surface_mesh.h"
#include "mapping/pipeline/mapper.h"
#include "render/query_slice.h"
#include "render/scene_types.h"
#include "render/view_spec.h"

namespace vdmap::app::gui {

/// Which world direction the 3-D view keeps up (render/view_spec.h, shared with `vdmap render`).
using render::kUpAxisNames;
using render::UpAxis;

/// Everything that persists between runs. Defaults are the library's defaults.
struct Settings {
  GlobalMapParams thresholds;  ///< live: changing one rebuilds the global map
  MapperParams mapper;         ///< re-run: changing one re-maps the sequence
  render::ColorMode color = render::ColorMode::kRgb;
  bool show_ellipsoids = true;  ///< false: ellipsoid centres as points
  /// Draw "hidden": no map at all (the paths and cameras alone). Not saved: a run starts with the map.
  bool hide_map = false;
  bool show_frustums = true, show_graph = true, show_trajectory = true;
  bool show_groundtruth = true;  ///< tracked poses: the ground-truth trajectory beside them
  float ellipsoid_sigma = 2.f;
  float play_fps = 0.f;                ///< playback limit, frames per second; 0: as fast as mapping goes
  UpAxis up_axis = UpAxis::kData;      ///< kData: estimated from the cameras and the map's floor
  std::optional<glm::vec3> up_vector;  ///< a user-set up direction (key up_vector), over up_axis
  render::Projection projection = render::Projection::kPerspective;
  render::Rotation rotation = render::Rotation::kOrbit;  ///< how a drag turns the 3-D view
  bool container_grid = false;                           ///< the container view's cell grid
  bool container_bounds = true;                          ///< the container view's image outline
  glm::vec3 background = render::kDarkBackground;        ///< "dark", "white" or "#rrggbb"
  bool show_legend = true;                               ///< the colour legend and tracking key over the 3-D view
  /// The surface mesh layer (keys show_mesh, mesh_style): built by the mapping worker with every
  /// global map while it is on.
  bool show_mesh = false;
  render::MeshStyle mesh_style = render::MeshStyle::kShaded;
  /// How it is made (keys mesh_max_slope, mesh_edge_sigma, mesh_stride, mesh_fuse; `vdmap mesh`'s
  /// options): a change re-meshes the local maps, nothing is integrated again.
  MeshParams mesh;
  /// Height slice (keys `slice`, `slice_lo`, `slice_hi`): only ellipsoids whose centre lies
  /// slice_lo..slice_hi metres above the floor are drawn, picked and framed.
  render::HeightSlice slice;
  // Point queries (docs/workbench.md "Queries"; keys probe, probe_offset, query_slice,
  // query_slice_at, query_slice_color, query_slice_max_distance).
  bool probe = false;            ///< Q: what the map says under the cursor
  float probe_offset_m = 0.05f;  ///< the probe stands this far in front of the surface under the cursor
  bool query_slice = false;      ///< the query slice is drawn
  render::QuerySliceSpec query_slice_spec;
  int window_width = 1600, window_height = 900;
  std::string last_sequence;
  /// Recently opened paths (any kind the workbench opens), newest first, at most kRecentFiles;
  /// settings key `recent`. addRecent keeps it so.
  std::vector<std::string> recent;
};

/// How many paths Settings::recent keeps.
inline constexpr std::size_t kRecentFiles = 10;
/// Puts `path` at the front of settings.recent (once), dropping the oldest beyond kRecentFiles.
void addRecent(Settings& settings, const std::string& path);

/// $XDG_CONFIG_HOME/vdmap/settings.json (or ~/.config/vdmap/settings.json).
std::filesystem::path settingsPath();

/// Reads settings. A missing file gives the defaults silently; an unreadable or malformed file,
/// or a value of the wrong type or out of range, gives the defaults and sets `warning` to a
/// one-line message naming the file. Keys the file lacks keep their defaults.
Settings loadSettings(const std::filesystem::path& file, std::string* warning);

/// Reads a settings file named explicitly (--settings): keys the file lacks keep `base`'s values.
/// Throws InputError naming the file for a missing, unreadable or malformed file or a bad value.
Settings readSettingsFile(const std::filesystem::path& file, const Settings& base = {});

/// The background names of the settings file, view files and --background: "dark", "white" or
/// "#rrggbb". parseBackground throws std::invalid_argument naming the accepted forms.
glm::vec3 parseBackground(const std::string& text);
std::string backgroundName(const glm::vec3& rgb);

/// The view a Settings describes (the window's global view with its options).
render::ViewSpec viewSpecOf(const Settings& settings);

/// Writes settings atomically (creating the folder). Throws std::runtime_error naming the file.
void saveSettings(const std::filesystem::path& file, const Settings& settings);

/// Writes into `file` the keys whose value differs between `before` (the settings as this run
/// last wrote them, or as it started) and `after`, keeping every other key of the file as it is:
/// values given with --set and not changed since are not saved, nor do they undo what another run
/// saved; a value put back to what it was at the start is written once it differs from what this
/// run wrote. Creates the file (and folder) when missing; writes nothing when nothing changed. A
/// file that exists but is not valid settings is never replaced: throws std::runtime_error saying
/// so, naming it.
void saveChangedSettings(const std::filesystem::path& file, const Settings& before, const Settings& after);

/// Whether a and b hold the same values (every key of the settings file).
bool sameSettings(const Settings& a, const Settings& b);

/// Whether a and b differ in a re-run parameter (a key of the settings file's "rerun" section),
/// so that switching between them means re-mapping the sequence.
bool rerunParamsDiffer(const Settings& a, const Settings& b);

/// The keys applySetting takes, for help texts: "thresholds: KEY, ...; rerun: ...; view: ...",
/// the keys of those sections of the settings file.
std::string settingKeyList();
/// Refuses (std::invalid_argument naming it) a --set of a re-run parameter: `what` (a saved
/// session or a map file) was mapped already, so only live thresholds and view keys apply.
void refuseRemapSettings(const std::vector<std::string>& set, const std::string& what);

/// Applies "key=value" to the thresholds, re-run parameters or view (the --set option); the
/// value is checked as in the settings file. Keys: settingKeyList().
/// Throws std::invalid_argument naming the key or value that is wrong.
void applySetting(Settings& settings, const std::string& key_value);

}  // namespace vdmap::app::gui
