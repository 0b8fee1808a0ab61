// The Map panel's "Picked ellipsoid" section: the ellipsoid clicked in the view (marked magenta).
#include <cstdio>
#include <string>

#include <Eigen/Eigenvalues>

#include "app/window/map_sections.h"
#include "app/window/widgets.h"

namespace vdmap::app::gui {

void drawPicked(Workbench& bench, WindowState& win) {
  UiState& ui = bench.ui();
  if (!ui.picked) return ImGui::TextWrapped("Click an ellipsoid in the view (it is marked magenta).");
  const Ellipsoid& e = *ui.picked;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(e.cov);
  const Eigen::Vector3d axes = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt() * 1000.0;
  if (beginRows("picked")) {
    label(win.check, "keyframe", "The keyframe it came from (for a merged one, its merge group's centre).");
    ImGui::Text("K%d", e.keyframe);
    label(win.check, "points n", "Depth points merged into it.");
    ImGui::Text("%u", e.count);
    label(win.check, "mean (m)", "Its centre in the world frame.");
    char mean[96];
    std::snprintf(mean, sizeof mean, "%.4f %.4f %.4f", e.mean.x(), e.mean.y(), e.mean.z());
    ImGui::AlignTextToFramePadding();
    ImGui::Text("%.3f, %.3f, %.3f", e.mean.x(), e.mean.y(), e.mean.z());
    ImGui::SameLine();
    if (ImGui::SmallButton("Copy##mean")) ImGui::SetClipboardText(mean);
    tip(std::string("Copies \"") + mean + "\" (x y z, metres) to the clipboard.");
    label(win.check, "sigma axes (mm)", "Standard deviations along its principal axes, largest last.");
    ImGui::Text("%.1f, %.1f, %.1f", axes.x(), axes.y(), axes.z());
    label(win.check, "colour", "Mean RGB of its points.");
    ImGui::ColorButton("##colour", {e.color.x() / 255.f, e.color.y() / 255.f, e.color.z() / 255.f, 1.f});
    ImGui::SameLine();
    ImGui::Text("%.0f, %.0f, %.0f", e.color.x(), e.color.y(), e.color.z());
    ImGui::EndTable();
  }
}

}  // namespace vdmap::app::gui
