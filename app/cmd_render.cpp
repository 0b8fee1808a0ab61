// vdmap render: maps a sequence (or reads a map and/or a mesh) and draws one view headless
// with OSMesa into a PNG, or times the ellipsoid renderer (--bench-ellipsoids).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <regex>

#include <glm/gtc/matrix_transform.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/commands.h"
#include "app/map_sequence.h"
#include "app/render_check.h"
#include "app/render_suite.h"
#include "app/timing.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "mapping/global_map/global_map.h"
#include "mapping/core/error.h"
#include "mapping/io/ply_reader.h"
#include "mapping/pipeline/session_file.h"
#include "render/colormap.h"
#include "render/container_renderer.h"
#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"
#include "render/primitive_renderer.h"

namespace vdmap::app {
namespace {

struct RenderArgs {
  SequenceArgs sequence;
  std::string map, mesh, view = "global", out, size, color = "rgb";
  float sigma = 2.f;
  float point_below_px = render::EllipsoidStyle{}.point_below_px;
  bool grid = false;
  int bench_ellipsoids = 0;
  int sphere_subdivisions = 1;
  RenderCheckArgs check;  // --expect, --tolerance, --diff, --update, --timings (app/render_check.h)
};

std::pair<int, int> parseSize(const std::string& text) {
  std::smatch m;
  static const std::regex pattern(R"((\d{1,9})x(\d{1,9}))");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("'" + text + "': expected WIDTHxHEIGHT, e.g. 1280x720");
  const int w = std::stoi(m[1]), h = std::stoi(m[2]);
  if (w < 1 || h < 1 || w > render::kMaxImageSide || h > render::kMaxImageSide)
    throw std::invalid_argument("'" + text + "': each side must be in 1.." + std::to_string(render::kMaxImageSide));
  return {w, h};
}

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
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<unsigned char> jpeg;
  if (!cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}))
    throw std::runtime_error(file.string() + ": cannot encode the JPEG");
  writeFileAtomically(file, std::string_view(reinterpret_cast<const char*>(jpeg.data()), jpeg.size()));
}

void runBench(const RenderArgs& args) {
  const auto [w, h] = parseSize(args.size.empty() ? "1280x720" : args.size);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-5.f, 5.f), size(0.005f, 0.04f), angle(0.f, 6.2832f);
  std::vector<render::EllipsoidInstance> set(static_cast<std::size_t>(args.bench_ellipsoids));
  for (auto& e : set) {
    e.mean = {pos(rng), pos(rng), pos(rng)};
    const glm::mat3 R = glm::mat3(glm::rotate(glm::mat4(1.f), angle(rng), glm::normalize(glm::vec3(pos(rng), pos(rng), pos(rng)) + 1e-3f)));
    const glm::vec3 s(size(rng), size(rng), size(rng) * 0.3f);
    e.cov = R * glm::mat3(s.x * s.x, 0, 0, 0, s.y * s.y, 0, 0, 0, s.z * s.z) * glm::transpose(R);
    e.rgb = {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng())};
  }
  auto context = render::createOffscreenContext();
  const render::Gl& gl = context->gl();
  render::Framebuffer fb(gl, w, h);
  render::EllipsoidRenderer renderer(gl, {.sigma = args.sigma, .sphere_subdivisions = args.sphere_subdivisions,
                                         .point_below_px = args.point_below_px});
  auto t0 = std::chrono::steady_clock::now();
  renderer.set(set);
  gl.Finish();
  const double upload_ms = msSince(t0);
  std::vector<double> times;
  for (int i = 0; i < 5; ++i) {
    // The eye moves 1 mm per frame, as in an interactive view: an unchanged view would let the
    // renderer reuse its mesh-pass selection and time less than a real frame.
    const render::ViewCamera view =
        render::ViewCamera::lookAt({12.f + 0.001f * i, -9.f, 7.f}, {0.f, 0.f, 0.f}, {0, 0, 1}, 60.f, w, h);
    t0 = std::chrono::steady_clock::now();
    fb.bindAndClear(1.f, 1.f, 1.f);
    renderer.draw(view);
    gl.Finish();
    times.push_back(msSince(t0));
  }
  std::printf("renderer     %s\n", context->description().c_str());
  std::printf("ellipsoids   %d instanced, icosphere level %d, points below %.1f px, %dx%d\n", args.bench_ellipsoids,
              args.sphere_subdivisions, args.point_below_px, w, h);
  std::printf("upload       %.1f ms (eigen-decomposition + buffer upload)\n", upload_ms);
  std::printf("frame time   %.1f ms median of %zu frames (min %.1f ms)\n", median(times), times.size(),
              *std::min_element(times.begin(), times.end()));
  if (!args.out.empty()) writeImage(args.out, fb.readRgb());
}

// --view: global, keyframe:K or container:K.
struct ViewChoice {
  enum class Kind { kGlobal, kKeyframe, kContainer } kind = Kind::kGlobal;
  int keyframe = -1;
};

ViewChoice parseView(const std::string& text) {
  std::smatch m;
  static const std::regex pattern(R"((global)|(keyframe|container):(\d{1,9}))");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("'" + text + "': expected global, keyframe:K or container:K");
  if (m[1].matched) return {};
  return {m[2] == "keyframe" ? ViewChoice::Kind::kKeyframe : ViewChoice::Kind::kContainer, std::stoi(m[3])};
}

// What one `vdmap render` draws: ellipsoids (a map file or the global map of a sequence), an
// optional mesh, the keyframe graph's lines, and for keyframe/container views the keyframe.
struct RenderScene {
  std::vector<render::EllipsoidInstance> ellipsoids;
  ColoredTriangleMesh mesh;
  render::ColoredLines lines;
  const Keyframe* keyframe = nullptr;
  PinholeCamera camera;
  std::vector<render::EllipsoidInstance> container_ellipsoids;  // K's own kept ellipsoids
  int cell_size_px = 5;
};

// The whole scene: exact bounds of every ellipsoid (its mean +- sigma along the axes), mesh
// vertex and graph line, so nothing at the edges is cut (a percentile box cropped the map).
render::ViewCamera globalView(const RenderScene& scene, float sigma, int w, int h) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  const auto add = [&](const glm::vec3& p, const glm::vec3& r) {
    lo = glm::min(lo, p - r);
    hi = glm::max(hi, p + r);
  };
  for (const auto& e : scene.ellipsoids)
    add(e.mean, sigma * glm::sqrt(glm::max(glm::vec3(e.cov[0][0], e.cov[1][1], e.cov[2][2]), glm::vec3(0.f))));
  for (const auto& p : scene.mesh.positions) add({p.x(), p.y(), p.z()}, glm::vec3(0.f));
  for (const auto& p : scene.lines.positions) add(p, glm::vec3(0.f));
  if (!(lo.x <= hi.x)) lo = glm::vec3(-1.f), hi = glm::vec3(1.f);  // nothing to frame
  return render::OrbitCamera::framing(lo, hi).view(w, h);
}

cv::Mat draw(const render::Gl& gl, const RenderScene& scene, const ViewChoice& choice, int w, int h,
             const RenderArgs& args, render::ColorMode color) {
  render::Framebuffer fb(gl, w, h);
  if (choice.kind == ViewChoice::Kind::kContainer) {
    render::ContainerRenderer container(gl);
    container.setKeyframe(scene.keyframe->rgb(), scene.camera, scene.keyframe->T_W_K);
    container.setEllipsoids(scene.container_ellipsoids, {.sigma = args.sigma, .color = color,
                                                         .cell_size_px = scene.cell_size_px, .show_grid = args.grid});
    fb.bindAndClear(0.f, 0.f, 0.f);
    container.draw(w, h);
    return fb.readRgb();
  }
  const render::ViewCamera view = choice.kind == ViewChoice::Kind::kKeyframe
                                      ? render::ViewCamera::fromPinhole(scene.camera, scene.keyframe->T_W_K, w, h)
                                      : globalView(scene, args.sigma, w, h);
  fb.bindAndClear(1.f, 1.f, 1.f);
  if (!scene.mesh.triangles.empty()) {
    render::MeshRenderer mesh_renderer(gl);
    mesh_renderer.set(render::toColoredMesh(scene.mesh));
    mesh_renderer.draw(view);
  }
  if (!scene.ellipsoids.empty()) {
    render::EllipsoidRenderer renderer(gl, {.sigma = args.sigma, .color = color,
                                             .sphere_subdivisions = args.sphere_subdivisions,
                                             .point_below_px = args.point_below_px});
    renderer.set(scene.ellipsoids);
    renderer.draw(view);
  }
  if (!scene.lines.positions.empty()) {
    render::LineRenderer lines(gl);
    lines.set(scene.lines);
    lines.setWidth(2.f);
    lines.draw(view);
  }
  return fb.readRgb();
}

// What the scene was made from, for the summary line.
struct SceneSource {
  std::string name;  ///< the sequence folder or the session file (keyframe range errors name it)
  int frames = 0;
  const KeyframeGraph* graph = nullptr;
};

// The views of a keyframe graph (mapped from a sequence or loaded from a session): the global
// map with the graph's lines, or keyframe K's view or container.
void addGraph(RenderScene* scene, const KeyframeGraph& graph, const PinholeCamera& camera, int cell_size_px,
              const GlobalMapParams& global_params, const ViewChoice& choice, const std::string& source,
              const std::string& view_text) {
  scene->camera = camera;
  scene->cell_size_px = cell_size_px;
  if (choice.kind == ViewChoice::Kind::kContainer || choice.kind == ViewChoice::Kind::kKeyframe) {
    if (choice.keyframe >= static_cast<int>(graph.size()))
      throw std::invalid_argument("--view " + view_text + ": " + source +
                                  (graph.size() == 0 ? std::string(" has no keyframe")
                                                     : " has keyframes 0.." + std::to_string(graph.size() - 1)));
    scene->keyframe = &graph.keyframe(choice.keyframe);
  }
  if (choice.kind == ViewChoice::Kind::kContainer) {
    scene->container_ellipsoids = render::toInstances(
        keptEllipsoids(scene->keyframe->container, global_params.filter, scene->keyframe->T_W_K, scene->keyframe->id));
  } else {
    scene->ellipsoids = render::toInstances(buildGlobalMap(graph, global_params).ellipsoids);
  }
  // Frustums at 10% of the scene's extent would need the bounds first; 0.15 m reads well for
  // rooms (the data vdmap is made for). Only the global view draws the graph.
  if (choice.kind == ViewChoice::Kind::kGlobal) scene->lines = render::keyframeGraphLines(graph, camera, 0.15f);
}

void runRender(RenderArgs args) {
  namespace fs = std::filesystem;
  if (args.bench_ellipsoids > 0) return runBench(args);
  // A missing option is a command-line error like map's: CLI11's message and exit code.
  checkRenderCheckArgs(args.check);
  if (args.out.empty() && args.check.expect.empty()) throw CLI::RequiredError("--out (or --expect GOLDEN.png)");
  if (args.sequence.folder.empty() && args.map.empty() && args.mesh.empty())
    throw CLI::RequiredError("give SEQ, --map (an ellipsoid PLY, a `vdmap map` folder or a .vdmap session), "
                             "--mesh PLY, or --map and --mesh", CLI::ExitCodes::RequiredError);
  if (!args.out.empty()) checkOutputFile(args.out, "--out");
  StageTimes times(args.check.timings);
  // The golden decodes before any work; its size is checked once the view's is known.
  const cv::Mat golden = args.check.expect.empty() || args.check.update ? cv::Mat() : readGolden(args.check.expect);
  // A saved session can stand where SEQ does (as for vdmap gui) or be given as --map (SEQ and
  // --map exclude each other).
  if (!args.sequence.folder.empty() && isSessionPath(args.sequence.folder)) std::swap(args.map, args.sequence.folder);
  const bool from_sequence = !args.sequence.folder.empty();
  const bool from_session = !args.map.empty() && isSessionPath(args.map);
  const ViewChoice choice = parseView(args.view);
  if (!from_sequence && !from_session && choice.kind != ViewChoice::Kind::kGlobal)
    throw std::invalid_argument("--view " + args.view +
                                " needs keyframes: give a sequence (SEQ) or a session (.vdmap); a --map PLY or map "
                                "folder has none");
  const std::pair<int, int> size = args.size.empty() ? std::pair{0, 0} : parseSize(args.size);  // 0: default
  const render::ColorMode color = render::parseColorMode(args.color);

  RenderScene scene;
  std::optional<Session> session;
  if (from_session) {
    session.emplace(loadSession(args.map, {.decode_images = false}));  // container:K decodes K's image
  } else if (!args.map.empty()) {
    // A `vdmap map` folder is drawn by its global map.
    const fs::path ply = fs::is_directory(args.map) ? fs::path(args.map) / "global_ellipsoids.ply" : fs::path(args.map);
    if (fs::is_directory(args.map) && !fs::exists(ply))
      throw InputError(args.map, "has no global_ellipsoids.ply (expected a `vdmap map` output folder)");
    scene.ellipsoids = render::toInstances(readPlyEllipsoids(ply));
  }
  if (!args.mesh.empty()) scene.mesh = readPlyMesh(args.mesh);
  // The context comes before the mapping: a missing OSMesa should not cost a mapping run.
  times.mark("load");
  auto context = render::createOffscreenContext();
  times.mark("context");
  std::unique_ptr<Mapper> mapper;
  SceneSource source;
  if (from_sequence) {
    const TumSequence seq = openSequence(args.sequence);
    noteCameraGuess(seq, "render");
    MapperParams params;
    params.poses = poseSource(args.sequence, seq);
    checkRefinementApplies(args.sequence, params.poses);
    mapper = std::make_unique<Mapper>(seq.camera(), params);
    mapSequence(seq, *mapper, {}, refinement(args.sequence));
    addGraph(&scene, mapper->graph(), seq.camera(), mapper->params().local_map.cell_size_px, GlobalMapParams{},
             choice, seq.folder().string(), args.view);
    source = {seq.folder().string(), mapper->framesMapped(), &mapper->graph()};
  } else if (session) {
    // The session's own live thresholds, as the workbench showed them when it was saved.
    addGraph(&scene, session->graph, session->info.camera, session->info.mapper.local_map.cell_size_px,
             session->info.global, choice, args.map, args.view);
    source = {args.map, session->info.state.frames_mapped, &session->graph};
    if (scene.keyframe && choice.kind == ViewChoice::Kind::kContainer) keyframeImage(*scene.keyframe, args.map);
  }
  times.mark("build");

  // Default sizes: the keyframe's own image for keyframe:K, the whole 2W x 2H container for
  // container:K, 1280x720 for the global view.
  auto [w, h] = size;
  if (w == 0) {
    const int scale = choice.kind == ViewChoice::Kind::kContainer ? 2 : 1;
    std::tie(w, h) = choice.kind == ViewChoice::Kind::kGlobal
                         ? std::pair{1280, 720}
                         : std::pair{scale * scene.camera.width, scale * scene.camera.height};
  }
  if (!golden.empty()) checkGoldenSize(args.check.expect, golden.size(), {w, h});
  const cv::Mat rgb = draw(context->gl(), scene, choice, w, h, args, color);
  times.mark("render");
  if (!args.out.empty()) writeImage(args.out, rgb);
  const std::size_t drawn =
      choice.kind == ViewChoice::Kind::kContainer ? scene.container_ellipsoids.size() : scene.ellipsoids.size();
  std::printf("%s (%dx%d, view %s, %s, %s", args.out.empty() ? "rendered" : ("wrote " + args.out).c_str(), w, h, args.view.c_str(),
              counted(static_cast<long long>(drawn), "ellipsoid").c_str(),
              counted(static_cast<long long>(scene.mesh.triangles.size()), "triangle").c_str());
  if (source.graph)
    std::printf(", %s, %s, %s", counted(source.frames, "frame").c_str(),
                counted(static_cast<long long>(source.graph->size()), "keyframe").c_str(),
                counted(static_cast<long long>(source.graph->edges().size()), "edge").c_str());
  std::printf(")\n");
  finishRenderCheck(args.check, golden, rgb, &times);  // --timings printed, --expect checked
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
      "sequence to map (default parameters) and render, or a saved session (.vdmap) to render without mapping");
  verb->add_option("--map", args->map,
                   "instead of SEQ: a saved session (.vdmap: every view, with its keyframes and graph), or an "
                   "ellipsoid PLY (docs/method.md 11) or `vdmap map` folder (its global_ellipsoids.ply; global view only)")
      ->excludes(seq);
  verb->add_option("--mesh", args->mesh, "triangle mesh PLY with vertex colours, drawn shaded");
  verb->add_option("--view", args->view,
                   "global (map, frustums, covisibility edges coloured by weight) | keyframe:K (the map from "
                   "keyframe K with its intrinsics) | container:K (K's image with its ellipses)")
      ->check(parsedBy(parseView, "VIEW"))
      ->capture_default_str();
  verb->add_option("--out", args->out, "image to write: PNG (.png) or JPEG (.jpg, .jpeg), as its extension says")
      ->check(parsedBy(imageFormat, "FILE.png|.jpg"));
  verb->add_option("--size", args->size,
                   "image size WIDTHxHEIGHT (default: 1280x720 global, the camera's for keyframe:K, the "
                   "container's 2W x 2H for container:K)")
      ->check(parsedBy(parseSize, "WxH"));
  std::string color_modes;  // "rgb | keyframe | ..."
  for (const char* name : render::kColorModeNames) color_modes += (color_modes.empty() ? "" : " | ") + std::string(name);
  verb->add_option("--color", args->color, color_modes)
      ->check(parsedBy(render::parseColorMode, "MODE"))
      ->capture_default_str();
  verb->add_flag("--grid", args->grid, "container view: draw the cell grid");
  verb->add_option("--sigma", args->sigma, "ellipsoid surface at this many standard deviations (> 0)")
      ->check(positiveFiniteCheck())
      ->capture_default_str();
  verb->add_option("--bench-ellipsoids", args->bench_ellipsoids,
                   "time N random instanced ellipsoids at --size instead of rendering a map")
      ->check(CLI::Range(0, std::numeric_limits<int>::max()));
  verb->add_option("--sphere-level", args->sphere_subdivisions, "icosphere subdivisions of one ellipsoid (0..3)")
      ->check(CLI::Range(0, 3))->capture_default_str();
  verb->add_option("--points-below", args->point_below_px,
                   "draw ellipsoids projecting to a radius below this many pixels as flat splats (0: never)")
      ->check(CLI::Range(0.f, 64.f))->capture_default_str();
  addRenderCheckArgs(*verb, args->check);
  verb->callback([args, verb] {
    if (!runSuiteIfGiven(*verb, args->check)) runRender(*args);  // --suite: many views (app/render_suite.h)
  });
}

}  // namespace vdmap::app
