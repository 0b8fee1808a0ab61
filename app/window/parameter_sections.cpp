// The Map panel's parameter sections: "Thresholds (live)" with the global map's figures, and
// "Re-run parameters"; one row per parameter of the table (app/cli/parameter_table.h).
#include <algorithm>
#include <cmath>
#include <vector>

#include "app/cli/mesh_options.h"
#include "app/window/map_file_panel.h"
#include "app/window/map_sections.h"
#include "app/window/tg_parts.h"
#include "app/window/widgets.h"
#include "mapping/core/message_text.h"

namespace vdmap::app::gui {
namespace {

// One parameter of the table as a slider, combo or checkbox; disabled, saying why, unless
// why_disabled is "".
void parameterRow(Workbench& bench, WindowState& win, const Parameter& p, const std::string& why_disabled) {
  const bool disabled = !why_disabled.empty();
  const bool pending = bench.parameters().pending(p);
  std::string help = parameterHelp(p);
  if (pending)
    help += "\n\nPending: the map shown was made with " + formatValue(p, bench.parameters().inUse(p)) +
            (p.live ? " (rebuilding)." : "; Re-run applies the edited value.");
  if (disabled) help = why_disabled + "\n\n" + help;
  const std::string text =
      std::string(p.label) + (p.unit.empty() ? "" : " (" + std::string(p.unit) + ")") + (pending ? " *" : "");
  label(win.check, text.c_str(), help, pending);
  ImGui::BeginDisabled(disabled);
  // The widget, then the "def" button that puts this parameter alone back to its default.
  const ImGuiStyle& style = ImGui::GetStyle();
  const float def_w = ImGui::CalcTextSize("def").x + 2.f * style.FramePadding.x;
  ImGui::SetNextItemWidth(
      std::max(4.f * ImGui::GetFontSize(), ImGui::GetContentRegionAvail().x - def_w - style.ItemInnerSpacing.x));
  double v = p.get(bench.ui().params);
  bool changed = false;
  const std::string id = "##" + std::string(p.key);
  switch (p.kind) {
    case Parameter::Kind::kBool: {
      bool b = v != 0;
      changed = ImGui::Checkbox(id.c_str(), &b);
      v = b;
      break;
    }
    case Parameter::Kind::kChoice: {
      int i = static_cast<int>(v);
      std::vector<const char*> names(p.choices.begin(), p.choices.end());
      changed = ImGui::Combo(id.c_str(), &i, names.data(), static_cast<int>(names.size()));
      v = i;
      break;
    }
    case Parameter::Kind::kInt:
    case Parameter::Kind::kReal: {
      const char* format = p.kind == Parameter::Kind::kInt ? "%.0f" : "%.3g";
      changed = ImGui::SliderScalar(id.c_str(), ImGuiDataType_Double, &v, &p.slider_lo, &p.slider_hi, format);
      if (p.kind == Parameter::Kind::kInt) v = std::round(v);
      break;
    }
  }
  tip(help);
  const double def = defaultValue(p);
  ImGui::SameLine(0.f, style.ItemInnerSpacing.x);
  ImGui::BeginDisabled(p.get(bench.ui().params) == def);
  const bool reset = ImGui::Button(("def" + id).c_str());
  tip("Back to the default, " + formatValue(p, def) + " (this parameter only).");
  ImGui::EndDisabled();
  ImGui::EndDisabled();
  if (reset) bench.parameters().resetParameter(p);
  else if (changed) bench.parameters().edit(p, v);
}

// The global map's figures (docs/method.md 6.4) under the thresholds, and a warning when the filter keeps
// few of the local maps' ellipsoids.
void drawMapFigures(Workbench& bench, WindowState& win) {
  const GlobalMap& m = win.global->map;
  std::size_t stored = 0;
  for (const KeyframeInfo& k : win.mapping->keyframes) stored += k.ellipsoids;
  if (beginRows("stats")) {
    const auto row = [&](const char* name, const std::string& help, const char* format, auto... values) {
      label(win.check, name, help);
      ImGui::Text(format, values...);
    };
    row("local maps", "Ellipsoids stored in all keyframes' containers (one per touched cell), before filtering.", "%zu",
        stored);
    row("Sigma_e",
        "Sigma_e (docs/method.md 6.4): ellipsoids the filter keeps in the local maps (enough points, not longer "
        "than k times the sensor model's expectation).",
        "%zu (%.0f%%)", m.sigma_e, 100.0 * m.sigma_e / std::max<std::size_t>(1, stored));
    row("merged", "After mean-shift merging within each merge group (docs/method.md 6.2), before occlusion removal.",
        "%zu", m.merged);
    row("fused", "Ellipsoids fused into a copy of the same surface from another merge group (docs/method.md 7).", "%zu",
        m.merged_across_groups);
    row("Sigma_e'",
        "Sigma_e' (docs/method.md 6.4): ellipsoids of the global map, after merging, occlusion removal and "
        "fusion across groups.",
        "%zu", m.sigma_e_prime);
    row("merge groups",
        "Groups of a centre keyframe and its neighbours with edge weight >= tau_group (docs/method.md 6.1).", "%zu",
        m.groups.size());
    row("t_g",
        "t_g (docs/method.md 6.4): wall time of the global map build: grouping, filtering and merging, occlusion "
        "removal, fusion across groups.",
        "%.3f s", m.t_g_s);
    const TgParts parts = tgParts(m);
    row("of which",
        "Grouping / filtering and merging / occlusion removal / fusion across groups (docs/method.md 7) / "
        "other (the rest of the build), ms: they add up to t_g.",
        "%.0f / %.0f / %.0f / %.0f / %.0f ms", parts.groups_ms, parts.merge_ms, parts.occlusion_ms, parts.fusion_ms,
        parts.other_ms);
    row("built from", "The frames mapped when this map was built (it is rebuilt now and then while playing).", "%s%s",
        counted(win.global->frames_mapped, "frame").c_str(), bench.player().status().busy ? ", rebuilding" : "");
    ImGui::EndTable();
  }
  if (stored > 0 && m.sigma_e * 20 < stored) {
    ImGui::PushStyleColor(ImGuiCol_Text, kKindColor[2]);
    ImGui::TextWrapped("The filter keeps only %.1f%% of the local maps' ellipsoids: raise the filter sigma factor k or "
                       "lower min points to keep more.",
                       100.0 * m.sigma_e / stored);
    ImGui::PopStyleColor();
  }
}

// "Show what the last edit changed" (D) and the last edit's counts.
void drawEditDiff(Workbench& bench) {
  UiState& ui = bench.ui();
  const MapDiff* diff = bench.view().diff();
  ImGui::BeginDisabled(!diff);
  ImGui::Checkbox("Show what the last edit changed (D)", &ui.show_edit_diff);
  ImGui::EndDisabled();
  tip("The 3-D view shows the map of the last threshold edit with the ellipsoids it kept grey, those it added "
      "(merged results, ellipsoids brought back) green and those it removed or merged away red (drawn from the map "
      "before the edit). Ellipsoids match by keyframe and exact mean.");
  if (diff) ImGui::TextWrapped("%s", diff->text().c_str());
}

}  // namespace

void drawThresholds(Workbench& bench, WindowState& win) {
  const bool file = bench.staticMap() != nullptr;  // opening files: a map file has nothing to rebuild
  if (beginRows("thresholds")) {
    for (const Parameter& p : parameterTable())
      if (p.live) parameterRow(bench, win, p, file ? kStaticMapWhy : whyDisabled(p, bench.ui().params));
    ImGui::EndTable();
  }
  if (file) return drawStaticMapFigures(bench, win);
  if (!win.global) return ImGui::TextWrapped("No global map yet: play or step the sequence.");
  drawEditDiff(bench);
  drawMapFigures(bench, win);
}

void drawRerun(Workbench& bench, WindowState& win) {
  const bool saved = bench.savedSession();
  const std::string why =
      bench.staticMap() ? std::string("A map file: ") + kStaticMapWhy + "."
                        : "A saved session keeps the parameters it was mapped with: there is no sequence to re-map.";
  if (beginRows("rerun")) {
    for (const Parameter& p : parameterTable())
      if (!p.live) parameterRow(bench, win, p, saved ? why : "");
    ImGui::EndTable();
  }
  bool any_pending = false;
  for (const Parameter& p : parameterTable()) any_pending |= !p.live && bench.parameters().pending(p);
  ImGui::BeginDisabled(saved || !any_pending);
  if (ImGui::Button("Re-run")) bench.parameters().rerun();
  tip(saved         ? why
      : any_pending ? "Re-maps the sequence from the first frame with the values marked * (up to the frame reached)."
                    : "Nothing to apply: the sliders show the parameters the map was made with.");
  ImGui::SameLine();
  if (ImGui::Button("Revert")) bench.ui().params.mapper = win.mapping->mapper;
  tip("Puts the sliders back to the parameters the map was made with.");
  ImGui::EndDisabled();
  if (any_pending) {
    ImGui::SameLine();
    ImGui::TextColored(kPendingColor, "* pending");
  }
}

void drawMesh(Workbench& bench, WindowState& win) {
  MeshParams& mesh = bench.ui().settings.mesh;
  const MeshParams defaults;
  const std::string made = " Changing it re-meshes the local maps; nothing is integrated again.";
  if (beginRows("mesh")) {
    label(win.check, "max slope (deg)",
          "Neighbouring cells are joined while the surface between them is turned at most this far from the "
          "camera (plus the depth noise); steeper surfaces and depth steps stay open. Default " +
              shortNumber(defaults.max_slope_deg) + "." + made);
    const double slope_lo = 0.0, slope_hi = kMeshMaxSlopeDeg;
    ImGui::SliderScalar("##mesh_max_slope", ImGuiDataType_Double, &mesh.max_slope_deg, &slope_lo, &slope_hi, "%.0f",
                        ImGuiSliderFlags_AlwaysClamp);
    label(win.check, "edge sigma",
          "The depth noise, in the sensor model's standard deviations, a join and the fusion allow. Default " +
              shortNumber(defaults.edge_sigma) + "." + made);
    const double sigma_lo = 0.0, sigma_hi = 10.0;  // up to kMeshMaxEdgeSigma typed (Ctrl+click)
    ImGui::SliderScalar("##mesh_edge_sigma", ImGuiDataType_Double, &mesh.edge_sigma, &sigma_lo, &sigma_hi, "%.1f");
    mesh.edge_sigma = std::clamp(mesh.edge_sigma, 0.0, kMeshMaxEdgeSigma);
    label(win.check, "stride (cells)",
          "Vertices on a grid of this many cells each way, each the mean of its kept cells (1: one per cell). "
          "Default " +
              std::to_string(defaults.stride) + "." + made);
    ImGui::SliderInt("##mesh_stride", &mesh.stride, 1, kMeshMaxStride, "%d", ImGuiSliderFlags_AlwaysClamp);
    label(win.check, "fuse",
          "Drop the triangles a finer keyframe covers; off keeps every keyframe's piece whole (overlapping copies "
          "stay). Default on." +
              made);
    ImGui::Checkbox("##mesh_fuse", &mesh.fuse);
    ImGui::EndTable();
  }
  if (ImGui::Button("Defaults##mesh")) mesh = defaults;
  tip("Puts the mesh's parameters back to vdmap mesh's defaults.");
  if (!bench.ui().settings.show_mesh) ImGui::TextDisabled("the mesh layer is off (View: mesh)");
}

}  // namespace vdmap::app::gui
