#include "app/workbench/player.h"

namespace vdmap::app::gui {

std::vector<MarkerCluster> clusterMarkers(const std::vector<float>& positions_px, float min_px) {
  std::vector<MarkerCluster> out;
  float first = 0.f;  // the cluster's first marker: a cluster spans at most min_px
  for (std::size_t i = 0; i < positions_px.size(); ++i) {
    const float x = positions_px[i];
    if (out.empty() || x - first >= min_px) {
      out.push_back({x, {}});
      first = x;
    }
    MarkerCluster& c = out.back();
    c.members.push_back(static_cast<int>(i));
    c.x = 0.5f * (first + x);
  }
  return out;
}

PlayerStatus Player::status() const { return state_.worker ? state_.worker->status() : PlayerStatus{}; }

void Player::play() {
  if (state_.worker) state_.worker->play();
}

void Player::pause() {
  if (state_.worker) state_.worker->pause();
}

void Player::playPause() { status().playing ? pause() : play(); }

void Player::step() {
  if (state_.worker) state_.worker->step();
}

void Player::stepBack() {
  if (const int target = status().target; target >= 2) seek(target - 2);
}

void Player::stepToKeyframe() {
  if (state_.worker) state_.worker->stepToKeyframe();
}

void Player::seek(int frame) {
  if (state_.worker) state_.worker->seek(frame);
}

void Player::setFps(float fps) {
  state_.ui.settings.play_fps = fps;
  if (state_.worker) state_.worker->setFps(fps);
}

void Player::sync() {
  const PlayerStatus st = status();
  if (st.error != shown_error_) {
    shown_error_ = st.error;
    if (!st.error.empty()) state_.report(StatusLine::Kind::kError, st.error);
  }
  if (st.message != shown_message_) {
    shown_message_ = st.message;
    if (!st.message.empty()) state_.report(StatusLine::Kind::kSuccess, st.message);
  }
}

void Player::newSession() {
  shown_error_.clear();
  shown_message_.clear();
}

}  // namespace vdmap::app::gui
