#include "app/workbench/edit_diff.h"

#include <cstring>
#include <unordered_set>

#include "app/cli/parameter_table.h"

namespace vdmap::app::gui {
namespace {

// An ellipsoid's identity across builds: its keyframe and the bits of its mean.
struct Key {
  int keyframe;
  double x, y, z;
  bool operator==(const Key& o) const {
    return keyframe == o.keyframe && std::memcmp(&x, &o.x, 3 * sizeof(double)) == 0;
  }
};
Key keyOf(const Ellipsoid& e) { return {e.keyframe, e.mean.x(), e.mean.y(), e.mean.z()}; }
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    std::size_t h = std::hash<int>()(k.keyframe);
    for (const double v : {k.x, k.y, k.z}) {
      std::uint64_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      h = h * 1000003u ^ std::hash<std::uint64_t>()(bits);
    }
    return h;
  }
};
using KeySet = std::unordered_set<Key, KeyHash>;

KeySet keysOf(const std::vector<Ellipsoid>& map) {
  KeySet keys(map.size());
  for (const Ellipsoid& e : map) keys.insert(keyOf(e));
  return keys;
}

bool sameThresholds(const GlobalMapParams& a, const GlobalMapParams& b) {
  return ParameterValues{{}, a} == ParameterValues{{}, b};
}

}  // namespace

std::string MapDiff::text() const {
  return (edit.empty() ? std::string("the last edit") : edit) + ": " + std::to_string(removed.size()) +
         " removed or merged, " + std::to_string(added_count) + " new";
}

MapDiff diffMaps(std::shared_ptr<const GlobalSnapshot> before, std::shared_ptr<const GlobalSnapshot> after) {
  MapDiff d;
  const ParameterValues old_values{{}, before->params}, new_values{{}, after->params};
  for (const Parameter& p : parameters())
    if (p.live && p.get(old_values) != p.get(new_values))
      d.edit += (d.edit.empty() ? "" : ", ") + std::string(p.label) + " " + formatValue(p, p.get(old_values)) + " -> " +
                formatValue(p, p.get(new_values));
  const std::vector<Ellipsoid>&old_map = before->map.ellipsoids, &new_map = after->map.ellipsoids;
  const KeySet old_keys = keysOf(old_map), new_keys = keysOf(new_map);
  for (const Ellipsoid& e : old_map)
    if (!new_keys.contains(keyOf(e))) d.removed.push_back(e);
  d.added.resize(new_map.size());
  for (std::size_t i = 0; i < new_map.size(); ++i) {
    d.added[i] = !old_keys.contains(keyOf(new_map[i]));
    d.added_count += d.added[i];
  }
  d.before = std::move(before);
  d.after = std::move(after);
  return d;
}

std::vector<Ellipsoid> diffColoured(const MapDiff& diff) {
  std::vector<Ellipsoid> out = diff.after->map.ellipsoids;
  for (std::size_t i = 0; i < out.size(); ++i) out[i].color = diff.added[i] ? kDiffAdded : kDiffKept;
  for (Ellipsoid e : diff.removed) {
    e.color = kDiffRemoved;
    out.push_back(e);
  }
  return out;
}

void EditDiffTracker::edited(std::shared_ptr<const GlobalSnapshot> shown, const GlobalMapParams& wanted) {
  if (!before_) before_ = std::move(shown);  // an earlier edit's map still to come: compared with the same map
  wanted_ = wanted;
}

void EditDiffTracker::sync(const std::shared_ptr<const GlobalSnapshot>& global) {
  if (!before_ || !global || global == before_ || !sameThresholds(global->params, wanted_)) return;
  const bool comparable =
      global->frames_mapped == before_->frames_mapped && global->before_optimisation == before_->before_optimisation;
  if (comparable) {
    diff_ = diffMaps(std::move(before_), global);
    diff_.serial = ++serial_;
  }
  before_.reset();
}

}  // namespace vdmap::app::gui
