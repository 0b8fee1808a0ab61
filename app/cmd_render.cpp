// vdmap render: maps a sequence (or reads a map and/or a mesh) and draws one view headless
// with OSMesa into a PNG.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "app/cli/command_line.h"
#include "app/cli/sequence_args.h"
#include "app/verbs.h"
#include "app/view/map_sequence.h"
#include "app/view/render_check.h"
#include "app/view/render_source.h"
#include "app/view/render_suite.h"
#include "app/view/render_view.h"
#include "app/view/view_file.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/files/ply_reader.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/image_codec.h"
#include "render/colormap.h"
#include "render/container_renderer.h"
#include "render/framebuffer.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"
#include "render/primitive_renderer.h"
#include "render/query_slice.h"

namespace vdmap::app {
namespace {

struct RenderArgs {
  SequenceArgs sequence;
  std::string map, mesh, out;
  RenderViewArgs view;
  RenderCheckArgs check;  // --expect, --tolerance, --diff, --update, --suite, --timings (app/view/render_check.h)
  std::optional<render::QuerySliceSpec> query_slice;  // --query-slice AXIS=VALUE, --query-slice-color
  render::QuerySliceColor query_slice_color = render::QuerySliceColor::kOccupancy;
};

// The image formats --out may name, by extension: PNG (lossless, what the goldens are) and JPEG.
enum class ImageFormat { kPng, kJpeg };

ImageFormat imageFormat(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".png") return ImageFormat::kPng;
  if (ext == ".jpg" || ext == ".jpeg") return ImageFormat::kJpeg;
  throw std::invalid_argument("'" + file.string() +
                              "': the image format follows the extension: .png, or .jpg / .jpeg for JPEG");
}

// Writes the image in the format its name says (atomically, as writePng does).
void writeImage(const std::filesystem::path& file, const cv::Mat& rgb) {
  if (imageFormat(file) == ImageFormat::kPng) return render::writePng(file, rgb);
  writeFileAtomically(file, encodeJpeg(rgb, 95));
}

void runRender(RenderArgs args) {
  // A missing option is a command-line error like map's: CLI11's message and exit code.
  checkRenderCheckArgs(args.check);
  if (!args.out.empty()) {  // checked here: with --suite --out is a folder
    try {
      imageFormat(args.out);
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--out", e.what());
    }
  }
  if (args.out.empty() && args.check.expect.empty()) throw CLI::RequiredError("--out");  // as every verb says it
  if (args.sequence.folder.empty() && args.map.empty() && args.mesh.empty())
    throw CLI::RequiredError("give SEQ, --map (an ellipsoid PLY, a `vdmap map` folder or a .vdmap session), "
                             "--mesh PLY, or --map and --mesh",
                             CLI::ExitCodes::RequiredError);
  if (!args.out.empty()) checkOutputFile(args.out, "--out");
  for (const auto& [option, file] :
       {std::pair<const char*, std::string>{"--out", args.out}, {"--diff", args.check.diff}})
    checkNotAnInput(file, option,
                    {{"SEQ", args.sequence.folder},
                     {"--map", args.map},
                     {"--mesh", args.mesh},
                     {"--view-file", args.view.view_file},
                     {"--settings", args.view.settings},
                     {"--expect", args.check.update ? "" : args.check.expect}});
  StageTimes times(args.check.timings);
  // The golden decodes before any work; its size is checked once the view's is known.
  const cv::Mat golden = args.check.expect.empty() || args.check.update ? cv::Mat() : readGolden(args.check.expect);
  // The view first (a bad view file or --settings costs no loading), then the context (a missing
  // OSMesa should not cost a mapping run), then the source.
  const bool session_given = (!args.map.empty() && isSessionPath(args.map)) ||
                             (!args.sequence.folder.empty() && isSessionPath(args.sequence.folder));
  const bool keyframes_given = session_given || !args.sequence.folder.empty();
  ResolvedView view = resolveViewSpec(args.view, std::nullopt);
  const std::string& drawn = args.map.empty() ? args.sequence.folder : args.map;
  if (session_given || isStaticMapFile(drawn)) gui::refuseRemapSettings(args.view.set, drawn);
  if (!keyframes_given && view.spec.kind != render::ViewKind::kGlobal)
    throw std::invalid_argument("--view " + viewName(view.spec) +
                                " needs keyframes: give a sequence (SEQ) or a session (.vdmap); a --map PLY or map "
                                "folder has none");
  sharedOffscreenGl();
  times.mark("context");
  RenderSource source(args.sequence, args.map, args.mesh, view.mapper);
  times.mark("load");
  if (args.query_slice) {  // the point queries' slice plane (docs/workbench.md "Queries")
    render::QuerySliceSpec slice = *args.query_slice;
    slice.color = args.query_slice_color;
    source.setQuerySlice(slice);
  }
  // The session's own thresholds (as the workbench showed them when it was saved) come under
  // --settings, --view-file and the flags.
  if (const auto thresholds = source.sessionThresholds()) view = resolveViewSpec(args.view, thresholds);
  source.checkView(view.spec);
  if (const auto [w, h] = source.imageSize(view.spec); !golden.empty())
    checkGoldenSize(args.check.expect, golden.size(), {w, h});
  if (args.check.timings && view.spec.kind != render::ViewKind::kContainer) source.globalMap(view.thresholds);
  times.mark("build");
  source.setMeshParams(view.mesh);
  const cv::Mat image = source.render(view.spec, view.thresholds);
  times.mark("render");
  if (!args.out.empty()) writeImage(args.out, image);
  // After the work, so that bad input stays one error line.
  std::fprintf(stderr, "vdmap render: note: settings: %s\n", view.settings_source.c_str());
  const glm::vec3 up = source.lastUp();
  // A map file without cameras stands on its level planes: say so, since a wrong guess draws the
  // map on its side.
  if (view.spec.kind != render::ViewKind::kContainer && !view.spec.look_at && source.lastUpFrom())
    if (const render::UpFrom from = *source.lastUpFrom(); from != render::UpFrom::kCameras)
      std::fprintf(stderr, "vdmap render: note: up (%.2f, %.2f, %.2f) %s; --up sets it\n", up.x, up.y, up.z,
                   from == render::UpFrom::kLevelPlanes
                       ? "estimated from the map's level planes and walls (it has no cameras)"
                       : "is +z: the map has no cameras and too few flat patches to estimate it");
  std::printf("%s (%dx%d, view %s, %s, %s", args.out.empty() ? "rendered" : ("wrote " + args.out).c_str(), image.cols,
              image.rows, viewName(view.spec).c_str(),
              counted(static_cast<long long>(source.lastDrawn()), "ellipsoid").c_str(),
              counted(static_cast<long long>(source.meshTriangles()), "triangle").c_str());
  if (const KeyframeGraph* graph = source.graph())
    std::printf(", %s, %s, %s", counted(source.framesMapped(), "frame").c_str(),
                counted(static_cast<long long>(graph->size()), "keyframe").c_str(),
                counted(static_cast<long long>(graph->edges().size()), "edge").c_str());
  // The container view is drawn in the keyframe's image: no up axis.
  if (view.spec.kind != render::ViewKind::kContainer) std::printf(", up (%.2f, %.2f, %.2f)", up.x, up.y, up.z);
  std::printf(")\n");
  if (const render::QuerySliceImage* slice = source.lastQuerySlice())
    std::printf("query slice %s=%.3f (%s): %dx%d samples, %zu occupied, %zu free, %zu unknown, %.0f ms\n",
                render::querySliceAxisName(slice->spec.axis), slice->spec.offset_m,
                render::querySliceColorName(slice->spec.color), slice->plane.width, slice->plane.height,
                slice->occupied, slice->free, slice->unknown, slice->compute_ms);
  finishRenderCheck(args.check, golden, image, &times);  // --timings printed, --expect checked
}

}  // namespace

void addRenderCommand(CLI::App& app) {
  auto* verb = app.add_subcommand(
      "render", "Render a view of a session, a map or a sequence (mapped first) headless to PNG with OSMesa");
  auto args = std::make_shared<RenderArgs>();
  addSequenceArgs(*verb, args->sequence);
  addPoseSourceArg(*verb, args->sequence);
  addRefineArg(*verb, args->sequence);
  CLI::Option* seq = verb->get_option("SEQ")->required(false)->description(
      "sequence to map (default parameters) and render, or a saved session (.vdmap) or map file to render "
      "without mapping");
  verb->add_option("--map", args->map,
                   "instead of SEQ: a saved session (.vdmap: every view, with its keyframes and graph), or a map "
                   "file (global view only): a `vdmap map` folder, an ellipsoid PLY (docs/method.md 11), a point PLY, "
                   "an OctoMap .bt/.ot")
      ->excludes(seq);
  verb->add_option("--mesh", args->mesh, "triangle mesh PLY with vertex colours, drawn shaded");
  verb->add_option("--out", args->out,
                   "image to write: PNG (.png) or JPEG (.jpg, .jpeg), as its extension says; with --suite: the "
                   "folder of the report and the failing views' images");
  addRenderViewOptions(*verb, args->view);
  addRenderCheckArgs(*verb, args->check);
  // The point queries' slice plane (docs/workbench.md "Queries"); not the height slice (--slice LO:HI).
  verb->add_option_function<std::string>(
          "--query-slice", [args](const std::string& text) { args->query_slice = render::parseQuerySlice(text); },
          "draw the query slice: a plane across AXIS (up: VALUE m above the floor; x, y, z: at that world coordinate), "
          "coloured by what the map answers there (free, occupied, unknown), e.g. up=1.0")
      ->check(parsedBy(render::parseQuerySlice, "AXIS=VALUE"));
  verb->add_option_function<std::string>(
          "--query-slice-color",
          [args](const std::string& text) { args->query_slice_color = render::parseQuerySliceColor(text); },
          "the query slice's colours: occupancy (free green, occupied red, unknown grey; default) or distance (to "
          "the nearest surface, viridis to 0.5 m; unknown grey)")
      ->check(parsedBy(render::parseQuerySliceColor, "occupancy|distance"));
  verb->callback([args, verb] {
    if (!runSuiteIfGiven(*verb, args->check, args->view, args->out))
      runRender(*args);  // --suite: many views (app/view/render_suite.h)
  });
}

}  // namespace vdmap::app
