// TEMPORARY stand-in for engineer A's app/render_view.cpp (bodies of app/render_view.h), so that
// the suite can be built and tested before they land. Removed at the merge of view-core.
#include <filesystem>
#include <regex>

#include "app/render_view.h"
#include "mapping/core/error.h"
#include "render/colormap.h"
#include "render/container_renderer.h"
#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/map_scene.h"

namespace vdmap::app {

void addRenderViewOptions(CLI::App& verb, RenderViewArgs& args) {
  verb.add_option("--view", args.view);
  verb.add_option("--size", args.size);
  verb.add_option("--color", args.color)->check(parsedBy(render::parseColorMode, "MODE"));
  verb.add_option("--orbit", args.orbit);
  verb.add_option("--view-file", args.view_file);
  verb.add_option("--settings", args.settings);
  verb.add_flag("--grid", args.grid);
}

ResolvedView resolveViewSpec(const RenderViewArgs& args, const std::optional<GlobalMapParams>& thresholds) {
  ResolvedView r;
  std::smatch m;
  const std::string view = args.view.empty() ? "global" : args.view;
  static const std::regex vp(R"((global)|(keyframe|container):(\d{1,9}))");
  if (!std::regex_match(view, m, vp)) throw std::invalid_argument("--view " + view);
  if (!m[1].matched) {
    r.spec.kind = m[2] == "keyframe" ? render::ViewKind::kKeyframe : render::ViewKind::kContainer;
    r.spec.keyframe = std::stoi(m[3]);
  }
  if (!args.size.empty()) std::sscanf(args.size.c_str(), "%dx%d", &r.spec.width, &r.spec.height);
  if (!args.color.empty()) r.spec.color = render::parseColorMode(args.color);
  if (!args.orbit.empty()) {
    render::Orbit o;
    std::sscanf(args.orbit.c_str(), "%f,%f", &o.azimuth_deg, &o.elevation_deg);
    r.spec.orbit = o;
  }
  r.spec.layers.grid = args.grid;
  r.thresholds = thresholds ? *thresholds : GlobalMapParams{};
  r.settings_source = "defaults";
  return r;
}

struct RenderSource::Impl {
  std::optional<Session> session;
  std::vector<Ellipsoid> file_map;
  bool built = false;
  std::vector<Ellipsoid> global;
};

RenderSource::RenderSource(const SequenceArgs&, const std::string& map, const std::string&) : impl_(new Impl), name_(map) {
  namespace fs = std::filesystem;
  if (isSessionPath(map)) {
    impl_->session.emplace(loadSession(map, {.decode_images = false}));
  } else {
    throw InputError(map, "the stand-in renders sessions only");
  }
}
RenderSource::~RenderSource() = default;
const KeyframeGraph* RenderSource::graph() const { return impl_->session ? &impl_->session->graph : nullptr; }
std::optional<GlobalMapParams> RenderSource::sessionThresholds() const {
  return impl_->session ? std::optional(impl_->session->info.global) : std::nullopt;
}
int RenderSource::framesMapped() const { return impl_->session ? impl_->session->info.state.frames_mapped : 0; }
const std::vector<Ellipsoid>& RenderSource::globalMap(const GlobalMapParams& params) {
  if (!impl_->session) return impl_->file_map;
  if (!impl_->built) impl_->global = buildGlobalMap(impl_->session->graph, params).ellipsoids;
  impl_->built = true;
  return impl_->global;
}
glm::vec3 RenderSource::up(render::UpAxis, const GlobalMapParams&) { return {0.f, 0.f, 1.f}; }
void RenderSource::checkView(const render::ViewSpec& spec) const {
  if (spec.kind == render::ViewKind::kGlobal) return;
  const int n = graph() ? static_cast<int>(graph()->size()) : 0;
  if (spec.keyframe >= n) throw std::invalid_argument("--view: " + name_ + " has keyframes 0.." + std::to_string(n - 1));
}
std::pair<int, int> RenderSource::imageSize(const render::ViewSpec& spec) const {
  if (spec.width > 0) return {spec.width, spec.height};
  if (spec.kind == render::ViewKind::kGlobal) return {1280, 720};
  const PinholeCamera& c = impl_->session->info.camera;
  const int s = spec.kind == render::ViewKind::kContainer ? 2 : 1;
  return {s * c.width, s * c.height};
}
const render::Gl& sharedOffscreenGl() {
  static std::unique_ptr<render::Context> context = render::createOffscreenContext();
  return context->gl();
}
cv::Mat RenderSource::render(const render::ViewSpec& spec, const GlobalMapParams& params) {
  const render::Gl& gl = sharedOffscreenGl();
  const auto [w, h] = imageSize(spec);
  render::Framebuffer fb(gl, w, h);
  if (spec.kind == render::ViewKind::kContainer) {
    const Keyframe& k = impl_->session->graph.keyframe(spec.keyframe);
    render::ContainerRenderer container(gl);
    container.setKeyframe(keyframeImage(k, name_), impl_->session->info.camera, k.T_W_K);
    container.setEllipsoids(render::toInstances(keptEllipsoids(k.container, params.filter, k.T_W_K, k.id)),
                            {.sigma = spec.sigma, .color = spec.color,
                             .cell_size_px = impl_->session->info.mapper.local_map.cell_size_px, .show_grid = spec.layers.grid});
    fb.bindAndClear(0.f, 0.f, 0.f);
    container.draw(w, h);
    return fb.readRgb();
  }
  const auto instances = render::toInstances(globalMap(params));
  render::ViewCamera view;
  if (spec.kind == render::ViewKind::kKeyframe) {
    view = render::ViewCamera::fromPinhole(impl_->session->info.camera, impl_->session->graph.keyframe(spec.keyframe).T_W_K, w, h);
  } else {
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& e : instances) lo = glm::min(lo, e.mean), hi = glm::max(hi, e.mean);
    if (!(lo.x <= hi.x)) lo = glm::vec3(-1.f), hi = glm::vec3(1.f);
    render::OrbitCamera cam = render::OrbitCamera::framing(lo, hi, {0, 0, 1}, float(w) / float(h));
    if (spec.orbit) {
      cam.yaw = glm::radians(spec.orbit->azimuth_deg);
      cam.pitch = glm::radians(spec.orbit->elevation_deg);
    }
    view = cam.view(w, h);
  }
  fb.bindAndClear(spec.background.x, spec.background.y, spec.background.z);
  render::EllipsoidRenderer renderer(gl, {.sigma = spec.sigma, .color = spec.color, .sphere_subdivisions = spec.sphere_level,
                                          .point_below_px = spec.points_below_px});
  renderer.set(instances);
  renderer.draw(view);
  last_drawn_ = instances.size();
  return fb.readRgb();
}

}  // namespace vdmap::app
