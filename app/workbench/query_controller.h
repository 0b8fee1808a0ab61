#pragma once
// The point queries (docs/workbench.md "Queries"; docs/method.md 13): the probe under the cursor
// and the query slice, read from the QueryMap the worker publishes with every global map.
#include <future>
#include <memory>
#include <optional>

#include "app/workbench/view_controller.h"
#include "app/workbench/workbench_state.h"
#include "render/query_slice.h"

namespace vdmap::app::gui {

/// The probe (ui().settings.probe, probe_result) and the query slice (ui().settings.query_slice, query_slice_spec).
class QueryController {
 public:
  QueryController(WorkbenchState& state, const ViewController& view) : state_(state), view_(view) {}

  /// The newest point queries of the open session (null while none are built: they are built
  /// while the probe or the query slice is on). sync() asks the worker for them.
  std::shared_ptr<const QuerySnapshot> snapshot() const;
  /// The probe's point for pixel (x, y) of a width x height viewport: on the query slice's plane
  /// while it is shown, else `surface` (the drawn surface under the pixel) moved toward the eye
  /// by ui().settings.probe_offset_m; nullopt when neither exists.
  std::optional<glm::vec3> probePoint(float x_px, float y_px, int width, int height,
                                      const std::optional<glm::vec3>& surface) const;
  /// Classifies `p` and its distance to the nearest surface with snapshot() (a note says why
  /// when none is built).
  ProbeResult probe(const glm::vec3& p, bool on_slice = false) const;
  /// The probe under pixel (x, y) into ui().probe_result (reset when there is no point there);
  /// returns whether the text shown changed.
  bool probeAt(float x_px, float y_px, int width, int height, const std::optional<glm::vec3>& surface);
  /// The query slice drawn now (null: none yet, or off). sync() starts its computation off the UI
  /// thread when the map, the spec or the up axis changed; the window is woken when it is done.
  std::shared_ptr<const render::QuerySliceImage> slice() const {
    return ui_.settings.query_slice ? slice_image_ : nullptr;
  }
  /// Blocks until the slice being computed (if any) is taken (tests and scripted runs).
  void waitSlice();
  /// Once per UI frame: the queries wanted or not, a finished slice taken, a new one started.
  void sync();

 private:
  // What a slice is computed for.
  struct SliceKey {
    std::shared_ptr<const QueryMap> map;  // held: a new map at the same address is not the same map
    render::QuerySliceSpec spec;
    render::HeightFrame height;
    bool operator==(const SliceKey&) const = default;
  };

  WorkbenchState& state_;
  UiState& ui_ = state_.ui;
  const std::unique_ptr<MappingWorker>& worker_ = state_.worker;
  const ViewController& view_;  // the viewport and the height frame
  // The slice shown, the one being computed and what each is computed for.
  std::shared_ptr<const render::QuerySliceImage> slice_image_;
  std::future<std::shared_ptr<const render::QuerySliceImage>> slice_job_;
  SliceKey slice_key_, slice_job_key_;
};

}  // namespace vdmap::app::gui
