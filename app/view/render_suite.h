#pragma once
// `vdmap render --suite views.yaml`: many views of one or more maps, each map loaded once, each
// view compared with its golden; a table on stdout, JUnit XML and the images of failing views in
// the suite's out folder (docs/cli.md "Render suites").
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/view/render_check.h"
#include "render/image_compare.h"

namespace vdmap::app {

struct SuiteOptions {
  bool update = false;                              ///< write goldens (every view's, or update_views') instead
  std::optional<render::ImageTolerance> tolerance;  ///< --tolerance: replaces the suite's default
  bool timings = false;                             ///< a note line with the stage times on stderr
  bool table = true;                                ///< print the table and the summary on stdout
  std::vector<std::string> update_views{};          ///< --update VIEW...: only these (the others compare)
  std::optional<render::CompareMethod> compare{};   ///< --compare: replaces the suite's compare
  std::string out{};                                ///< --out DIR: replaces the suite's out folder
  std::string settings{};                           ///< --settings FILE: replaces the suite's settings
  std::vector<std::string> set{};                   ///< --set KEY=VALUE for every view (its own win)
  bool require_goldens = false;                     ///< a missing golden is bad input (bench: nothing to compare)
};

/// One view's outcome. Times in seconds: the global map it needed built (0 when cached), the
/// drawing, the comparison (and the writing of its images).
struct SuiteViewResult {
  std::string name, map, size;
  bool updated = false, passed = true;
  bool no_golden = false;  ///< compared but there was no golden: fails
  /// With --update: "new" (no golden before), "changed" (the old one differs under the view's
  /// compare), "rewritten" (it differed within the tolerance), "same" (identical: not written).
  std::string change;
  render::ImageComparison comparison{};
  double build_s = 0, render_s = 0, check_s = 0;
};

/// A whole run: the views in the suite's order, what was loaded and built, stage times.
struct SuiteResult {
  std::vector<SuiteViewResult> views;
  int maps_loaded = 0;        ///< maps and sessions opened (each once)
  int global_maps_built = 0;  ///< distinct global maps built (one per map and thresholds)
  double validate_s = 0;      ///< reading the suite, loading the maps, checking views and goldens
  double load_s = 0;          ///< of validate_s: loading the maps
  double context_s = 0;       ///< creating the offscreen GL context (first use in the process)
  double total_s = 0;
  std::vector<std::string> orphans;  ///< PNGs in the goldens folder that no view of the suite names
  int failed() const;
};

/// Runs the suite `file`. Validates all of it before anything is rendered or written: unknown
/// keys, maps that are missing or do not load, bad view options, keyframes out of range, goldens
/// damaged or of another size (when compared), views named by --update that are not there throw
/// InputError naming FILE:LINE. Then draws every view, compares it (or writes its golden with
/// `update`), writes OUT/NAME.actual.png and OUT/NAME.diff.png of each failing view and
/// OUT/junit.xml. A view without a golden fails ("no golden") and the others still run. Never
/// throws for a differing view: the caller turns failed() into exit code 2.
SuiteResult runSuite(const std::filesystem::path& file, const SuiteOptions& options);

/// `vdmap render --suite`: runs it and throws ExitWith(2) when a view differs.
void runSuiteCommand(const std::string& file, const SuiteOptions& options);

/// With --suite: checks the options (checkSuiteExcludes), runs runSuiteCommand with --out,
/// --settings and --set (`out`, `view`) and returns true; without: false.
struct RenderViewArgs;
bool runSuiteIfGiven(const CLI::App& verb, const RenderCheckArgs& args, const RenderViewArgs& view,
                     const std::string& out);

/// Refuses (CLI::ExcludesError) every option of `verb` given with --suite besides --suite,
/// --update, --tolerance, --compare, --timings, --out, --settings and --set: a suite's views
/// carry their own options.
void checkSuiteExcludes(const CLI::App& verb);

}  // namespace vdmap::app
