#include "mapping/global_map/global_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include <tbb/enumerable_thread_specific.h>

#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"
#include "mapping/global_map/detail/fusion_across_groups.h"
#include "mapping/global_map/detail/merge_within_groups.h"
#include "mapping/global_map/detail/occlusion_removal.h"

// The build (docs/method.md 6.4): merge groups (6.1, merge_groups.cpp), merging within each group
// (6.2, merge_within_groups.cpp), occlusion removal (6.3, occlusion_removal.cpp) and fusion across
// groups (7, fusion_across_groups.cpp), each stage timed for the reported figures.
namespace vdmap {
namespace global_map_detail {

// What a build keeps in a GlobalMapWorkspace (names as in buildGlobalMap's steps).
struct WorkspaceBuffers {
  // False for a build's own buffers (no workspace given): each step then frees what the later
  // ones no longer read and keeps only its output, so a one-off build (vdmap map) peaks lower.
  bool keep = true;
  // Per keyframe id: its kept cells and what they were computed from.
  struct Kept {
    std::uint64_t container = 0, revision = 0;
    FilterParams filter;
    std::vector<bool> kept;
  };
  std::vector<Kept> kept;
  std::vector<std::vector<Ellipsoid>> merged;  // per merge group
  tbb::enumerable_thread_specific<MergeScratch> merge_scratch;
  // Ellipsoid i of the merge is *merged_at[i], from group group_of[i]: merged[g] holds
  // ellipsoids offset[g] .. offset[g + 1] - 1.
  std::vector<std::size_t> offset, kept_offset;
  std::vector<const Ellipsoid*> merged_at;
  std::vector<int> group_of, kept_group_of;
  std::vector<double> lambda_max, kept_lambda_max;
  std::vector<char> removed;
  std::vector<const Ellipsoid*> survivor;  // into merged: what occlusion removal kept, in order
  OcclusionBuffers occlusion;
  FusionBuffers fusion;

  // The stage cache (keep only; GlobalMapWorkspace says what each stage is kept by). Poses and
  // real parameters are compared bit for bit: any change, however small, runs the stage again.
  // merged[g] was made from merge_key[g]; group_lambda[g] holds the lambda_max of its ellipsoids.
  struct MergeKey {
    int centre = -1;
    std::vector<int> members;
    std::vector<std::uint64_t> containers;  // per member: container id, revision
    std::vector<std::vector<bool>> kept;    // per member
    std::vector<double> poses;              // per member: T_W_K's 16 entries
    double merge_distance_m = 0;
  };
  std::vector<MergeKey> merge_key;
  std::vector<std::vector<double>> group_lambda;
  std::vector<MergeGroup> groups;  // the last build's, for GlobalMap::reuse.groups
  // Serials name the merged list (offset, merged_at, group_of, lambda_max) and the survivors
  // (survivor, kept_group_of, kept_lambda_max): each changes whenever its stage re-runs.
  std::uint64_t merge_serial = 0, survivor_serial = 0;
  struct OcclusionKey {
    std::uint64_t merge_serial = 0;
    std::vector<double> poses;              // every keyframe's T_W_K
    std::vector<std::uint64_t> containers;  // every keyframe's container id
    std::vector<double> edges;              // a, b, weight per covisibility edge
    bool on = false;
    double distance_m = 0, angle_deg = 0;  // 0 when off
  };
  std::optional<OcclusionKey> occlusion_key;
  struct FusionKey {
    std::uint64_t survivor_serial = 0;
    bool on = false;
    double max_distance = 0;  // 0 when off
  };
  std::optional<FusionKey> fusion_key;
  std::vector<Ellipsoid> fused;  // the last fusion's map->ellipsoids and merged_across_groups
  std::size_t fused_across = 0;
};

namespace {

using Clock = std::chrono::steady_clock;

// Occlusion removal and fusion both rank the ellipsoids by lambda_max.
bool needsLambdaMax(const GlobalMapParams& params) { return params.occlusion_removal || params.fuse_across_groups; }

// map->kept and map->sigma_e. The filter's answer depends on a container and the filter
// parameters only, not on poses: a rebuild after a loop closure reuses it for every keyframe.
void filterLocalMaps(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws, GlobalMap* map) {
  ws->kept.resize(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t k) {
    const KeyframeContainer& box = graph.keyframe(static_cast<int>(k)).container;
    WorkspaceBuffers::Kept& cached = ws->kept[k];
    // (id, revision) name the container's cells exactly (keyframe_container.h); ids start at 1, so
    // a new entry (container 0) never matches.
    if (cached.container != box.id() || cached.revision != box.revision() || cached.filter != params.filter)
      cached = {box.id(), box.revision(), params.filter, keptCells(box, params.filter)};
  });
  map->kept.resize(graph.size());
  for (std::size_t k = 0; k < graph.size(); ++k) {
    map->kept[k] = ws->kept[k].kept;
    map->sigma_e += static_cast<std::size_t>(std::count(map->kept[k].begin(), map->kept[k].end(), true));
  }
}

// Bit-exact comparisons go through these: a pose's 16 entries.
void appendPose(const Transform& T, std::vector<double>* out) {
  const Eigen::Matrix4d m = T.matrix();
  out->insert(out->end(), m.data(), m.data() + 16);
}

bool sameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

bool sameGroups(const std::vector<MergeGroup>& a, const std::vector<MergeGroup>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t g = 0; g < a.size(); ++g)
    if (a[g].centre != b[g].centre || a[g].members != b[g].members) return false;
  return true;
}

WorkspaceBuffers::MergeKey mergeKey(const KeyframeGraph& graph, const MergeGroup& group, const GlobalMap& map,
                                    const GlobalMapParams& params) {
  WorkspaceBuffers::MergeKey key;
  key.centre = group.centre;
  key.members = group.members;
  for (const int id : group.members) {
    const Keyframe& k = graph.keyframe(id);
    key.containers.push_back(k.container.id());
    key.containers.push_back(k.container.revision());
    key.kept.push_back(map.kept[static_cast<std::size_t>(id)]);
    appendPose(k.T_W_K, &key.poses);
  }
  key.merge_distance_m = params.merge_distance_m;
  return key;
}

bool sameMergeKey(const WorkspaceBuffers::MergeKey& a, const WorkspaceBuffers::MergeKey& b) {
  return a.centre == b.centre && a.members == b.members && a.containers == b.containers && sameBits(a.poses, b.poses) &&
         std::memcmp(&a.merge_distance_m, &b.merge_distance_m, sizeof(double)) == 0 && a.kept == b.kept;
}

// With ws->keep: ws->merged[g] for every group of map->groups, each taken over from the previous
// build when its MergeKey is unchanged (found by its centre) and merged otherwise, into a
// previous build's buffer where one is left over. Bumps ws->merge_serial unless every group was
// taken over in place.
void mergeOrReuseGroups(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws,
                        GlobalMap* map) {
  // Taken out until this stage is done: a build that fails midway leaves no key behind.
  const std::vector<WorkspaceBuffers::MergeKey> old_keys = std::move(ws->merge_key);
  ws->merge_key.clear();
  const std::size_t groups = map->groups.size(), old_groups = std::min(ws->merged.size(), old_keys.size());
  std::vector<WorkspaceBuffers::MergeKey> keys(groups);
  parallelFor(params.threads, groups, [&](std::size_t g) { keys[g] = mergeKey(graph, map->groups[g], *map, params); });
  std::vector<int> old_of_centre(graph.size(), -1);
  for (std::size_t o = 0; o < old_groups; ++o) {
    const auto centre = static_cast<std::size_t>(old_keys[o].centre);
    if (centre < old_of_centre.size()) old_of_centre[centre] = static_cast<int>(o);
  }
  std::vector<std::vector<Ellipsoid>> merged(groups);
  std::vector<std::vector<double>> lambda(groups);
  std::vector<char> reused(groups, 0), taken(old_groups, 0);
  bool in_place = groups == old_groups;
  for (std::size_t g = 0; g < groups; ++g) {
    const int o = old_of_centre[static_cast<std::size_t>(map->groups[g].centre)];
    if (o < 0 || !sameMergeKey(keys[g], old_keys[static_cast<std::size_t>(o)])) {
      in_place = false;
      continue;
    }
    merged[g].swap(ws->merged[static_cast<std::size_t>(o)]);
    lambda[g].swap(ws->group_lambda[static_cast<std::size_t>(o)]);
    reused[g] = taken[static_cast<std::size_t>(o)] = 1;
    in_place = in_place && o == static_cast<int>(g);
  }
  // The groups to merge get the buffers no group took over (their memory is already touched).
  std::size_t spare = 0;
  for (std::size_t g = 0; g < groups; ++g) {
    if (reused[g]) continue;
    while (spare < old_groups && taken[spare]) ++spare;
    if (spare == old_groups) break;
    merged[g].swap(ws->merged[spare]);
    lambda[g].swap(ws->group_lambda[spare]);
    taken[spare] = 1;
  }
  parallelFor(params.threads, groups, [&](std::size_t g) {
    if (reused[g]) return;
    mergeGroup(graph, map->groups[g], params, map->kept, &ws->merge_scratch.local(), &merged[g]);
    lambda[g].resize(merged[g].size());
    for (std::size_t l = 0; l < merged[g].size(); ++l) lambda[g][l] = largestEigenvalue(floored(merged[g][l].cov));
  });
  ws->merged = std::move(merged);
  ws->group_lambda = std::move(lambda);
  ws->merge_key = std::move(keys);  // after the merge: a build that fails midway leaves none
  map->reuse.merged_groups = static_cast<std::size_t>(std::count(reused.begin(), reused.end(), 1));
  if (!in_place || ws->merge_serial == 0) ++ws->merge_serial;
}

// Every group of map->groups merged (ws->merged), then indexed as one list: offset, merged_at,
// group_of and, when a later stage needs it (always with ws->keep), lambda_max. Sets map->merged.
void mergeWithinGroups(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws,
                       GlobalMap* map) {
  if (ws->keep) {
    mergeOrReuseGroups(graph, params, ws, map);
  } else {
    ws->merged.resize(map->groups.size());
    parallelFor(params.threads, map->groups.size(), [&](std::size_t g) {
      mergeGroup(graph, map->groups[g], params, map->kept, &ws->merge_scratch.local(), &ws->merged[g]);
      ws->merged[g].shrink_to_fit();  // reserved for all of the group's inputs
    });
    ws->merge_scratch.clear();
  }
  const std::size_t groups = ws->merged.size();
  ws->offset.assign(groups + 1, 0);
  for (std::size_t g = 0; g < groups; ++g) ws->offset[g + 1] = ws->offset[g] + ws->merged[g].size();
  const std::size_t n = ws->offset.back();
  map->merged = n;
  const bool need_lambda = ws->keep || needsLambdaMax(params);
  ws->merged_at.resize(n);
  ws->group_of.resize(n);
  ws->lambda_max.resize(need_lambda ? n : 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    for (std::size_t l = 0; l < ws->merged[g].size(); ++l) {
      ws->merged_at[ws->offset[g] + l] = &ws->merged[g][l];
      ws->group_of[ws->offset[g] + l] = static_cast<int>(g);
      if (ws->keep) ws->lambda_max[ws->offset[g] + l] = ws->group_lambda[g][l];
      else if (need_lambda) ws->lambda_max[ws->offset[g] + l] = largestEigenvalue(floored(ws->merged[g][l].cov));
    }
  });
}

WorkspaceBuffers::OcclusionKey occlusionKey(const KeyframeGraph& graph, const GlobalMapParams& params,
                                            const WorkspaceBuffers& ws) {
  WorkspaceBuffers::OcclusionKey key;
  key.merge_serial = ws.merge_serial;
  for (const Keyframe& k : graph.keyframes()) {
    appendPose(k.T_W_K, &key.poses);
    key.containers.push_back(k.container.id());
  }
  for (const CovisibilityEdge& e : graph.edges().edges())
    key.edges.insert(key.edges.end(), {static_cast<double>(e.a), static_cast<double>(e.b), e.weight});
  key.on = params.occlusion_removal;
  if (key.on) key.distance_m = params.occlusion_distance_m, key.angle_deg = params.occlusion_angle_deg;
  return key;
}

bool sameOcclusionKey(const WorkspaceBuffers::OcclusionKey& a, const WorkspaceBuffers::OcclusionKey& b) {
  return a.merge_serial == b.merge_serial && a.on == b.on && sameBits(a.poses, b.poses) &&
         a.containers == b.containers && sameBits(a.edges, b.edges) &&
         sameBits({a.distance_m, a.angle_deg}, {b.distance_m, b.angle_deg});
}

// Occlusion removal over the merged ellipsoids (or none), then the survivors in order: survivor,
// kept_group_of and kept_lambda_max. Without ws->keep the survivors move to the front of their
// group's vector, which then lets the removed go.
void removeOccluded(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws) {
  const std::size_t n = ws->merged_at.size(), groups = ws->merged.size();
  if (params.occlusion_removal)
    occludingEllipsoids(graph, ws->merged_at, ws->lambda_max, params, &ws->occlusion, &ws->removed);
  else ws->removed.assign(n, 0);
  if (!ws->keep) releaseOcclusionBuffers(&ws->occlusion);
  ws->kept_offset.assign(groups + 1, 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    ws->kept_offset[g + 1] =
        static_cast<std::size_t>(std::count(ws->removed.begin() + static_cast<std::ptrdiff_t>(ws->offset[g]),
                                            ws->removed.begin() + static_cast<std::ptrdiff_t>(ws->offset[g + 1]), 0));
  });
  std::partial_sum(ws->kept_offset.begin(), ws->kept_offset.end(), ws->kept_offset.begin());
  const std::size_t kept = ws->kept_offset.back();
  const bool need_lambda = ws->keep || needsLambdaMax(params);
  ws->survivor.resize(kept);
  ws->kept_group_of.resize(kept);
  ws->kept_lambda_max.resize(need_lambda ? kept : 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    std::size_t to = ws->kept_offset[g];
    std::vector<Ellipsoid>& merged = ws->merged[g];
    for (std::size_t i = ws->offset[g]; i < ws->offset[g + 1]; ++i) {
      if (ws->removed[i]) continue;
      if (ws->keep) ws->survivor[to] = ws->merged_at[i];
      else merged[to - ws->kept_offset[g]] = merged[i - ws->offset[g]];  // forward: never overwrites one still to move
      ws->kept_group_of[to] = static_cast<int>(g);
      if (need_lambda) ws->kept_lambda_max[to] = ws->lambda_max[i];
      ++to;
    }
    if (ws->keep) return;
    merged.resize(to - ws->kept_offset[g]);
    merged.shrink_to_fit();
    for (std::size_t l = 0; l < merged.size(); ++l) ws->survivor[ws->kept_offset[g] + l] = &merged[l];
  });
  if (ws->keep) return;
  releaseVector(&ws->merged_at);  // into the groups' vectors before they were compacted
  releaseVector(&ws->group_of);
  releaseVector(&ws->lambda_max);
  releaseVector(&ws->removed);
}

// removeOccluded, skipped with ws->keep when its OcclusionKey is unchanged (the survivors are
// then the previous build's). Bumps ws->survivor_serial when it runs.
void removeOrReuseOccluded(const KeyframeGraph& graph, const GlobalMapParams& params, WorkspaceBuffers* ws,
                           GlobalMap* map) {
  if (!ws->keep) return removeOccluded(graph, params, ws);
  WorkspaceBuffers::OcclusionKey key = occlusionKey(graph, params, *ws);
  if (ws->occlusion_key && sameOcclusionKey(*ws->occlusion_key, key)) {
    map->reuse.occlusion = true;
    return;
  }
  ws->occlusion_key.reset();  // until it has run
  removeOccluded(graph, params, ws);
  ws->occlusion_key = std::move(key);
  ++ws->survivor_serial;
}

// map->ellipsoids: the survivors fused across groups, or as they are.
void fuseSurvivors(const GlobalMapParams& params, WorkspaceBuffers* ws, GlobalMap* map) {
  const std::size_t kept = ws->survivor.size();
  if (params.fuse_across_groups) {
    map->ellipsoids = fuseAcrossGroups(ws->survivor, ws->kept_group_of, ws->kept_lambda_max, params, &ws->fusion);
    map->merged_across_groups = kept - map->ellipsoids.size();
  } else {
    map->ellipsoids.resize(kept);
    parallelFor(params.threads, kept, [&](std::size_t k) { map->ellipsoids[k] = *ws->survivor[k]; });
  }
}

// fuseSurvivors, or with ws->keep its previous output when its FusionKey is unchanged.
void fuseOrReuseSurvivors(const GlobalMapParams& params, WorkspaceBuffers* ws, GlobalMap* map) {
  if (!ws->keep) return fuseSurvivors(params, ws, map);
  WorkspaceBuffers::FusionKey key{ws->survivor_serial, params.fuse_across_groups,
                                  params.fuse_across_groups ? params.fusion_max_distance : 0.0};
  if (ws->fusion_key && ws->fusion_key->survivor_serial == key.survivor_serial && ws->fusion_key->on == key.on &&
      sameBits({ws->fusion_key->max_distance}, {key.max_distance})) {
    map->ellipsoids = ws->fused;
    map->merged_across_groups = ws->fused_across;
    map->reuse.fusion = true;
    return;
  }
  ws->fusion_key.reset();  // until it has run
  fuseSurvivors(params, ws, map);
  ws->fused = map->ellipsoids;
  ws->fused_across = map->merged_across_groups;
  ws->fusion_key = key;
}

}  // namespace
}  // namespace global_map_detail

std::vector<Ellipsoid> localEllipsoids(const KeyframeGraph& graph, const GlobalMap& map) {
  std::vector<Ellipsoid> local;
  local.reserve(map.sigma_e);
  forEachLocalEllipsoid(graph, map, [&local](const Ellipsoid& e) { local.push_back(e); });
  return local;
}

void forEachLocalEllipsoid(const KeyframeGraph& graph, const GlobalMap& map,
                           const std::function<void(const Ellipsoid&)>& visit) {
  for (const Keyframe& k : graph.keyframes())
    forEachKeptEllipsoid(k.container, map.kept.at(static_cast<std::size_t>(k.id)), k.T_W_K, k.id, visit);
}

struct GlobalMapWorkspace::Buffers : global_map_detail::WorkspaceBuffers {};

GlobalMapWorkspace::GlobalMapWorkspace() : buffers_(std::make_unique<Buffers>()) {}
GlobalMapWorkspace::~GlobalMapWorkspace() = default;

void GlobalMapWorkspace::forgetStages() {
  buffers_->merge_key.clear();
  buffers_->groups.clear();
  buffers_->occlusion_key.reset();
  buffers_->fusion_key.reset();
}

GlobalMap buildGlobalMap(const KeyframeGraph& graph, const GlobalMapParams& params, GlobalMapWorkspace* workspace) {
  using namespace global_map_detail;
  params.validate();
  std::unique_ptr<GlobalMapWorkspace> own;  // this build's, without one given
  if (workspace == nullptr) workspace = (own = std::make_unique<GlobalMapWorkspace>()).get();
  WorkspaceBuffers& ws = *workspace->buffers_;
  ws.keep = own == nullptr;
  ws.fusion.keep = ws.keep;
  GlobalMap map;
  const auto start = Clock::now();
  map.groups = mergeGroups(graph, params.tau_group);
  if (ws.keep) {
    map.reuse.groups = sameGroups(map.groups, ws.groups);
    ws.groups = map.groups;
  }
  map.groups_ms = msSince(start);

  const auto merge_start = Clock::now();
  filterLocalMaps(graph, params, &ws, &map);
  mergeWithinGroups(graph, params, &ws, &map);
  map.merge_ms = msSince(merge_start);

  // Occlusion removal before fusion: it judges each viewpoint's own group's ellipsoids, and a
  // fused ellipsoid carries only its seed's keyframe, so fusing first would hide copies from the
  // viewpoints whose coarse occluders they remove.
  const auto occlusion_start = Clock::now();
  removeOrReuseOccluded(graph, params, &ws, &map);
  map.occlusion_ms = msSince(occlusion_start);

  const auto fusion_start = Clock::now();
  fuseOrReuseSurvivors(params, &ws, &map);
  map.fusion_ms = msSince(fusion_start);
  map.sigma_e_prime = map.ellipsoids.size();
  map.t_g_s = secondsSince(start);
  return map;
}

}  // namespace vdmap
