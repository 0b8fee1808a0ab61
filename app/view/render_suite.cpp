// `vdmap render --suite`: reading and validating the suite file (YAML), drawing its views through
// RenderSource (app/view/render_view.h), the table, the JUnit report and the failing views' images.
#include "app/view/render_suite.h"
#include "app/cli/error_text.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <regex>
#include <set>

#include <yaml-cpp/yaml.h>

#include "app/view/junit_xml.h"
#include "app/view/render_check.h"
#include "app/view/render_source.h"
#include "app/view/render_view.h"
#include "mapping/core/error.h"
#include "mapping/core/message_text.h"
#include "mapping/core/timing.h"
#include "mapping/files/session_file.h"
#include "mapping/io/text_list.h"
#include "render/framebuffer.h"

namespace vdmap::app {

namespace fs = std::filesystem;

int SuiteResult::failed() const {
  return static_cast<int>(
      std::count_if(views.begin(), views.end(), [](const SuiteViewResult& v) { return !v.passed; }));
}

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct MapEntry {
  std::string name;
  fs::path path;
  int line = 0;
};

// A tolerance's keys as given; what is not given comes from the layer below.
struct ToleranceKeys {
  std::optional<int> counts;
  std::optional<double> share;
  std::optional<render::CompareMethod> compare;
};

struct ViewEntry {
  std::string name, map;
  int line = 0;
  RenderViewArgs args;
  ToleranceKeys tolerance;
  std::optional<render::QuerySliceSpec> query_slice;  // query-slice, query-slice-color
};

struct SuiteFile {
  std::string name;  ///< as given, for messages
  fs::path folder;   ///< paths in the file are relative to it
  ToleranceKeys tolerance;
  fs::path goldens, out;
  std::string settings;
  std::vector<MapEntry> maps;
  std::vector<ViewEntry> views;
};

int lineOf(const YAML::Node& node) { return node.Mark().line + 1; }

std::string scalar(const YAML::Node& node, const std::string& file, const std::string& what) {
  if (!node.IsScalar()) throw InputError(file, lineOf(node), what + " must be a text or number");
  return node.Scalar();
}

fs::path relativeTo(const fs::path& folder, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() ? p : (folder / p).lexically_normal();
}

// tolerance: {counts: 8, share: 0.025 or 2.5%}, over `base`.
ToleranceKeys readTolerance(const YAML::Node& node, const std::string& file, ToleranceKeys base) {
  if (!node.IsMap()) throw InputError(file, lineOf(node), "tolerance must be a map {counts: 8, share: 2.5%}");
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    const int line = lineOf(entry.first);
    try {
      if (key == "counts") {
        base.counts = entry.second.as<int>();
        if (*base.counts < 0 || *base.counts > 255) throw YAML::Exception(entry.second.Mark(), "");
      } else if (key == "share") {
        base.share = parseShare(scalar(entry.second, file, "share"));
      } else {
        throw InputError(file, line, "unknown tolerance key '" + key + "' (expected counts, share)");
      }
    } catch (const std::exception& e) {
      if (dynamic_cast<const InputError*>(&e)) throw;
      throw InputError(
          file, line,
          "tolerance " + key + (key == "counts" ? " must be an integer in 0..255" : " must be in 0..1 or 0%..100%"));
    }
  }
  return base;
}

render::CompareMethod readCompare(const YAML::Node& node, const std::string& file) {
  try {
    return render::parseCompareMethod(scalar(node, file, "compare"));
  } catch (const std::invalid_argument& e) {
    throw InputError(file, lineOf(node), std::string("compare: ") + e.what());
  }
}

// The tolerance a view is compared with: its own keys, else the command line's, else the
// suite's, else the compare's default.
render::ImageTolerance resolveTolerance(const ToleranceKeys& view, const SuiteOptions& options,
                                        const ToleranceKeys& suite) {
  const render::CompareMethod method =
      view.compare ? *view.compare : options.compare.value_or(suite.compare.value_or(render::CompareMethod::kNearby));
  render::ImageTolerance t = defaultTolerance(method);
  if (options.tolerance) t = *options.tolerance;
  t.channel_counts =
      view.counts.value_or(options.tolerance ? t.channel_counts : suite.counts.value_or(t.channel_counts));
  t.pixel_share = view.share.value_or(options.tolerance ? t.pixel_share : suite.share.value_or(t.pixel_share));
  t.method = method;
  return t;
}

// The render flags a suite view may carry as keys (the flags without --), from the same
// registration render uses.
struct ViewOptionParser {
  RenderViewArgs scratch;
  CLI::App app;
  ViewOptionParser() { addRenderViewOptions(app, scratch); }
};

// A view's keys as render's command line: "color: uncertainty" -> --color uncertainty, a
// true flag -> --grid, a list -> the option once per element. Paths are made relative to the
// suite file's folder.
ViewEntry readView(const YAML::Node& node, const SuiteFile& suite, const std::string& file, ViewOptionParser& known,
                   const SuiteOptions& options) {
  ViewEntry view;
  view.line = lineOf(node);
  if (!node.IsMap()) throw InputError(file, view.line, "a view must be a map {name: ..., map: ..., ...}");
  std::vector<std::string> argv;
  for (const std::string& set : options.set) argv.insert(argv.end(), {"--set", set});  // the view's own come after
  bool settings_given = false;
  std::optional<render::QuerySliceColor> slice_color;
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    const int line = lineOf(entry.first);
    if (key == "name") {
      view.name = scalar(entry.second, file, "name");
    } else if (key == "map") {
      view.map = scalar(entry.second, file, "map");
    } else if (key == "tolerance") {
      view.tolerance = readTolerance(entry.second, file, view.tolerance);
    } else if (key == "compare") {
      view.tolerance.compare = readCompare(entry.second, file);
    } else if (key == "query-slice" || key == "query-slice-color") {  // render's, not a view option
      try {
        const std::string text = scalar(entry.second, file, key);
        if (key == "query-slice") view.query_slice = render::parseQuerySlice(text);
        else slice_color = render::parseQuerySliceColor(text);
      } catch (const std::invalid_argument& e) {
        throw InputError(file, line, key + ": " + e.what());
      }
    } else {
      const CLI::Option* option = known.app.get_option_no_throw("--" + key);
      if (!option || key == "help")
        throw InputError(file, line,
                         "unknown view key '" + key +
                             "' (a view has name, map, tolerance, compare and render's view "
                             "options without --, e.g. view, size, color, orbit, view-file, query-slice)");
      const bool flag = option->get_expected_max() == 0;  // a flag takes no value
      const bool path = key == "view-file" || key == "settings";
      settings_given = settings_given || key == "settings";
      const auto add = [&](const YAML::Node& value) {
        const std::string text = scalar(value, file, key);
        if (flag) {
          if (text == "true") argv.push_back("--" + key);
          else if (text != "false") throw InputError(file, line, key + " must be true or false");
          return;
        }
        argv.push_back("--" + key);
        argv.push_back(path ? relativeTo(suite.folder, text).string() : text);
      };
      if (entry.second.IsSequence()) {
        for (const auto& element : entry.second) add(element);
      } else {
        add(entry.second);
      }
    }
  }
  if (view.name.empty()) throw InputError(file, view.line, "a view needs a name (its golden is GOLDENS/NAME.png)");
  static const std::regex name_pattern(R"([A-Za-z0-9][A-Za-z0-9._+-]*)");
  if (!std::regex_match(view.name, name_pattern))
    throw InputError(file, view.line,
                     "view name '" + view.name + "': letters, digits, '.', '_', '+' and '-' only (it names files)");
  if (view.map.empty()) throw InputError(file, view.line, "view '" + view.name + "' needs a map (a name under maps)");
  if (slice_color && !view.query_slice)
    throw InputError(file, view.line, "view '" + view.name + "': query-slice-color needs query-slice");
  if (slice_color) view.query_slice->color = *slice_color;
  if (!settings_given && !suite.settings.empty()) {
    argv.push_back("--settings");
    argv.push_back(suite.settings);
  }
  CLI::App parser;
  addRenderViewOptions(parser, view.args);
  std::reverse(argv.begin(), argv.end());  // CLI11 takes a vector in reverse order
  try {
    parser.parse(argv);
  } catch (const CLI::ParseError& e) {
    throw InputError(file, view.line, "view '" + view.name + "': " + e.what());
  }
  return view;
}

// Refuses a map that gives a key twice (YAML allows reading either), anywhere in `node`.
void refuseDuplicateKeys(const YAML::Node& node, const std::string& file) {
  if (node.IsSequence())
    for (const YAML::Node& item : node) refuseDuplicateKeys(item, file);
  if (!node.IsMap()) return;
  std::set<std::string> seen;
  for (const auto& entry : node) {
    if (entry.first.IsScalar() && !seen.insert(entry.first.Scalar()).second)
      throw InputError(file, lineOf(entry.first), "key '" + entry.first.Scalar() + "' is given twice in one map");
    refuseDuplicateKeys(entry.second, file);
  }
}

SuiteFile readSuite(const fs::path& file_path, const SuiteOptions& options) {
  const std::string file = file_path.string();
  YAML::Node root;
  checkNotAFolder(file_path);
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw InputError(file, "cannot open the suite file");
  } catch (const YAML::ParserException& e) {
    throw InputError(file, e.mark.line + 1, "not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw InputError(file, "expected a map with version, maps and views");
  refuseDuplicateKeys(root, file);
  SuiteFile suite;
  suite.name = file;
  suite.folder = fs::absolute(file_path).parent_path();
  suite.goldens = suite.folder / "goldens";
  suite.out = suite.folder / "render-out";
  static const std::set<std::string> keys = {"version", "tolerance", "compare", "goldens",
                                             "out",     "settings",  "maps",    "views"};
  for (const auto& entry : root)
    if (!keys.count(entry.first.Scalar()))
      throw InputError(file, lineOf(entry.first),
                       "unknown key '" + entry.first.Scalar() +
                           "' (expected version, tolerance, compare, goldens, out, settings, maps, views)");
  if (!root["version"] || scalar(root["version"], file, "version") != "1")
    throw InputError(file, root["version"] ? lineOf(root["version"]) : 1, "expected version: 1");
  if (root["tolerance"]) suite.tolerance = readTolerance(root["tolerance"], file, suite.tolerance);
  if (root["compare"]) suite.tolerance.compare = readCompare(root["compare"], file);
  if (root["goldens"]) suite.goldens = relativeTo(suite.folder, scalar(root["goldens"], file, "goldens"));
  if (root["out"]) suite.out = relativeTo(suite.folder, scalar(root["out"], file, "out"));
  if (root["settings"]) suite.settings = relativeTo(suite.folder, scalar(root["settings"], file, "settings")).string();
  if (!options.out.empty()) suite.out = fs::absolute(options.out).lexically_normal();  // the command line's
  if (!options.settings.empty()) suite.settings = fs::absolute(options.settings).lexically_normal().string();
  const YAML::Node maps = root["maps"];
  if (!maps || !maps.IsMap() || maps.size() == 0)
    throw InputError(file, maps ? lineOf(maps) : 1, "maps must name at least one map: {NAME: PATH, ...}");
  for (const auto& entry : maps)
    suite.maps.push_back(
        {entry.first.Scalar(), relativeTo(suite.folder, scalar(entry.second, file, "map path")), lineOf(entry.first)});
  const YAML::Node views = root["views"];
  if (!views || !views.IsSequence() || views.size() == 0)
    throw InputError(file, views ? lineOf(views) : 1, "views must be a list of at least one view");
  ViewOptionParser known;
  std::set<std::string> names;
  for (const auto& node : views) {
    ViewEntry view = readView(node, suite, file, known, options);
    if (!names.insert(view.name).second) throw InputError(file, view.line, "a second view named '" + view.name + "'");
    if (std::none_of(suite.maps.begin(), suite.maps.end(), [&](const MapEntry& m) { return m.name == view.map; }))
      throw InputError(file, view.line, "view '" + view.name + "': no map '" + view.map + "' under maps");
    suite.views.push_back(std::move(view));
  }
  return suite;
}

// A map of the suite, loaded once.
struct LoadedMap {
  std::unique_ptr<RenderSource> source;
  std::set<const void*> global_maps;  // distinct global maps it built
};

// One view, resolved and checked.
struct PreparedView {
  const ViewEntry* entry = nullptr;
  LoadedMap* map = nullptr;
  ResolvedView resolved;
  render::ImageTolerance tolerance;
  fs::path golden;
  cv::Mat golden_rgb;  // empty when there is none (or, updating, none of the view's size)
  bool update = false;
  int width = 0, height = 0;
};

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

void removeIfThere(const fs::path& file) {
  std::error_code ec;
  fs::remove(file, ec);
}

// A path as the report shows it: relative to the suite's folder (absolute on another root).
std::string shown(const fs::path& file, const fs::path& folder) {
  const fs::path relative = file.lexically_relative(folder);
  return relative.empty() ? file.string() : relative.string();
}

// The PNGs of the goldens folder no view names.
std::vector<std::string> orphanGoldens(const fs::path& goldens, const std::vector<ViewEntry>& views) {
  std::set<std::string> names;
  for (const ViewEntry& v : views) names.insert(v.name + ".png");
  std::vector<std::string> orphans;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(goldens, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file(ec) && entry.path().extension() == ".png" && !names.count(name)) orphans.push_back(name);
  }
  std::sort(orphans.begin(), orphans.end());
  return orphans;
}

// With --update: writes the golden unless it holds the same pixels, and says how it changed.
std::string updateGolden(const PreparedView& p, const cv::Mat& rgb) {
  std::error_code ec;
  std::string change = "new";
  if (!p.golden_rgb.empty()) {
    if (cv::norm(p.golden_rgb, rgb, cv::NORM_INF) == 0) return "same";
    change = render::compareImages(p.golden_rgb, rgb, p.tolerance).matches ? "rewritten" : "changed";
  } else if (fs::exists(p.golden, ec)) {
    change = "changed";  // damaged or of another size
  }
  render::writePng(p.golden, rgb);  // atomic: temporary file and rename
  return change;
}

}  // namespace

SuiteResult runSuite(const fs::path& file_path, const SuiteOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  SuiteResult result;
  const SuiteFile suite = readSuite(file_path, options);
  const std::string& file = suite.name;
  for (const std::string& name : options.update_views)
    if (std::none_of(suite.views.begin(), suite.views.end(), [&](const ViewEntry& v) { return v.name == name; }))
      throw InputError(file, "--update " + name + ": no view of that name");

  // Validation: every map used loads (once), every view resolves and fits its map, every golden
  // decodes at its view's size. Nothing is rendered or written before all of it passed.
  std::map<std::string, LoadedMap> loaded;
  for (const MapEntry& m : suite.maps) {
    std::error_code ec;
    if (!fs::exists(m.path, ec))
      throw InputError(file, m.line, "map '" + m.name + "': no such file or folder " + m.path.string());
    if (fs::is_directory(m.path, ec) && !fs::exists(m.path / "global_ellipsoids.ply", ec))
      throw InputError(file, m.line,
                       "map '" + m.name + "': " + m.path.string() +
                           " is not a `vdmap map` folder (a sequence? map it once with `vdmap map --save`)");
    const bool used =
        std::any_of(suite.views.begin(), suite.views.end(), [&](const ViewEntry& v) { return v.map == m.name; });
    if (!used) continue;  // named but not drawn: checked, not loaded
    const auto t0 = std::chrono::steady_clock::now();
    try {
      loaded[m.name].source = std::make_unique<RenderSource>(SequenceArgs{}, m.path.string(), "");
    } catch (const std::exception& e) {
      throw InputError(file, m.line, "map '" + m.name + "': " + errorMessage(e));
    }
    result.load_s += secondsSince(t0);
    ++result.maps_loaded;
  }
  std::vector<PreparedView> prepared;
  for (const ViewEntry& view : suite.views) {
    PreparedView p;
    p.entry = &view;
    p.map = &loaded.at(view.map);
    RenderSource& source = *p.map->source;
    try {
      p.resolved = resolveViewSpec(view.args, source.sessionThresholds());
      source.checkView(p.resolved.spec);
      std::tie(p.width, p.height) = source.imageSize(p.resolved.spec);
      if (p.resolved.spec.kind == render::ViewKind::kContainer && source.graph())
        keyframeImage(source.graph()->keyframe(p.resolved.spec.keyframe), source.name());  // lazy images: decode now
    } catch (const std::exception& e) {
      throw InputError(file, view.line, "view '" + view.name + "': " + errorMessage(e));
    }
    p.tolerance = resolveTolerance(view.tolerance, options, suite.tolerance);
    p.golden = suite.goldens / (view.name + ".png");
    p.update = options.update && (options.update_views.empty() ||
                                  std::count(options.update_views.begin(), options.update_views.end(), view.name));
    std::error_code exists_ec;
    if (fs::exists(p.golden, exists_ec) || (options.require_goldens && !p.update)) {
      try {
        p.golden_rgb = readGolden(p.golden.string(), cv::Size(p.width, p.height));
      } catch (const std::exception& e) {
        if (!p.update) throw InputError(file, view.line, "view '" + view.name + "': " + errorMessage(e));
      }
    }
    prepared.push_back(std::move(p));
  }
  std::error_code ec;
  fs::create_directories(suite.out, ec);
  if (ec) throw InputError(suite.out.string(), "cannot create the suite's out folder (" + ec.message() + ")");
  if (std::any_of(prepared.begin(), prepared.end(), [](const PreparedView& p) { return p.update; })) {
    fs::create_directories(suite.goldens, ec);
    if (ec) throw InputError(suite.goldens.string(), "cannot create the goldens folder (" + ec.message() + ")");
  }
  result.validate_s = secondsSince(start);

  auto t0 = std::chrono::steady_clock::now();
  sharedOffscreenGl();
  result.context_s = secondsSince(t0);

  SuiteReport report;
  report.name = file_path.filename().string();
  for (const PreparedView& p : prepared) {
    SuiteViewResult r;
    r.name = p.entry->name;
    r.map = p.entry->map;
    r.size = sizeText(p.width, p.height);
    RenderSource& source = *p.map->source;
    source.setQuerySlice(p.entry->query_slice);
    t0 = std::chrono::steady_clock::now();
    if (p.resolved.spec.kind != render::ViewKind::kContainer && source.graph())   // a map file's is read, not built
      p.map->global_maps.insert(source.globalMap(p.resolved.thresholds).data());  // one buffer per map built
    r.build_s = secondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    source.setMeshParams(p.resolved.mesh);
    const cv::Mat rgb = source.render(p.resolved.spec, p.resolved.thresholds);
    r.render_s = secondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    const fs::path actual = suite.out / (r.name + ".actual.png"), diff = suite.out / (r.name + ".diff.png");
    if (p.update) {
      r.updated = true;
      r.change = updateGolden(p, rgb);
    } else if (p.golden_rgb.empty()) {
      r.no_golden = true;
      r.passed = false;
    } else {
      r.comparison = checkRender(rgb, p.golden_rgb, p.golden.string(), p.tolerance, false, diff.string()).comparison;
      r.passed = r.comparison.matches;
    }
    if (r.passed) {
      removeIfThere(actual);  // a previous run's images of a view that passes now
      removeIfThere(diff);
    } else {
      render::writePng(actual, rgb);
    }
    r.check_s = secondsSince(t0);
    SuiteCase c;
    c.map = r.map;
    c.view = r.name;
    c.seconds = r.build_s + r.render_s + r.check_s;
    c.passed = r.passed;
    if (r.no_golden) {
      c.message = "no golden: " + shown(p.golden, suite.folder) + " (write it with --update " + r.name + ")";
      c.details = "actual: " + shown(actual, suite.folder) + "\n";
    } else if (!r.passed) {
      c.message = r.comparison.summary();
      c.details = "golden: " + shown(p.golden, suite.folder) + "\nactual: " + shown(actual, suite.folder) +
                  "\ndiff: " + shown(diff, suite.folder) + "\n";
    }
    report.cases.push_back(std::move(c));
    result.views.push_back(std::move(r));
  }
  for (const auto& [name, map] : loaded) result.global_maps_built += static_cast<int>(map.global_maps.size());
  result.orphans = orphanGoldens(suite.goldens, suite.views);
  result.total_s = secondsSince(start);
  report.seconds = result.total_s;
  writeJUnit(suite.out / "junit.xml", report);

  if (options.table) {
    std::size_t name_w = 4, map_w = 3;
    for (const SuiteViewResult& r : result.views) {
      name_w = std::max(name_w, r.name.size());
      map_w = std::max(map_w, r.map.size());
    }
    const int nw = static_cast<int>(name_w), mw = static_cast<int>(map_w);
    std::printf("%-*s | %-*s | %-9s | %12s | %7s | %5s | %-9s | %6s\n", nw, "view", mw, "map", "size", "differing px",
                "share", "worst", "result", "ms");
    for (const SuiteViewResult& r : result.views) {
      const std::string verdict = r.updated ? r.change : r.no_golden ? "NO GOLDEN" : r.passed ? "pass" : "DIFFERS";
      const double ms = 1e3 * (r.build_s + r.render_s + r.check_s);
      if (r.updated || r.no_golden)
        std::printf("%-*s | %-*s | %-9s | %12s | %7s | %5s | %-9s | %6.0f\n", nw, r.name.c_str(), mw, r.map.c_str(),
                    r.size.c_str(), "-", "-", "-", verdict.c_str(), ms);
      else
        std::printf("%-*s | %-*s | %-9s | %12ld | %6.2f%% | %5d | %-9s | %6.0f\n", nw, r.name.c_str(), mw,
                    r.map.c_str(), r.size.c_str(), r.comparison.differing, 100.0 * r.comparison.share,
                    r.comparison.worst, verdict.c_str(), ms);
    }
    std::string changed;
    for (const SuiteViewResult& r : result.views)
      if (r.change == "new" || r.change == "changed")
        changed += (changed.empty() ? "" : ", ") + r.name + " (" + r.change + ")";
    if (options.update) std::printf("goldens changed: %s\n", changed.empty() ? "none" : changed.c_str());
    if (!result.orphans.empty()) {
      std::string list;
      for (const std::string& o : result.orphans) list += (list.empty() ? "" : ", ") + o;
      std::printf("orphan goldens (no view of the suite names them) in %s: %s\n",
                  shown(suite.goldens, suite.folder).c_str(), list.c_str());
    }
    const int written = static_cast<int>(
        std::count_if(result.views.begin(), result.views.end(), [](const SuiteViewResult& r) { return r.updated; }));
    const int views = static_cast<int>(result.views.size());
    std::printf("%s: %d pass, %d differ, %s updated; maps loaded: %d, global maps built: %d; %.2f s; report %s\n",
                counted(views, "view").c_str(), views - result.failed() - written, result.failed(),
                counted(written, "golden").c_str(), result.maps_loaded, result.global_maps_built, result.total_s,
                shown(suite.out / "junit.xml", suite.folder).c_str());
  }
  if (options.timings) {
    std::vector<double> render_s, check_s;
    double build_s = 0;
    for (const SuiteViewResult& r : result.views) {
      render_s.push_back(r.render_s);
      check_s.push_back(r.check_s);
      build_s += r.build_s;
    }
    std::fprintf(stderr,
                 "vdmap render: note: timings: validate %.3f s (load %.3f s), context %.3f s, build %.3f s, "
                 "per view median render %.3f s, check %.3f s, total %.3f s\n",
                 result.validate_s, result.load_s, result.context_s, build_s, median(render_s), median(check_s),
                 result.total_s);
  }
  return result;
}

void runSuiteCommand(const std::string& file, const SuiteOptions& options) {
  const SuiteResult result = runSuite(file, options);
  if (result.failed() > 0) {
    std::string names;
    for (const SuiteViewResult& r : result.views)
      if (!r.passed) names += (names.empty() ? "" : ", ") + r.name + (r.no_golden ? " (no golden)" : "");
    throw ExitWith(2, file + ": " + std::to_string(result.failed()) + " of " + std::to_string(result.views.size()) +
                          " views differ from their goldens: " + names);
  }
}

bool runSuiteIfGiven(const CLI::App& verb, const RenderCheckArgs& args, const RenderViewArgs& view,
                     const std::string& out) {
  if (args.suite.empty()) return false;
  checkSuiteExcludes(verb);
  runSuiteCommand(
      args.suite,
      {.update = args.update,
       .tolerance = args.tolerance.empty() ? std::nullopt : std::optional(parseTolerance(args.tolerance)),
       .timings = args.timings,
       .update_views = args.update_views,
       .compare = args.compare.empty() ? std::nullopt : std::optional(render::parseCompareMethod(args.compare)),
       .out = out,
       .settings = view.settings,
       .set = view.set});
  return true;
}

void checkSuiteExcludes(const CLI::App& verb) {
  for (const CLI::Option* option : verb.get_options()) {
    if (option->count() == 0) continue;
    const std::string name = option->get_name();
    static const std::set<std::string> allowed = {"--suite",   "--update", "--tolerance", "--compare",
                                                  "--timings", "--out",    "--settings",  "--set"};
    if (allowed.count(name)) continue;
    throw CLI::ExcludesError("--suite", name);
  }
}

}  // namespace vdmap::app
