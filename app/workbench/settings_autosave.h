#pragma once
// When the window writes the settings while it runs (the file format is app/view/settings.h).
#include <chrono>
#include <optional>

#include "app/view/settings.h"

namespace vdmap::app::gui {

/// When the window saves the settings while it runs: one second (`delay`) after the last change,
/// so a slider dragged for a while is written once. Pure: the caller gives the clock.
class SettingsAutosave {
 public:
  using Clock = std::chrono::steady_clock;
  /// `saved`: the settings as they are in the file now (nothing is due until they change).
  explicit SettingsAutosave(Settings saved, Clock::duration delay = std::chrono::seconds(1))
      : saved_(std::move(saved)), noted_(saved_), delay_(delay) {}
  /// The settings at `now`: a change restarts the delay.
  void note(Clock::time_point now, const Settings& settings);
  /// Whether a save is due at `now` (a change noted at least `delay` ago, not saved yet).
  bool due(Clock::time_point now) const { return changed_at_ && now - *changed_at_ >= delay_; }
  /// How long until due (nullopt: nothing to save).
  std::optional<Clock::duration> dueIn(Clock::time_point now) const;
  /// The noted settings were written.
  void saved() {
    saved_ = noted_;
    changed_at_.reset();
  }
  const Settings& noted() const { return noted_; }
  /// The settings as last written (or as given at the start): what the file holds of this run.
  const Settings& written() const { return saved_; }

 private:
  Settings saved_, noted_;
  Clock::duration delay_;
  std::optional<Clock::time_point> changed_at_;
};

}  // namespace vdmap::app::gui
