#pragma once
// View files (JSON, "vdmap_view": 1): one view of a map as the workbench saves it and
// `vdmap render --view-file` draws it (docs/cli.md "render"). Strict: every key is required, an
// unknown key is refused, a value out of range or not finite is an InputError naming "FILE: key".
#include <filesystem>
#include <string>

#include "app/view/settings.h"
#include "mapping/global_map/global_map.h"
#include "render/view_spec.h"

namespace vdmap::app {

/// Reads a view file. `thresholds`, when given, receives its "thresholds" section (the live
/// parameters; they apply only through --settings V.json). Throws InputError naming the file.
render::ViewSpec readViewFile(const std::filesystem::path& file, GlobalMapParams* thresholds = nullptr);

/// Writes `spec` with the live thresholds and `source` (informational: the session or sequence
/// shown) atomically. Throws std::runtime_error naming the file.
void writeViewFile(const std::filesystem::path& file, const render::ViewSpec& spec, const GlobalMapParams& thresholds,
                   const std::string& source);

/// What a printed `vdmap render` command draws: the session, map file or sequence, the flags that
/// select what of it is shown (a sequence's " --frames 0:150 --camera kinect"), and " --set K=V"
/// for each threshold that differs from what `vdmap render` starts with for it.
struct CommandSource {
  CommandSource(std::string p, std::string f = "", std::string s = "")
      : path(std::move(p)), flags(std::move(f)), thresholds(std::move(s)) {}
  CommandSource(const char* p) : path(p) {}
  std::string path, flags, thresholds;
};

/// The `vdmap render` command that draws `spec` of `source` into `out`: with `view_file` empty
/// every option spelled out (--view, --size, --look-at/--orbit, --color, ...; defaults left out,
/// the thresholds as --set), else `vdmap render SOURCE --view-file VIEW_FILE --out OUT` (with
/// `--settings VIEW_FILE` when the thresholds differ: the file holds them). Paths are quoted
/// when needed.
std::string renderCommand(const render::ViewSpec& spec, const CommandSource& source, const std::string& view_file = "",
                          const std::string& out = "view.png");

/// --settings FILE: a settings.json or a view file (told apart by its "vdmap_view" key). A view
/// file gives its thresholds only; a settings file its thresholds and view keys. Keys it lacks
/// keep `base`'s values. Throws InputError naming the file.
gui::Settings readSettingsArg(const std::filesystem::path& file, const gui::Settings& base = {});

/// Whether `file` is a view file (a JSON object with a "vdmap_view" key); false when unreadable.
bool isViewFile(const std::filesystem::path& file);

/// "global", "keyframe:K" or "container:K" (the view names of --view and view files) and back;
/// parseViewName throws std::invalid_argument naming the forms.
std::string viewName(const render::ViewSpec& spec);
void parseViewName(const std::string& text, render::ViewSpec* spec);

}  // namespace vdmap::app
