#include "app/workbench/settings_autosave.h"

#include <algorithm>

namespace vdmap::app::gui {

void SettingsAutosave::note(Clock::time_point now, const Settings& settings) {
  if (sameSettings(settings, noted_)) return;
  noted_ = settings;
  if (sameSettings(noted_, saved_)) changed_at_.reset();  // changed back: nothing to write
  else changed_at_ = now;
}

std::optional<SettingsAutosave::Clock::duration> SettingsAutosave::dueIn(Clock::time_point now) const {
  if (!changed_at_) return std::nullopt;
  return std::max(Clock::duration::zero(), *changed_at_ + delay_ - now);
}

}  // namespace vdmap::app::gui
