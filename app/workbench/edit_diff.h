#pragma once
// What the last threshold edit changed in the global map: the ellipsoids it removed or merged
// away and those it added (merged results, ellipsoids brought back), counted and drawn
// highlighted on request (docs/workbench.md "What an edit changed").
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "app/workbench/mapping_worker.h"

namespace vdmap::app::gui {

/// The difference between the global map before a threshold edit and the one built with it.
/// Ellipsoids match by keyframe and exact mean (an ellipsoid no threshold touched is rebuilt
/// bit for bit).
struct MapDiff {
  std::shared_ptr<const GlobalSnapshot> before, after;
  /// The live parameters that differ: "merge distance h 0.25 -> 0.541" (joined by ", ").
  std::string edit;
  std::vector<Ellipsoid> removed;  ///< in before's map, not in after's: filtered out, merged away, occluded
  std::vector<bool> added;         ///< per ellipsoid of after's map: not in before's (new, merged, brought back)
  std::size_t added_count = 0;
  int serial = 0;  ///< 1, 2, ... per diff of the session

  /// "merge distance h 0.25 -> 0.541: 52 removed or merged, 16 new".
  std::string text() const;
};

/// The difference of two builds of the global map.
MapDiff diffMaps(std::shared_ptr<const GlobalSnapshot> before, std::shared_ptr<const GlobalSnapshot> after);

/// Colours of the diff as the 3-D view draws it (with colour "rgb"): what stayed, what the edit
/// added, what it removed.
inline const Eigen::Vector3f kDiffKept{90.f, 90.f, 90.f}, kDiffAdded{40.f, 230.f, 80.f},
    kDiffRemoved{240.f, 40.f, 40.f};
/// after's map with every ellipsoid coloured kDiffKept or kDiffAdded, then the removed ones
/// coloured kDiffRemoved.
std::vector<Ellipsoid> diffColoured(const MapDiff& diff);

/// Follows the threshold edits of the open session and computes the diff when an edit's map
/// arrives. UI thread only.
class EditDiffTracker {
 public:
  /// A threshold edit asking for `wanted` is sent while `shown` is the newest map: the map built
  /// with `wanted` is compared with `shown`, or with the map an earlier edit still waits on.
  void edited(std::shared_ptr<const GlobalSnapshot> shown, const GlobalMapParams& wanted);
  /// Once per UI frame: when the newest map is the one the edit waits on, the diff is computed.
  /// A map of other frames (mapping went on, a pose edit) drops the edit: nothing to compare.
  void sync(const std::shared_ptr<const GlobalSnapshot>& global);
  /// The last edit's diff; null when there is none yet.
  const MapDiff* diff() const { return diff_.after ? &diff_ : nullptr; }
  /// The diff to draw over `global`: diff() when `show` is set and its map is `global`, else null.
  const MapDiff* shown(bool show, const std::shared_ptr<const GlobalSnapshot>& global) const {
    return show && diff_.after && diff_.after == global ? &diff_ : nullptr;
  }
  /// A new session: no edit, no diff.
  void reset() { *this = {}; }

 private:
  std::shared_ptr<const GlobalSnapshot> before_;  // the map the pending edit is compared with
  GlobalMapParams wanted_;
  MapDiff diff_;
  int serial_ = 0;
};

}  // namespace vdmap::app::gui
