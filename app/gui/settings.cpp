#include "app/gui/settings.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include <nlohmann/json.hpp>

#include "mapping/core/atomic_file.h"
#include "render/colormap.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The settings file's sections whose keys --set takes.
constexpr const char* kSetSections[] = {"thresholds", "rerun", "view"};

json toJson(const Settings& s) {
  const GlobalMapParams& g = s.thresholds;
  return {
      {"thresholds",
       {{"sensor_model", sensorModelName(g.filter.model)},
        {"filter_sigma_factor", g.filter.filter_sigma_factor},
        {"min_points", g.filter.min_points},
        {"tau_group", g.tau_group},
        {"merge_distance", g.merge_distance_m},
        {"occlusion_removal", g.occlusion_removal},
        {"occlusion_distance", g.occlusion_distance_m},
        {"occlusion_angle", g.occlusion_angle_deg}}},
      {"rerun",
       {{"cell_size", s.mapper.local_map.cell_size_px},
        {"tau", s.mapper.keyframes.tau},
        {"orb_features", s.mapper.features.orb_features}}},
      {"view",
       {{"color", render::colorModeName(s.color)},
        {"show_ellipsoids", s.show_ellipsoids},
        {"show_frustums", s.show_frustums},
        {"show_graph", s.show_graph},
        {"show_trajectory", s.show_trajectory},
        {"ellipsoid_sigma", s.ellipsoid_sigma},
        {"play_fps", s.play_fps}}},
      {"window", {{"width", s.window_width}, {"height", s.window_height}}},
      {"last_sequence", s.last_sequence},
  };
}

// Copies the value at j[key] into `out` when present (json type errors propagate).
template <typename T>
void read(const json& j, const char* key, T& out) {
  if (j.contains(key)) out = j.at(key).get<T>();
}

Settings fromJson(const json& j) {
  Settings s;
  if (!j.is_object()) throw std::invalid_argument("expected a JSON object");
  if (j.contains("thresholds")) {
    const json& t = j.at("thresholds");
    GlobalMapParams& g = s.thresholds;
    if (t.contains("sensor_model")) g.filter.model = parseSensorModel(t.at("sensor_model").get<std::string>());
    read(t, "filter_sigma_factor", g.filter.filter_sigma_factor);
    read(t, "min_points", g.filter.min_points);
    read(t, "tau_group", g.tau_group);
    read(t, "merge_distance", g.merge_distance_m);
    read(t, "occlusion_removal", g.occlusion_removal);
    read(t, "occlusion_distance", g.occlusion_distance_m);
    read(t, "occlusion_angle", g.occlusion_angle_deg);
    g.validate();
  }
  if (j.contains("rerun")) {
    const json& r = j.at("rerun");
    read(r, "cell_size", s.mapper.local_map.cell_size_px);
    read(r, "tau", s.mapper.keyframes.tau);
    read(r, "orb_features", s.mapper.features.orb_features);
    if (s.mapper.local_map.cell_size_px < 1 || s.mapper.local_map.cell_size_px > 64)
      throw std::invalid_argument("rerun.cell_size must be in 1..64");
    if (!(s.mapper.keyframes.tau > 0 && s.mapper.keyframes.tau <= 1))
      throw std::invalid_argument("rerun.tau must be in (0, 1]");
    if (s.mapper.features.orb_features < 1) throw std::invalid_argument("rerun.orb_features must be >= 1");
  }
  if (j.contains("view")) {
    const json& v = j.at("view");
    if (v.contains("color")) s.color = render::parseColorMode(v.at("color").get<std::string>());
    read(v, "show_ellipsoids", s.show_ellipsoids);
    read(v, "show_frustums", s.show_frustums);
    read(v, "show_graph", s.show_graph);
    read(v, "show_trajectory", s.show_trajectory);
    read(v, "ellipsoid_sigma", s.ellipsoid_sigma);
    read(v, "play_fps", s.play_fps);
    if (!(s.ellipsoid_sigma > 0 && s.ellipsoid_sigma <= 10)) throw std::invalid_argument("view.ellipsoid_sigma must be in (0, 10]");
    if (!(s.play_fps >= 0 && s.play_fps <= 1000)) throw std::invalid_argument("view.play_fps must be in [0, 1000]");
  }
  if (j.contains("window")) {
    read(j.at("window"), "width", s.window_width);
    read(j.at("window"), "height", s.window_height);
    if (s.window_width < 320 || s.window_height < 240 || s.window_width > 16384 || s.window_height > 16384)
      throw std::invalid_argument("window size must be in 320x240..16384x16384");
  }
  read(j, "last_sequence", s.last_sequence);
  return s;
}

}  // namespace

fs::path settingsPath() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  const fs::path base = xdg && *xdg ? fs::path(xdg) : fs::path(home && *home ? home : ".") / ".config";
  return base / "vdmap" / "settings.json";
}

Settings loadSettings(const fs::path& file, std::string* warning) {
  if (!fs::exists(file)) return {};
  try {
    std::ifstream in(file);
    if (!in) throw std::runtime_error("cannot be read");
    return fromJson(json::parse(in));
  } catch (const std::exception& e) {
    if (warning) *warning = file.string() + ": " + e.what() + "; using the default settings";
    return {};
  }
}

void saveSettings(const fs::path& file, const Settings& settings) {
  fs::create_directories(file.parent_path());
  writeFileAtomically(file, toJson(settings).dump(2) + "\n");
}

bool rerunParamsDiffer(const Settings& a, const Settings& b) { return toJson(a).at("rerun") != toJson(b).at("rerun"); }

std::string settingKeyList() {
  const json defaults = toJson(Settings{});
  std::string list;
  for (const char* section : kSetSections) {
    list += std::string(list.empty() ? "" : "; ") + section + ":";
    for (const auto& [key, value] : defaults.at(section).items())
      list += (list.back() == ':' ? " " : ", ") + key;
  }
  return list;
}

void applySetting(Settings& settings, const std::string& key_value) {
  const auto eq = key_value.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("--set '" + key_value + "': expected KEY=VALUE");
  const std::string key = key_value.substr(0, eq), value = key_value.substr(eq + 1);
  // Re-use the JSON reader so both paths accept and check the same keys and ranges.
  json j = toJson(settings);
  const json parsed = json::parse(value, nullptr, false);
  const json v = parsed.is_discarded() ? json(value) : parsed;
  const auto section = std::find_if(std::begin(kSetSections), std::end(kSetSections),
                                    [&](const char* name) { return j[name].contains(key); });
  if (section == std::end(kSetSections)) throw std::invalid_argument("--set '" + key + "': unknown key (see vdmap gui --help)");
  j[*section][key] = v;
  try {
    settings = fromJson(j);
  } catch (const std::exception& e) {
    throw std::invalid_argument("--set '" + key_value + "': " + e.what());
  }
}

}  // namespace vdmap::app::gui
