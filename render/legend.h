#pragma once
// The legend over the 3-D view, the same pixels in the workbench and `vdmap render`: the colour
// ramp of the uncertainty and count modes with its title and range, the keyframes' colours of
// the keyframe mode, and the key of the tracking lines. Rasterised on the CPU with OpenCV's
// Hershey font (deterministic, no font files) and blended over the view by OverlayRenderer.
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/type_precision.hpp>
#include <opencv2/core.hpp>

#include "render/query_slice.h"
#include "render/scene_lines.h"

namespace vdmap::render {

/// The range of the colour ramp of a colour mode over a map, in the units a legend shows:
/// uncertainty: the largest standard deviation sqrt(lambda_max), m; count: points per ellipsoid.
/// Empty for rgb / keyframe colours or an empty map. The ramp is logarithmic in both.
struct ColorRange {
  float lo = 0.f, hi = 0.f;
};
/// One coloured entry: a swatch (keyframe colours) or a line (tracking key) with its label.
struct LegendKey {
  glm::u8vec3 color{0};
  std::string text;
  bool operator==(const LegendKey&) const = default;
};

/// What the legend says. Empty parts are not drawn; an empty legend draws nothing.
struct Legend {
  std::vector<LegendKey> lines;     ///< tracking key: the trajectory, ground truth, loop closures
  std::string ramp_title;           ///< "largest std. deviation (log scale)"; empty: no ramp
  std::string ramp_lo, ramp_hi;     ///< the ramp's ends, in the title's units
  std::string swatch_title;         ///< "keyframe colours"; empty: no swatches
  std::vector<LegendKey> swatches;  ///< one per keyframe, K0, K1, ...
  bool empty() const { return lines.empty() && ramp_title.empty() && swatch_title.empty(); }
  bool operator==(const Legend&) const = default;
};

/// The legend of a view coloured by `mode` (range: the map's colorRange) with `graph`: a ramp for
/// uncertainty (metres) and count, a swatch per keyframe for keyframe colours, and for tracked
/// poses the key of the lines shown (trajectory; ground truth when `groundtruth_shown` and there
/// is one; loop closures when `loops_shown` and there are some).
Legend legendFor(ColorMode mode, const std::optional<ColorRange>& range, const GraphScene& graph,
                 bool trajectory_shown = true, bool groundtruth_shown = true, bool loops_shown = true);

/// Adds the key of the query slice drawn with `spec` (render/query_slice.h): for occupancy colours
/// a line per class (free, occupied, unknown); for distance colours the ramp "distance to the
/// surface (m)" from 0 to the max distance, or, when the map's colours hold the ramp, its two ends
/// as lines.
void addQuerySliceKey(Legend& legend, const QuerySliceSpec& spec);

/// A length for people: "0.42 mm", "3.1 mm", "1.20 m".
std::string metresText(double m);

/// The legend as an RGBA image (CV_8UC4, RGBA order, row 0 on top): a panel of `background` at
/// 60 % opacity behind opaque text (light on a dark background, dark on a light one), at most
/// `max_width` pixels wide. Keyframe colours: labelled swatches when they fit in two rows, else a
/// strip of one thin cell per keyframe (id order, up to 3 rows) labelled at its ends and middle.
/// `scale` 1 is a 12 px font. Empty for an empty legend.
cv::Mat rasterizeLegend(const Legend& legend, const glm::vec3& background, int max_width, float scale = 1.f);

/// The window's font size at scale 1, pixels: the em the legend is placed by, in the window and in
/// `vdmap render` alike.
inline constexpr float kWindowEmPx = 13.f;
/// The room the window's up label takes at the bottom right, in em: its longest text, "up: data
/// (-0.00, -0.00, -0.00)", in the window's font (7 px a character at 13 px). A fixed room, not
/// the label measured, so that the window and `vdmap render` (which draws no label) wrap the
/// legend at the same width.
inline constexpr float kUpLabelEm = 16.5f;

/// How wide the legend may be in a view of `view_width` pixels whose bottom-right corner holds
/// the up label (`em` the font size): up to 3 em left of the label's room, or, in a view narrower
/// than 40 em, the whole width with the label moved to the top instead.
struct LegendPlace {
  int max_width = 0;
  bool up_label_on_top = false;
};
LegendPlace legendPlace(int view_width, float em = kWindowEmPx);

/// Where the legend image goes in a viewport of `height` pixels: its top-left corner in image
/// coordinates (row 0 on top), bottom-left with a margin.
cv::Point legendOrigin(const cv::Mat& legend, int height, float scale = 1.f);

}  // namespace vdmap::render
