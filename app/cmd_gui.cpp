// `vdmap` (no verb: the built-in scene) and `vdmap gui SEQ`: the workbench window, with a
// scripted path for tests (--play-to-end --set KEY=VALUE --screenshot PNG --stats-json FILE --exit).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "app/cli/command_line.h"
#include "app/cli/error_text.h"
#include "app/cli/sequence_args.h"
#include "app/verbs.h"
#include "app/view/progress.h"
#include "app/view/settings.h"
#include "app/view/view_file.h"
#include "app/window/glfw_context.h"
#include "app/window/workbench_window.h"
#include "app/workbench/workbench.h"
#include "mapping/core/error.h"
#include "mapping/files/map_file.h"
#include "mapping/files/session_file.h"
#include "mapping/synth/builtin_scene.h"
#include "render/sequence_synth.h"

namespace vdmap::app {
namespace {
namespace fs = std::filesystem;

struct GuiArgs {
  SequenceArgs sequence;
  std::string map;        ///< a saved session or a map file (mapping/files/map_file.h) instead of a sequence
  std::string settings;   ///< --settings: this file instead of the defaults or the user's settings
  std::string view_file;  ///< --view-file: read (strictly) before the window opens
  gui::ScriptOptions script;
  std::vector<std::string> set;
  std::string window_size;
};

// A stable fingerprint of the built-in scene, so a cached copy is regenerated when the scene
// or its walk changes.
std::uint64_t sceneFingerprint(const BuiltinScene& scene) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](double v) {
    const auto bits = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::llround(v * 1e6)));
    h = (h ^ bits) * 1099511628211ull;
  };
  for (const StampedPose& p : scene.trajectory) {
    mix(p.t);
    for (int i = 0; i < 3; ++i) mix(p.T_W_C.translation()[i]);
  }
  mix(static_cast<double>(scene.mesh.positions.size()));
  mix(static_cast<double>(scene.mesh.triangles.size()));
  return h;
}

// The built-in scene as a sequence in $XDG_CACHE_HOME/vdmap, rendered on first use. With
// --frames A:B only the first B frames of the walk are rendered, unless the whole walk is
// cached already: each frame is rendered (and its noise drawn) on its own, so the first B
// frames of the whole walk are those B frames.
struct BuiltinCache {
  BuiltinScene scene;
  fs::path folder;  ///< the cached sequence to open (may not exist yet)
  int count = 0;    ///< frames it holds
  bool cached() const { return fs::exists(folder / "rgb.txt"); }
};

BuiltinCache builtinCache(const std::string& frames) {
  BuiltinCache c{makeBuiltinScene(), {}, 0};
  const int last = frames.empty() ? -1 : parseFrameRange(frames).last;
  const int total = static_cast<int>(c.scene.trajectory.size());
  c.count = last < 0 ? total : std::min(last, total);
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  const fs::path cache = xdg && *xdg     ? fs::path(xdg)
                         : home && *home ? fs::path(home) / ".cache"
                                         : fs::temp_directory_path();
  const auto fingerprint = static_cast<unsigned long long>(sceneFingerprint(c.scene));
  const auto folder = [&](int n) {
    char name[64];
    std::snprintf(name, sizeof name, "builtin-%016llx-%d", fingerprint, n);
    return cache / "vdmap" / name;
  };
  c.folder = fs::exists(folder(total) / "rgb.txt") ? folder(total) : folder(c.count);
  return c;
}

// Renders the built-in scene into c.folder (OSMesa, on the calling thread, which must not own
// the window's context), reporting progress to `progress` and the terminal.
std::string renderBuiltin(const BuiltinCache& c, const std::function<void(std::size_t, std::size_t)>& progress,
                          const std::function<bool()>& cancelled) {
  fs::create_directories(c.folder.parent_path());
  render::SynthOptions options;
  options.camera = c.scene.camera;
  options.last_frame = c.count;
  ProgressBar bar("rendering the built-in scene", static_cast<std::size_t>(c.count));
  options.progress = [&](std::size_t done, std::size_t total) {
    bar.update(done);
    progress(done, total);
  };
  options.cancelled = cancelled;
  try {
    render::synthesizeSequence(c.scene.mesh, c.scene.trajectory, options, c.folder);
  } catch (...) {
    if (!c.cached()) throw;  // another vdmap may have written the same folder meanwhile; then use that one
  }
  return c.folder.string();
}

// Which settings a run starts with (docs/workbench.md "Which settings apply"): the file given
// with --settings; else the defaults for a scripted run (reproducible) and the user's file for an
// interactive one. A saved session opened at start keeps its own thresholds, unless --settings
// names a file: the thresholds that file sets then go over the session's.
struct StartSettings {
  gui::Settings settings;
  fs::path user_file;   ///< read now and saved at the end; empty: neither (scripted, or --settings)
  std::string source;   ///< what the note names
  std::string warning;  ///< the user's file was malformed (its defaults are used)
};

StartSettings startSettings(const GuiArgs& args, bool session) {
  StartSettings start;
  if (!args.settings.empty()) {
    start.settings = readSettingsArg(args.settings);  // strict: a bad file is an error naming it
    start.source = args.settings + (session ? " over the session's thresholds" : "");
    return start;
  }
  if (!args.script.exit) {
    start.user_file = gui::settingsPath();
    start.settings = gui::loadSettings(start.user_file, &start.warning);
    const std::string user =
        start.user_file.string() + (fs::exists(start.user_file) ? "" : " (not there yet: defaults)");
    start.source = session ? "the session's thresholds, view options from " + user : user;
    return start;
  }
  start.source = session ? "the session's thresholds" : "defaults";
  return start;
}

void runGui(GuiArgs args, bool builtin) {
  const std::string verb = builtin ? "vdmap" : "vdmap gui";
  const bool session = !builtin && !args.map.empty() && isSessionPath(args.map);
  const StartSettings start = startSettings(args, session);
  if (!args.view_file.empty()) args.script.view = readViewFile(args.view_file);
  const fs::path& settings_file = start.user_file;
  const std::string& warning = start.warning;
  if (!warning.empty()) std::cerr << "vdmap: warning: " << warning << "\n";
  // --set and --window-size hold for this run only: they are not saved (Workbench::saveSettings).
  gui::Settings settings = start.settings;
  for (const std::string& kv : args.set) gui::applySetting(settings, kv);
  if (!args.map.empty()) gui::refuseRemapSettings(args.set, args.map);
  if (!args.window_size.empty()) {
    int w = 0, h = 0;
    char rest = 0;
    if (std::sscanf(args.window_size.c_str(), "%dx%d%c", &w, &h, &rest) != 2 || w < 320 || h < 240 || w > 16384 ||
        h > 16384)
      throw CLI::ValidationError("--window-size",
                                 "'" + args.window_size + "': expected WxH within 320x240..16384x16384");
    settings.window_width = w;
    settings.window_height = h;
  }
  // A missing sequence or session is named before the display is looked at (without a display,
  // `gui /nope` named the display); a damaged session still opens the window with its error.
  // A map file is read now, so a bad one fails with its one line before the window opens.
  std::shared_ptr<const StaticMap> static_map;
  if (!builtin && !args.map.empty() && !isSessionPath(args.map)) {
    if (!fs::exists(args.map)) throw InputError(args.map, "no such session or map file");
    if (detectMapFile(args.map) == MapFileKind::kViewFile)
      throw InputError(args.map, "is a view file: give it with --view-file beside the map or sequence it views");
    static_map = std::make_shared<const StaticMap>(loadStaticMap(fs::absolute(args.map).lexically_normal()));
  }
  if (!builtin && args.map.empty()) noteCameraGuess(openSequence(args.sequence), "gui");
  // Without a display, say so now rather than after rendering the built-in scene (a minute).
  gui::requireDisplay();
  std::cerr << verb << ": note: settings: " << start.source << "\n";
  gui::Workbench bench(settings, warning);
  bench.files().setSessionSettings(args.settings, args.set);
  bench.ui().settings_source = start.source;
  bench.ui().settings_file = settings_file.string();
  // Saved 1 s after the last change while the window runs, and on close (below); scripted and
  // --settings runs have no settings file and never save.
  if (!settings_file.empty()) bench.enableSettingsAutosave(settings_file.string(), settings);
  gui::Preparation prepare;
  if (builtin) {
    const BuiltinCache cache = builtinCache(args.sequence.frames);
    args.sequence.folder = cache.folder.string();
    if (!cache.cached())  // rendered while the window shows its progress
      prepare = {"rendering the built-in scene", args.sequence,
                 [cache](const std::function<void(std::size_t, std::size_t)>& progress,
                         const std::function<bool()>& cancelled) { return renderBuiltin(cache, progress, cancelled); }};
  }
  bench.files().setRefinement(refinement(args.sequence));
  // A failure shows in the window, which stays open.
  if (!prepare.run) {
    if (static_map) bench.files().openMapFile(static_map);
    else if (!args.map.empty()) bench.files().openSession(args.map);
    else bench.files().open(args.sequence);
  }
  const int code = gui::runWorkbenchWindow(bench, args.script, settings_file.string(), std::move(prepare));
  if (!settings_file.empty()) {
    try {
      bench.saveSettings();
    } catch (const std::exception& e) {
      std::cerr << "vdmap: warning: settings not saved: " << errorMessage(e) << "\n";
    }
  }
  if (code != 0) throw std::runtime_error(bench.firstError());
}

void addGuiOptions(CLI::App& app, GuiArgs& args) {
  app.add_flag("--play-to-end", args.script.play_to_end, "start playing at once (scripted runs)");
  app.add_option("--keyframe", args.script.keyframe, "select keyframe K in the inspector (scripted runs)");
  app.add_option("--screenshot", args.script.screenshot, "write a PNG of the window once mapping is done");
  app.add_option("--stats-json", args.script.stats_json,
                 "write frames, keyframes, Sigma_e, Sigma_e', t_g and the UI frame time once mapping is done");
  app.add_flag("--exit", args.script.exit, "close once the screenshot/stats are written (settings are not touched)");
  app.add_option("--set", args.set,
                 "KEY=VALUE for this run (as in settings.json; not saved): " + gui::settingKeyList());
  app.add_option_function<std::string>(
      "--press", [&args](const std::string& keys) { args.script.press = gui::parseKeyNames(keys); },
      "scripted: keys pressed once mapping is done, before the screenshot (comma-separated: a-z, space, right, left, "
      "f1, esc, pgup, pgdn, each with ctrl+ before it for Ctrl; e.g. h for the help, ctrl+s to save the view)");
  app.add_option("--edit", args.script.edit,
                 "scripted: KEY=VALUE, a threshold edited once mapping is done, before the keys (as its slider "
                 "does; D then shows what it changed); repeatable");
  app.add_option("--window-size", args.window_size, "WxH: the window's size for this run (not saved)");
  app.add_option("--drop", args.script.drop,
                 "scripted: PATH dropped on the window once mapping is done, before the screenshot (any kind the "
                 "workbench opens; a view file is applied as a view); repeatable");
  app.add_option_function<std::string>(
      "--view-file", [&args](const std::string& file) { args.view_file = file; },
      "scripted: show this view file's view (camera, view options) once mapping is done, instead of the default view");
  app.add_option(
      "--save-view", args.script.save_view,
      "scripted: save the view shown as a view file once mapping is done (as S does), for vdmap render --view-file");
  app.add_option("--view-screenshot", args.script.view_screenshot,
                 "scripted: a PNG of the 3-D view alone (no panels) at the view's size, once mapping is done");
  app.add_option("--settings", args.settings,
                 "FILE: start from this settings.json (or a view file's thresholds) instead of the defaults (scripted "
                 "runs) or your own settings (interactive runs); its thresholds go over a session's; your settings are "
                 "neither read nor written");
  app.add_flag("--expand-sections", args.script.expand_sections,
               "scripted: open every collapsible section of the panels (the stats' labels_cut then covers them all)");
  app.add_option("--measure-latency", args.script.latency_runs,
                 "scripted: after the screenshot, N threshold edits (each live parameter to another value and back, "
                 "merge distance first), each timed until its map is drawn (stats: slider_to_map_ms, "
                 "slider_to_map_stages_ms)");
  app.add_option("--measure-orbit", args.script.orbit_frames,
                 "scripted: then N frames orbiting the view (stats: orbit_frame_ms, orbit_fast_ms, fast_instances, "
                 "settle_ms)");
  // Progressive drawing:
  app.add_option("--fast-budget", args.script.fast_budget,
                 "N ellipsoids drawn (as points, a spatially even sample) while the camera moves, instead of the "
                 "budget adapted to the frame time (scripted runs and tests)")
      ->check(CLI::PositiveNumber);
  app.add_option("--measure-idle", args.script.idle_seconds,
                 "scripted: then S seconds of nothing happening (stats: idle_cpu_s, process CPU seconds)");
  app.add_option_function<std::string>(
      "--measure",
      [&args](const std::string& text) {
        float v[4];
        char rest = 0;
        if (std::sscanf(text.c_str(), "%f,%f,%f,%f%c", &v[0], &v[1], &v[2], &v[3], &rest) != 4 ||
            !std::all_of(v, v + 4, [](float x) { return std::isfinite(x) && x >= 0; }))
          throw CLI::ValidationError("--measure", "'" + text + "': expected X1,Y1,X2,Y2 (view pixels, >= 0)");
        args.script.measure.assign(v, v + 4);
      },
      "scripted: measure between view pixels X1,Y1 and X2,Y2 once mapping is done, as Ctrl+click does (stats: "
      "measure {a, b, distance_m})");
  // Point queries (docs/workbench.md "Queries").
  app.add_option_function<std::string>(
      "--probe",
      [&args](const std::string& text) {
        float v[2];
        char rest = 0;
        if (std::sscanf(text.c_str(), "%f,%f%c", &v[0], &v[1], &rest) != 2 ||
            !std::all_of(v, v + 2, [](float x) { return std::isfinite(x) && x >= 0; }))
          throw CLI::ValidationError("--probe", "'" + text + "': expected X,Y (view pixels, >= 0)");
        args.script.probe.assign(v, v + 2);
      },
      "scripted: the probe (Q) at view pixel X,Y once mapping is done (stats: probe {class, p, distance_m, point})");
  app.add_option_function<std::string>(
      "--query-slice",
      [&args](const std::string& text) {
        const auto color =
            args.script.query_slice ? args.script.query_slice->color : render::QuerySliceColor::kOccupancy;
        try {
          args.script.query_slice = render::parseQuerySlice(text);
        } catch (const std::invalid_argument& e) {
          throw CLI::ValidationError("--query-slice", e.what());
        }
        args.script.query_slice->color = color;
      },
      "show the query slice across AXIS (up: VALUE m above the floor; x, y, z: at that coordinate), e.g. up=1.0 "
      "(Queries section; not the height slice, --set slice)");
  app.add_option_function<std::string>(
      "--query-slice-color",
      [&args](const std::string& text) {
        if (!args.script.query_slice) args.script.query_slice = render::QuerySliceSpec{};
        try {
          args.script.query_slice->color = render::parseQuerySliceColor(text);
        } catch (const std::invalid_argument& e) {
          throw CLI::ValidationError("--query-slice-color", e.what());
        }
      },
      "the query slice's colours: occupancy (free green, occupied red, unknown grey) or distance (to the nearest "
      "surface)");
  app.add_option("--close-after-frames", args.script.close_after_frames,
                 "close the window as a user would after N frames drawn (tests: closing during the first start)")
      ->check(CLI::PositiveNumber);
}

}  // namespace

void addGuiCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("gui", "Open the workbench on a sequence, a saved session or a map file");
  auto args = std::make_shared<GuiArgs>();
  addSequenceArgs(*verb, args->sequence);
  addPoseSourceArg(*verb, args->sequence);
  addRefineArg(*verb, args->sequence);
  verb->get_option("SEQ")->required(false);
  verb->add_option("--map", args->map,
                   "open a saved session (.vdmap) or a map file instead of a sequence: a `vdmap map` folder, an "
                   "ellipsoid or point PLY, an OctoMap .bt/.ot (any of them as SEQ does too)");
  addGuiOptions(*verb, *args);
  verb->callback([args] {
    // `vdmap gui S.vdmap` (or a map folder, PLY, OctoMap) opens it, as the workbench's Open field does.
    const fs::path& seq = args->sequence.folder;
    if (args->map.empty() && !recogniseSequence(seq) &&
        (fs::is_regular_file(seq) || fs::exists(seq / "global_ellipsoids.ply")))
      std::swap(args->map, args->sequence.folder);
    if (args->sequence.folder.empty() == args->map.empty())
      throw CLI::ValidationError("SEQ", "give a sequence SEQ or --map FILE (one of them)");
    runGui(*args, false);
  });
}

std::function<void()> addBuiltinWorkbenchOptions(CLI::App& app) {
  auto args = std::make_shared<GuiArgs>();
  app.add_option("--frames", args->sequence.frames, "built-in scene: frames A:B of the walk (B exclusive)")
      ->check(frameRangeCheck());
  addGuiOptions(app, *args);
  return [args] { runGui(*args, true); };
}

}  // namespace vdmap::app
