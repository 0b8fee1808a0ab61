#pragma once
// The parts of t_g (docs/method.md 6.4) the Thresholds section lists under it.
#include "mapping/global_map/global_map.h"

namespace vdmap::app::gui {

/// The global map build's stages, ms, and `other`: what t_g holds besides them (the filter's
/// bookkeeping between stages, timing itself), so that the five add up to t_g exactly.
struct TgParts {
  double groups_ms = 0, merge_ms = 0, occlusion_ms = 0, fusion_ms = 0, other_ms = 0;
};

inline TgParts tgParts(const GlobalMap& m) {
  TgParts p{m.groups_ms, m.merge_ms, m.occlusion_ms, m.fusion_ms, 0};
  p.other_ms = 1e3 * m.t_g_s - (p.groups_ms + p.merge_ms + p.occlusion_ms + p.fusion_ms);
  return p;
}

}  // namespace vdmap::app::gui
