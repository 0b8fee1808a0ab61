#include "app/gui/workbench_window.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <tuple>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_stdlib.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Eigenvalues>

#include "app/gui/glfw_context.h"
#include "app/timing.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "render/colormap.h"
#include "render/container_renderer.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/map_scene.h"
#include "render/primitive_renderer.h"
#include "render/scene_lines.h"

namespace vdmap::app::gui {
namespace {

using Clock = std::chrono::steady_clock;
constexpr float kLeftWidth = 370.f, kRightWidth = 410.f;
constexpr float kBackground[3] = {0.13f, 0.13f, 0.15f};
// Icosahedra (20 triangles) rather than level-1 spheres (80): at 2 sigma an ellipsoid covers a
// few pixels, and with a software renderer (llvmpipe) the view's frame time is 4x lower.
constexpr render::EllipsoidStyle kEllipsoidStyle{.sphere_subdivisions = 0};

// Raw depth as a colour image: viridis over 0..6 m, black where there is no measurement.
cv::Mat depthToRgb(const cv::Mat& depth, double depth_scale) {
  cv::Mat d8, bgr, rgb;
  depth.convertTo(d8, CV_8U, 255.0 / (6.0 * depth_scale));
  cv::applyColorMap(d8, bgr, cv::COLORMAP_VIRIDIS);
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  rgb.setTo(cv::Scalar::all(0), depth == 0);
  return rgb;
}

// An RGB image (CV_8UC3) as a texture ImGui can show.
class ImageTexture {
 public:
  explicit ImageTexture(const render::Gl& gl) : gl_(&gl) { gl.GenTextures(1, &id_); }
  ~ImageTexture() { gl_->DeleteTextures(1, &id_); }
  ImageTexture(const ImageTexture&) = delete;
  ImageTexture& operator=(const ImageTexture&) = delete;

  void set(const cv::Mat& rgb) {
    if (rgb.empty()) return;
    const cv::Mat image = rgb.isContinuous() ? rgb : rgb.clone();
    gl_->BindTexture(GL_TEXTURE_2D, id_);
    gl_->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl_->TexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.cols, image.rows, 0, GL_RGB, GL_UNSIGNED_BYTE, image.data);
    gl_->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl_->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl_->BindTexture(GL_TEXTURE_2D, 0);
    width_ = image.cols;
    height_ = image.rows;
  }
  void show(float width) const {
    if (width_ == 0) return;
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(id_)),
                 ImVec2(width, width * static_cast<float>(height_) / static_cast<float>(width_)));
  }

 private:
  const render::Gl* gl_;
  GLuint id_ = 0;
  int width_ = 0, height_ = 0;
};

// Slider/drag over a double with a float-like format.
bool editDouble(const char* label, double& value, double lo, double hi, const char* format = "%.3f") {
  return ImGui::SliderScalar(label, ImGuiDataType_Double, &value, &lo, &hi, format);
}

class WorkbenchWindow {
 public:
  WorkbenchWindow(Workbench& bench, GlfwWindowContext& context, const ScriptOptions& script)
      : bench_(bench), context_(context), gl_(context.gl()), script_(script), ellipsoids_(gl_, kEllipsoidStyle), points_(gl_),
        lines_(gl_), rgb_(gl_), depth_(gl_), container_(gl_) {
    lines_.setWidth(1.5f);
    if (script_.play_to_end && bench_.session()) bench_.session()->play();
    if (script_.keyframe >= 0 && bench_.session()) {  // selected before it is mapped, unlike Workbench::selectKeyframe
      bench_.ui().selected_keyframe = script_.keyframe;
      bench_.session()->selectKeyframe(script_.keyframe);
    }
  }

  // One UI frame; returns false when the window should close.
  bool frame() {
    glfwPollEvents();
    const auto t0 = Clock::now();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    glfwGetFramebufferSize(context_.window(), &fb_width_, &fb_height_);
    syncScene();
    drawSequencePanel();
    drawMapPanel();
    drawBanners();
    handleMouse();
    bench_.ui().reset_layout = false;
    ImGui::Render();
    drawScene();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    advanceScript();
    if (!screenshot_request_.empty()) {
      saveScreenshot(screenshot_request_);
      screenshot_request_.clear();
    }
    const double ms = msSince(t0);
    if (bench_.session() && bench_.session()->status().busy) busy_frame_ms_.push_back(ms);
    glfwSwapBuffers(context_.window());
    return !glfwWindowShouldClose(context_.window()) && !script_finished_;
  }

  // Scripted runs (--exit) fail on an error still shown; a user closing the window never does.
  int exitCode() const { return script_.exit && !bench_.ui().error.empty() ? 1 : 0; }

 private:
  UiState& ui() { return bench_.ui(); }

  // Mirrors the session's newest snapshots into GPU buffers (only what changed).
  void syncScene() {
    MapSession* session = bench_.session();
    if (!session) return;
    bench_.syncPoseFields();
    if (session != shown_session_) {  // a newly opened sequence: everything shown is stale
      shown_session_ = session;
      shown_mapping_ = nullptr;
      shown_lines_ = {};
      shown_generation_ = -1;
      shown_selection_ = nullptr;
    }
    mapping_ = session->mapping();
    global_ = session->global();
    if (mapping_.get() != shown_mapping_) {
      shown_mapping_ = mapping_.get();
      rgb_.set(mapping_->rgb);
      if (!mapping_->depth.empty()) depth_.set(depthToRgb(mapping_->depth, mapping_->camera.depth_scale));
    }
    const Settings& s = ui().settings;
    ellipsoids_.setStyle({.sigma = s.ellipsoid_sigma, .color = s.color});
    const int generation = global_ ? global_->generation : 0;
    if (generation != shown_generation_) {  // a new global map: new geometry
      instances_ = global_ ? render::toInstances(global_->map.ellipsoids) : std::vector<render::EllipsoidInstance>{};
      ellipsoids_.set(instances_);
      points_.set(instances_, s.color);
      shown_generation_ = generation;
      shown_color_ = s.color;
      if (global_ && !global_->map.ellipsoids.empty() && !ui().camera_framed) bench_.resetView();
    } else if (s.color != shown_color_) {  // only the colours: setStyle above re-colours the ellipsoids
      points_.set(instances_, s.color);
      shown_color_ = s.color;
    }
    const auto selection = session->selection();
    if (selection && (selection != shown_selection_ || s.color != container_color_)) updateContainerView(selection);
    const LinesKey lines_key{mapping_.get(), ui().selected_keyframe, s.show_frustums, s.show_graph, s.show_trajectory};
    if (lines_key == shown_lines_) return;
    shown_lines_ = lines_key;
    render::ColoredLines lines;
    std::vector<Transform> poses;
    for (const KeyframeInfo& k : mapping_->keyframes) {
      poses.push_back(k.T_W_K);
      if (!s.show_frustums) continue;
      const glm::u8vec3 color = k.id == ui().selected_keyframe ? glm::u8vec3(255, 255, 255)
                                : k.id == mapping_->current_keyframe ? glm::u8vec3(255, 220, 0)
                                                                     : render::keyframeColor(k.id);
      render::addFrustum(lines, mapping_->camera, k.T_W_K, 0.25f, color);
    }
    if (s.show_graph) {
      std::vector<render::GraphEdge> edges;
      for (const CovisibilityEdge& e : mapping_->edges) edges.push_back({e.a, e.b, static_cast<float>(e.weight)});
      render::addEdges(lines, poses, edges);
    }
    if (s.show_trajectory) render::addTrajectory(lines, mapping_->trajectory, {90, 200, 255});
    if (!mapping_->trajectory.empty())
      render::addFrustum(lines, mapping_->camera, mapping_->trajectory.back(), 0.15f, {255, 60, 60});
    lines_.set(lines);
  }

  // Draws the selected keyframe's image plane with its local map (the session's selection, which
  // follows ui().selected_keyframe a moment later).
  void updateContainerView(std::shared_ptr<const SelectionSnapshot> selection) {
    const int id = selection->keyframe;
    if (id >= static_cast<int>(mapping_->keyframes.size())) return;  // not in this mapping snapshot yet
    shown_selection_ = std::move(selection);
    container_color_ = ui().settings.color;
    if (id < 0) return;
    const KeyframeInfo& k = mapping_->keyframes[static_cast<std::size_t>(id)];
    container_.setKeyframe(k.rgb.decode(), mapping_->camera, k.T_W_K);
    container_.setEllipsoids(render::toInstances(shown_selection_->local), {.sigma = 2.f, .color = ui().settings.color});
    if (!container_fb_) container_fb_ = std::make_unique<render::Framebuffer>(gl_, container_.containerWidth(), container_.containerHeight());
    container_fb_->bindAndClear(0.f, 0.f, 0.f);
    container_.draw(container_fb_->width(), container_fb_->height());
    container_image_.set(container_fb_->readRgb());
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  void drawScene() {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl_.Viewport(0, 0, fb_width_, fb_height_);
    gl_.ClearColor(kBackground[0], kBackground[1], kBackground[2], 1.f);
    gl_.ClearDepth(1.0);
    gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (!bench_.session() || fb_width_ <= 0 || fb_height_ <= 0) return;
    const render::ViewCamera view = bench_.view(fb_width_, fb_height_);
    if (ui().settings.show_ellipsoids) ellipsoids_.draw(view);
    else points_.draw(view);
    lines_.draw(view);
  }

  void handleMouse() {
    const ImGuiIO& io = ImGui::GetIO();
    if (io.WantCaptureMouse || !bench_.session()) return;
    render::OrbitCamera& cam = ui().camera;
    if (ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
      ui().view_from_keyframe = -1;
      cam.orbit(-io.MouseDelta.x * 0.006f, io.MouseDelta.y * 0.006f);
    }
    if (ImGui::IsMouseDragging(ImGuiMouseButton_Right) || ImGui::IsMouseDragging(ImGuiMouseButton_Middle)) {
      ui().view_from_keyframe = -1;
      const float k = cam.distance_m * 0.0015f;
      cam.pan(-io.MouseDelta.x * k, io.MouseDelta.y * k);
    }
    if (io.MouseWheel != 0.f) {
      ui().view_from_keyframe = -1;
      cam.dolly(std::pow(0.9f, io.MouseWheel));
    }
    if (ImGui::IsMouseReleased(ImGuiMouseButton_Left)) {
      const ImVec2 drag = ImGui::GetMouseDragDelta(ImGuiMouseButton_Left, 0.f);
      if (drag.x * drag.x + drag.y * drag.y < 9.f)
        bench_.pick(io.MousePos.x * io.DisplayFramebufferScale.x, io.MousePos.y * io.DisplayFramebufferScale.y,
                    fb_width_, fb_height_);
    }
  }

  ImGuiCond layoutCond() const { return bench_.ui().reset_layout ? ImGuiCond_Always : ImGuiCond_FirstUseEver; }

  void drawSequencePanel() {
    const ImVec2 size = ImGui::GetIO().DisplaySize;
    ImGui::SetNextWindowPos({0, 0}, layoutCond());
    ImGui::SetNextWindowSize({kLeftWidth, size.y}, layoutCond());
    ImGui::Begin("Sequence");
    ImGui::InputText("##folder", &ui().sequence_text);
    ImGui::SameLine();
    if (ImGui::Button("Open")) bench_.openPath(ui().sequence_text);
    MapSession* session = bench_.session();
    if (!session) {
      ImGui::TextWrapped("Nothing open: type a TUM RGB-D folder or a .vdmap session above.");
      ImGui::End();
      return;
    }
    const PlayerStatus status = session->status();
    const int total = mapping_->frames_total, mapped = mapping_->frames_mapped;
    if (const TumSequence* sequence = session->sequence()) {
      ImGui::TextWrapped("%s", sequence->folder().c_str());
      ImGui::Text("camera %s, %d frames", sequence->cameraSource().c_str(), total);
    } else {
      ImGui::TextWrapped("saved session of %d frames (no sequence to play)", total);
    }
    if (ImGui::Button(status.playing ? "Pause" : "Play", {60, 0})) status.playing ? session->pause() : session->play();
    ImGui::SameLine();
    if (ImGui::Button("Step")) session->step();
    ImGui::SameLine();
    if (ImGui::Button("Next keyframe")) session->stepToKeyframe();
    ImGui::SameLine();
    ImGui::TextUnformatted(status.busy ? "working" : "idle");
    ImGui::SetNextItemWidth(-80);
    if (ImGui::SliderFloat("fps limit", &ui().settings.play_fps, 0.f, 60.f, ui().settings.play_fps > 0 ? "%.0f" : "max"))
      session->setFps(ui().settings.play_fps);

    // The scrubber, with a tick under it at every keyframe's first frame.
    if (!scrubbing_) scrub_ = std::max(0, mapped - 1);
    ImGui::SetNextItemWidth(-1);
    ImGui::SliderInt("##frame", &scrub_, 0, std::max(0, total - 1), "frame %d");
    scrubbing_ = ImGui::IsItemActive();
    if (ImGui::IsItemDeactivatedAfterEdit()) session->seek(scrub_);
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    ImDrawList* draw = ImGui::GetWindowDrawList();
    for (const KeyframeInfo& k : mapping_->keyframes) {
      const float x = lo.x + 6.f + (hi.x - lo.x - 12.f) * static_cast<float>(k.frame) / std::max(1, total - 1);
      draw->AddLine({x, hi.y - 5}, {x, hi.y}, IM_COL32(255, 220, 0, 255), 2.f);
    }
    ImGui::Text("%d / %d frames mapped, %zu keyframes", mapped, total, mapping_->keyframes.size());
    if (!status.error.empty()) ImGui::TextColored({1, 0.4f, 0.4f, 1}, "%s", status.error.c_str());
    if (!status.message.empty()) ImGui::TextWrapped("%s", status.message.c_str());

    const float image_width = ImGui::GetContentRegionAvail().x;
    rgb_.show(image_width);
    depth_.show(image_width);

    // Stage timings of the last frames.
    std::vector<float> total_ms;
    std::vector<double> features, decision, update;
    const std::size_t n = mapping_->times.size(), first = n > 200 ? n - 200 : 0;
    for (std::size_t i = first; i < n; ++i) {
      const StageTimes& t = mapping_->times[i];
      total_ms.push_back(static_cast<float>(t.total_ms));
      features.push_back(t.features_ms);
      decision.push_back(t.decision_ms);
      update.push_back(t.update_ms);
    }
    char overlay[128];
    std::snprintf(overlay, sizeof overlay, "median %.1f ms", median({total_ms.begin(), total_ms.end()}));
    ImGui::PlotLines("##times", total_ms.data(), static_cast<int>(total_ms.size()), 0, overlay, 0.f, FLT_MAX,
                     {image_width, 70});
    ImGui::Text("per frame (median): features %.1f, decision %.1f, update %.1f ms", median(features),
                median(decision), median(update));
    ImGui::End();
  }

  void drawThresholds() {
    Settings& s = ui().settings;
    GlobalMapParams& g = s.thresholds;
    bool changed = false;
    const char* models[] = {sensorModelName(SensorModel::kNguyen2012), sensorModelName(SensorModel::kBelter2018)};
    int model = static_cast<int>(g.filter.model);
    if (ImGui::Combo("sensor model", &model, models, 2)) {
      g.filter.model = static_cast<SensorModel>(model);
      changed = true;
    }
    changed |= editDouble("filter sigma factor", g.filter.filter_sigma_factor, 0.5, 10.0, "%.2f");
    changed |= ImGui::SliderInt("min points", &g.filter.min_points, 3, 100);
    changed |= editDouble("tau group", g.tau_group, 0.0, 1.0, "%.2f");
    changed |= editDouble("merge distance (m)", g.merge_distance_m, 0.0, 1.0);
    changed |= ImGui::Checkbox("occlusion removal", &g.occlusion_removal);
    changed |= editDouble("occlusion distance (m)", g.occlusion_distance_m, 0.0, 2.0);
    changed |= editDouble("occlusion angle (deg)", g.occlusion_angle_deg, 0.0, 90.0, "%.1f");
    if (changed) bench_.applyThresholds();
    if (global_) {
      ImGui::Text("Sigma_e %zu -> merged %zu -> Sigma_e' %zu", global_->map.sigma_e, global_->map.merged,
                  global_->map.sigma_e_prime);
      ImGui::Text("t_g %.3f s (groups %.0f, merge %.0f, occlusion %.0f ms), %zu groups", global_->map.t_g_s,
                  global_->map.groups_ms, global_->map.merge_ms, global_->map.occlusion_ms, global_->map.groups.size());
      ImGui::Text("built from %d frames%s", global_->frames_mapped,
                  bench_.session()->status().busy ? "; rebuilding..." : "");
    }
  }

  void drawRerun() {
    MapperParams& m = ui().settings.mapper;
    ImGui::SliderInt("cell size (px)", &m.local_map.cell_size_px, 1, 32);
    editDouble("tau", m.keyframes.tau, 0.01, 1.0, "%.2f");
    ImGui::SliderInt("ORB features", &m.features.orb_features, 100, 4000);
    if (ImGui::Button("Re-run sequence")) bench_.rerun();
  }

  void drawView() {
    Settings& s = ui().settings;
    int color = static_cast<int>(s.color);
    if (ImGui::Combo("colour", &color, render::kColorModeNames.data(), static_cast<int>(render::kColorModeNames.size())))
      s.color = static_cast<render::ColorMode>(color);
    ImGui::Checkbox("ellipsoids (off: points)", &s.show_ellipsoids);
    ImGui::SliderFloat("sigma", &s.ellipsoid_sigma, 0.5f, 4.f, "%.1f");
    ImGui::Checkbox("frustums", &s.show_frustums);
    ImGui::SameLine();
    ImGui::Checkbox("graph", &s.show_graph);
    ImGui::SameLine();
    ImGui::Checkbox("trajectory", &s.show_trajectory);
    if (ImGui::Button("Reset view")) bench_.resetView();
    ImGui::SameLine();
    if (ImGui::Button("Screenshot")) screenshot_request_ = screenshot_text_;
    ImGui::SameLine();
    ImGui::SetNextItemWidth(-1);
    ImGui::InputText("##shot", &screenshot_text_);
    ImGui::TextDisabled("left drag: orbit, right drag: pan, wheel: zoom, click: pick");
  }

  void drawKeyframes() {
    if (mapping_->keyframes.empty()) return ImGui::TextUnformatted("no keyframes yet");
    if (ImGui::BeginListBox("##keyframes", {-1, 110})) {
      for (const KeyframeInfo& k : mapping_->keyframes) {
        char label[64];
        std::snprintf(label, sizeof label, "K%d  frame %d  %zu cells", k.id, k.frame, k.ellipsoids);
        if (ImGui::Selectable(label, k.id == ui().selected_keyframe)) bench_.selectKeyframe(k.id);
      }
      ImGui::EndListBox();
    }
    const int id = ui().selected_keyframe;
    if (id < 0 || id >= static_cast<int>(mapping_->keyframes.size())) return;
    const KeyframeInfo& k = mapping_->keyframes[static_cast<std::size_t>(id)];
    std::size_t kept = 0;
    if (global_ && id < static_cast<int>(global_->map.kept.size())) {
      const std::vector<bool>& cells = global_->map.kept[static_cast<std::size_t>(id)];
      kept = static_cast<std::size_t>(std::count(cells.begin(), cells.end(), true));
    }
    ImGui::Text("K%d: %zu ellipsoids, %zu kept by the filter, %d frames", id, k.ellipsoids, kept, k.frames_integrated);
    container_image_.show(ImGui::GetContentRegionAvail().x);
    std::string neighbours;
    for (const CovisibilityEdge& e : mapping_->edges)
      if (e.a == id || e.b == id) {
        char item[32];
        std::snprintf(item, sizeof item, "K%d (%.2f) ", e.a == id ? e.b : e.a, e.weight);
        neighbours += item;
      }
    ImGui::TextWrapped("neighbours (weight): %s", neighbours.empty() ? "none" : neighbours.c_str());
    if (ImGui::Button("View from keyframe")) ui().view_from_keyframe = id;
    ImGui::TextUnformatted("pose T_W_K (drag to correct):");
    bool moved = ImGui::DragFloat3("t (m)", &ui().pose_translation_m.x, 0.005f, -100.f, 100.f, "%.3f");
    moved |= ImGui::DragFloat3("rpy (deg)", &ui().pose_rotation_deg.x, 0.2f, -180.f, 180.f, "%.1f");
    if (moved) bench_.applyPoseEdit();
  }

  void drawPicked() {
    if (!ui().picked) return ImGui::TextUnformatted("click an ellipsoid in the view");
    const Ellipsoid& e = *ui().picked;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(e.cov);
    const Eigen::Vector3d axes = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt() * 1000.0;
    ImGui::Text("keyframe K%d, n = %u", e.keyframe, e.count);
    ImGui::Text("mean (%.3f, %.3f, %.3f) m", e.mean.x(), e.mean.y(), e.mean.z());
    ImGui::Text("sigma axes %.1f, %.1f, %.1f mm", axes.x(), axes.y(), axes.z());
    ImGui::ColorButton("##colour", {e.color.x() / 255.f, e.color.y() / 255.f, e.color.z() / 255.f, 1.f});
    ImGui::SameLine();
    ImGui::Text("colour (%.0f, %.0f, %.0f)", e.color.x(), e.color.y(), e.color.z());
  }

  void drawMapPanel() {
    const ImVec2 size = ImGui::GetIO().DisplaySize;
    ImGui::SetNextWindowPos({size.x - kRightWidth, 0}, layoutCond());
    ImGui::SetNextWindowSize({kRightWidth, size.y}, layoutCond());
    ImGui::Begin("Map");
    if (bench_.session()) {
      if (ImGui::CollapsingHeader("Thresholds (live)", ImGuiTreeNodeFlags_DefaultOpen)) drawThresholds();
      if (ImGui::CollapsingHeader("Re-run parameters")) drawRerun();
      if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) drawView();
      if (ImGui::CollapsingHeader("Keyframes", ImGuiTreeNodeFlags_DefaultOpen)) drawKeyframes();
      if (ImGui::CollapsingHeader("Picked ellipsoid", ImGuiTreeNodeFlags_DefaultOpen)) drawPicked();
      if (ImGui::CollapsingHeader("Pose correction")) {
        ImGui::InputText("TUM file", &ui().trajectory_text);
        if (ImGui::Button("Load corrected trajectory")) bench_.loadTrajectory();
      }
      if (ImGui::CollapsingHeader("Export and save")) {
        ImGui::InputText("folder", &ui().export_text);
        if (ImGui::Button("Export (as vdmap map)")) bench_.exportMap();
        ImGui::InputText("session", &ui().session_text);
        if (ImGui::Button("Save session (.vdmap)")) bench_.saveSession();
      }
    }
    if (ImGui::CollapsingHeader("Settings")) {
      if (ImGui::Button("Reset to defaults")) bench_.resetToDefaults();
      ImGui::TextDisabled("saved on exit to %s", settingsPath().c_str());
    }
    ImGui::End();
  }

  void drawBanners() {
    for (std::string* text : {&ui().error, &ui().warning}) {
      if (text->empty()) continue;
      const bool error = text == &ui().error;
      ImGui::SetNextWindowPos({kLeftWidth + 10, error ? 10.f : 80.f}, ImGuiCond_Always);
      ImGui::SetNextWindowSize({ImGui::GetIO().DisplaySize.x - kLeftWidth - kRightWidth - 20, 0}, ImGuiCond_Always);
      ImGui::Begin(error ? "Error" : "Warning", nullptr, ImGuiWindowFlags_NoCollapse);
      ImGui::PushStyleColor(ImGuiCol_Text, error ? ImVec4(1, 0.45f, 0.45f, 1) : ImVec4(1, 0.85f, 0.3f, 1));
      ImGui::TextWrapped("%s", text->c_str());
      ImGui::PopStyleColor();
      if (ImGui::Button("Dismiss")) text->clear();
      ImGui::End();
    }
  }

  // The scripted path: once mapping and map building are done, frame the map, render a few
  // frames so the final map is on screen, then write the screenshot and the figures.
  void advanceScript() {
    const bool scripted = !script_.screenshot.empty() || !script_.stats_json.empty() || script_.exit;
    if (!scripted || script_finished_) return;
    if (countdown_ < 0) {
      MapSession* session = bench_.session();
      bool done = true;
      if (session) {
        const PlayerStatus st = session->status();
        done = !st.busy && (st.target >= mapping_->frames_total || !script_.play_to_end || !st.error.empty());
        if (done && !st.error.empty()) ui().error = st.error;
      }
      if (!done) return;
      bench_.resetView();
      if (script_.keyframe >= 0) bench_.selectKeyframe(script_.keyframe);
      countdown_ = 3;  // frames to draw the final map before the screenshot
      return;
    }
    if (--countdown_ > 0) return;
    if (!script_.screenshot.empty()) saveScreenshot(script_.screenshot);
    if (!script_.stats_json.empty()) writeStats(script_.stats_json);
    script_finished_ = script_.exit;
    if (!script_.exit) countdown_ = 1 << 30;
  }

  void saveScreenshot(const std::string& file) {
    cv::Mat image(fb_height_, fb_width_, CV_8UC3);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl_.ReadBuffer(GL_BACK);
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl_.ReadPixels(0, 0, fb_width_, fb_height_, GL_RGB, GL_UNSIGNED_BYTE, image.data);
    cv::flip(image, image, 0);
    try {
      render::writePng(file, image);
      if (bench_.ui().warning.empty()) bench_.ui().warning = "screenshot written to " + file;
    } catch (const std::exception& e) {
      bench_.ui().error = e.what();
    }
  }

  void writeStats(const std::string& file) {
    nlohmann::json stats = {{"error", ui().error}};
    if (mapping_) {
      stats["frames_mapped"] = mapping_->frames_mapped;
      stats["frames_total"] = mapping_->frames_total;
      stats["keyframes"] = mapping_->keyframes.size();
      stats["edges"] = mapping_->edges.size();
    }
    if (global_) {
      stats["sigma_e"] = global_->map.sigma_e;
      stats["merged"] = global_->map.merged;
      stats["sigma_e_prime"] = global_->map.sigma_e_prime;
      stats["t_g_s"] = global_->map.t_g_s;
      stats["merge_distance_m"] = global_->params.merge_distance_m;
    }
    stats["ui_frames_while_busy"] = busy_frame_ms_.size();
    stats["ui_frame_ms_median_while_busy"] = median(busy_frame_ms_);
    try {
      writeFileAtomically(file, stats.dump(2) + "\n");
    } catch (const std::exception& e) {
      ui().error = e.what();
    }
  }

  Workbench& bench_;
  GlfwWindowContext& context_;
  const render::Gl& gl_;
  ScriptOptions script_;
  render::EllipsoidRenderer ellipsoids_;
  std::vector<render::EllipsoidInstance> instances_;  // of the global map shown
  render::PointRenderer points_;
  render::LineRenderer lines_;
  ImageTexture rgb_, depth_, container_image_{gl_};
  render::ContainerRenderer container_;
  std::unique_ptr<render::Framebuffer> container_fb_;
  std::shared_ptr<const MappingSnapshot> mapping_;
  std::shared_ptr<const GlobalSnapshot> global_;
  const MapSession* shown_session_ = nullptr;
  const MappingSnapshot* shown_mapping_ = nullptr;
  // What the lines were built from: the snapshot, the selection and the line toggles.
  using LinesKey = std::tuple<const MappingSnapshot*, int, bool, bool, bool>;
  LinesKey shown_lines_{};
  int shown_generation_ = -1;
  std::shared_ptr<const SelectionSnapshot> shown_selection_;  // in the container view (held: compared by address)
  render::ColorMode shown_color_ = render::ColorMode::kRgb, container_color_ = render::ColorMode::kRgb;
  int fb_width_ = 0, fb_height_ = 0;
  int scrub_ = 0;
  bool scrubbing_ = false;
  std::string screenshot_text_ = "vdmap_screenshot.png", screenshot_request_;
  int countdown_ = -1;
  bool script_finished_ = false;
  std::vector<double> busy_frame_ms_;
};

}  // namespace

int runWorkbenchWindow(Workbench& bench, const ScriptOptions& script, const std::string& settings_file) {
  Settings& s = bench.ui().settings;
  GlfwWindowContext context(s.window_width, s.window_height, "vdmap workbench");
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  const std::string ini = settings_file.empty() ? "" : (std::filesystem::path(settings_file).parent_path() / "imgui.ini").string();
  ImGui::GetIO().IniFilename = ini.empty() ? nullptr : ini.c_str();
  std::error_code ignored;  // ImGui writes imgui.ini at DestroyContext, before saveSettings makes the folder
  if (!ini.empty()) std::filesystem::create_directories(std::filesystem::path(ini).parent_path(), ignored);
  ImGui::StyleColorsDark();
  if (!ImGui_ImplGlfw_InitForOpenGL(context.window(), true) || !ImGui_ImplOpenGL3_Init("#version 330"))
    throw std::runtime_error("Dear ImGui could not initialise its OpenGL 3 backend");
  int code = 0;
  {
    WorkbenchWindow window(bench, context, script);
    while (window.frame()) {
    }
    code = window.exitCode();
  }
  glfwGetWindowSize(context.window(), &s.window_width, &s.window_height);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  if (!settings_file.empty()) {
    try {
      saveSettings(settings_file, s);
    } catch (const std::exception& e) {
      std::cerr << "vdmap: warning: settings not saved: " << e.what() << "\n";
    }
  }
  return code;
}

}  // namespace vdmap::app::gui
