#include "render/legend.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "render/colormap.h"

namespace vdmap::render {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kPanelAlpha = 153;  // 60 %

// Sizes at scale 1, pixels.
struct Metrics {
  float scale;
  double font() const { return 0.42 * scale; }
  int px(float v) const { return std::max(1, static_cast<int>(std::lround(v * scale))); }
  int pad() const { return px(8); }
  int row() const { return px(18); }
  int textWidth(const std::string& text) const {
    int baseline = 0;
    return cv::getTextSize(text, kFont, font(), 1, &baseline).width;
  }
};

std::string number(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f", v);
  return text;
}

// Draws into the colour canvas and the coverage mask alike.
struct Canvas {
  cv::Mat rgb, mask;
  cv::Scalar ink;
  const Metrics& m;
  void text(const std::string& s, int x, int baseline_y) {
    cv::putText(rgb, s, {x, baseline_y}, kFont, m.font(), ink, 1, cv::LINE_AA);
    cv::putText(mask, s, {x, baseline_y}, kFont, m.font(), cv::Scalar(255), 1, cv::LINE_AA);
  }
  void box(int x0, int y0, int x1, int y1, const glm::u8vec3& c) {
    cv::rectangle(rgb, {x0, y0}, {x1 - 1, y1 - 1}, cv::Scalar(c.r, c.g, c.b), cv::FILLED);
    cv::rectangle(mask, {x0, y0}, {x1 - 1, y1 - 1}, cv::Scalar(255), cv::FILLED);
  }
};

}  // namespace

std::string metresText(double m) {
  char text[32];
  if (m < 0.01) std::snprintf(text, sizeof text, "%.2f mm", m * 1e3);
  else if (m < 1.0) std::snprintf(text, sizeof text, "%.1f mm", m * 1e3);
  else std::snprintf(text, sizeof text, "%.2f m", m);
  return text;
}

Legend legendFor(ColorMode mode, const std::optional<ColorRange>& range, const GraphScene& graph, bool trajectory_shown,
                 bool groundtruth_shown, bool loops_shown) {
  Legend legend;
  if (graph.tracked) {
    if (trajectory_shown) legend.lines.push_back({kTrajectoryColor, "tracked"});
    if (groundtruth_shown && !graph.groundtruth.empty()) legend.lines.push_back({kGroundTruthColor, "ground truth"});
    if (loops_shown && !graph.loops.empty()) legend.lines.push_back({kLoopEdgeColor, "loop closure"});
  }
  if (range && (mode == ColorMode::kUncertainty || mode == ColorMode::kCount)) {
    const bool uncertainty = mode == ColorMode::kUncertainty;
    legend.ramp_title = uncertainty ? "largest std. deviation (log scale)" : "points per ellipsoid (log scale)";
    legend.ramp_lo = uncertainty ? metresText(range->lo) : number(range->lo);
    legend.ramp_hi = uncertainty ? metresText(range->hi) : number(range->hi);
  } else if (range && mode == ColorMode::kHeight) {
    char lo[32], hi[32];
    std::snprintf(lo, sizeof lo, "%.2f", range->lo);
    std::snprintf(hi, sizeof hi, "%.2f", range->hi);
    legend.ramp_title = "height above floor (m)";
    legend.ramp_lo = lo;
    legend.ramp_hi = hi;
  } else if (mode == ColorMode::kKeyframe && !graph.keyframes.empty()) {
    legend.swatch_title = "keyframe colours";
    for (int i = 0; i < static_cast<int>(graph.keyframes.size()); ++i)
      legend.swatches.push_back({keyframeColor(i), std::string("K").append(std::to_string(i))});
  }
  return legend;
}

void addQuerySliceKey(Legend& legend, const QuerySliceSpec& spec) {
  if (spec.color == QuerySliceColor::kOccupancy) {
    const auto rgb = [](const std::array<std::uint8_t, 4>& c) { return glm::u8vec3(c[0], c[1], c[2]); };
    legend.lines.push_back({rgb(kSliceFree), "slice: free"});
    legend.lines.push_back({rgb(kSliceOccupied), "occupied"});
    legend.lines.push_back({rgb(kSliceUnknown), "unknown"});
    return;
  }
  char hi[32];
  std::snprintf(hi, sizeof hi, "%.2f", spec.max_distance_m);
  if (legend.ramp_title.empty()) {
    legend.ramp_title = "slice: distance to the surface (m)";
    legend.ramp_lo = "0";
    legend.ramp_hi = hi;
    return;
  }
  legend.lines.push_back({colormap(0.f), "slice: at the surface"});
  legend.lines.push_back({colormap(1.f), std::string(hi) + " m or more"});
}

cv::Mat rasterizeLegend(const Legend& legend, const glm::vec3& background, int max_width, float scale) {
  if (legend.empty()) return {};
  const Metrics m{std::max(scale, 0.25f)};
  const int pad = m.pad(), row = m.row(), ascent = m.px(12);
  const int max_inner = std::max(m.px(40), max_width - 2 * pad - 2 * m.px(8));
  // Widths first: the panel is as wide as its widest row.
  int width = 0, height = 0;
  const int key_line = m.px(20), key_gap = m.px(6), key_space = m.px(12);
  int lines_w = 0;
  for (const LegendKey& k : legend.lines) lines_w += key_line + key_gap + m.textWidth(k.text) + key_space;
  if (!legend.lines.empty()) width = std::max(width, lines_w - key_space), height += row;
  const int ramp_w = std::min(m.px(200), max_inner), ramp_h = m.px(10);
  if (!legend.ramp_title.empty()) {
    width = std::max({width, ramp_w, m.textWidth(legend.ramp_title)});
    height += row + ramp_h + m.px(4) + row;
  }
  const int cell = m.px(50);
  const int per_row = std::max(1, max_inner / cell);
  const int n = static_cast<int>(legend.swatches.size());
  // Up to two rows of labelled swatches; more keyframes: a strip of one thin cell per keyframe
  // in id order (at least 3 px each, up to 3 rows), labelled at its ends and middle.
  const bool strip = n > 2 * per_row;
  const int rows = strip ? 0 : (n + per_row - 1) / per_row;
  const int cell_w = strip ? std::max(m.px(3), max_inner / std::max(1, n)) : 0;
  const int per_strip_row = strip ? std::max(1, max_inner / cell_w) : 0;
  const int strip_rows = strip ? std::min(3, (n + per_strip_row - 1) / per_strip_row) : 0;
  const int strip_per_row = strip ? (n + strip_rows - 1) / strip_rows : 0;  // cells per row, the last may be shorter
  const int strip_cell = strip ? std::max(1, std::min(cell_w, max_inner / std::max(1, strip_per_row))) : 0;
  const int strip_h = m.px(10);
  if (!legend.swatch_title.empty()) {
    if (strip) {
      width = std::max({width, m.textWidth(legend.swatch_title), strip_per_row * strip_cell});
      height += row + strip_rows * (strip_h + m.px(2)) + row;
    } else {
      width = std::max({width, m.textWidth(legend.swatch_title), std::min(n, per_row) * cell});
      height += row + rows * row;
    }
  }
  width = std::min(width, max_inner);
  const glm::u8vec3 bg8(glm::clamp(background, 0.f, 1.f) * 255.f + 0.5f);
  const bool dark = 0.299f * background.r + 0.587f * background.g + 0.114f * background.b < 0.5f;
  Canvas c{cv::Mat(height + 2 * pad, width + 2 * pad, CV_8UC3, cv::Scalar(bg8.r, bg8.g, bg8.b)),
           cv::Mat(height + 2 * pad, width + 2 * pad, CV_8U, cv::Scalar(0)),
           dark ? cv::Scalar(230, 230, 230) : cv::Scalar(30, 30, 30), m};
  int y = pad;  // top of the next row
  if (!legend.lines.empty()) {
    int x = pad;
    for (const LegendKey& k : legend.lines) {
      const int mid = y + row / 2 - m.px(2);
      c.box(x, mid - m.px(1.5f), x + key_line, mid - m.px(1.5f) + m.px(3), k.color);
      x += key_line + key_gap;
      c.text(k.text, x, y + ascent);
      x += m.textWidth(k.text) + key_space;
    }
    y += row;
  }
  if (!legend.ramp_title.empty()) {
    c.text(legend.ramp_title, pad, y + ascent);
    y += row;
    constexpr int kSteps = 32;
    for (int i = 0; i < kSteps; ++i) {
      const int x0 = pad + ramp_w * i / kSteps, x1 = pad + ramp_w * (i + 1) / kSteps;
      c.box(x0, y, x1, y + ramp_h, colormap((i + 0.5f) / kSteps));
    }
    y += ramp_h + m.px(4);
    c.text(legend.ramp_lo, pad, y + ascent);
    c.text(legend.ramp_hi, pad + ramp_w - m.textWidth(legend.ramp_hi), y + ascent);
    y += row;
  }
  if (!legend.swatch_title.empty()) {
    c.text(legend.swatch_title, pad, y + ascent);
    y += row;
    if (strip) {
      for (int i = 0; i < n; ++i) {
        const int x = pad + (i % strip_per_row) * strip_cell, yy = y + (i / strip_per_row) * (strip_h + m.px(2));
        c.box(x, yy, x + strip_cell, yy + strip_h, legend.swatches[i].color);
      }
      y += strip_rows * (strip_h + m.px(2));
      // Labels under the strip: the first id at the left, the middle id under its cell (one
      // row) and the last id at the right.
      const int last_x = pad + std::min(n, strip_per_row) * strip_cell;
      const std::string& first = legend.swatches.front().text;
      const std::string& end = legend.swatches.back().text;
      c.text(first, pad, y + ascent);
      c.text(end, last_x - m.textWidth(end), y + ascent);
      if (strip_rows == 1) {
        const std::string& mid = legend.swatches[n / 2].text;
        const int mid_x = pad + (n / 2) * strip_cell + strip_cell / 2 - m.textWidth(mid) / 2;
        if (mid_x > pad + m.textWidth(first) + m.px(6) &&
            mid_x + m.textWidth(mid) + m.px(6) < last_x - m.textWidth(end))
          c.text(mid, mid_x, y + ascent);
      }
    } else {
      for (int i = 0; i < n; ++i) {
        const int x = pad + (i % per_row) * cell, yy = y + (i / per_row) * row;
        const int sw = m.px(10);
        c.box(x, yy + (row - sw) / 2 - m.px(2), x + sw, yy + (row - sw) / 2 - m.px(2) + sw, legend.swatches[i].color);
        c.text(legend.swatches[i].text, x + sw + m.px(4), yy + ascent);
      }
    }
  }
  cv::Mat rgba;
  cv::cvtColor(c.rgb, rgba, cv::COLOR_RGB2RGBA);
  // The colour of an antialiased glyph edge is already blended with the panel's colour: opaque
  // wherever anything was drawn, the panel's opacity elsewhere.
  cv::Mat alpha = cv::max(c.mask > 0, kPanelAlpha);
  cv::insertChannel(alpha, rgba, 3);
  return rgba;
}

LegendPlace legendPlace(int view_width, float em) {
  if (view_width < 40.f * em) return {view_width, true};
  return {std::max(1, view_width - static_cast<int>(std::lround((kUpLabelEm + 3.f) * em))), false};
}

cv::Point legendOrigin(const cv::Mat& legend, int height, float scale) {
  const int margin = std::max(1, static_cast<int>(std::lround(8 * scale)));
  return {margin, height - margin - legend.rows};
}

}  // namespace vdmap::render
