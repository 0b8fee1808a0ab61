#include "render/colormap.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

namespace vdmap::render {
namespace {

float lambdaMax(const glm::mat3& cov) {
  Eigen::Matrix3f m;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) m(r, c) = cov[c][r];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver;
  solver.computeDirect(m, Eigen::EigenvaluesOnly);
  return std::max(solver.eigenvalues()(2), 1e-12f);
}

std::vector<glm::u8vec4> rampColors(const std::vector<float>& values) {
  std::vector<glm::u8vec4> colors(values.size());
  if (values.empty()) return colors;
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  const float span = *hi - *lo > 1e-9f ? *hi - *lo : 1.f;
  for (std::size_t i = 0; i < values.size(); ++i)
    colors[i] = glm::u8vec4(colormap((values[i] - *lo) / span), 255);
  return colors;
}

}  // namespace

glm::u8vec3 colormap(float t) {
  // Viridis sampled at 9 stops, linearly interpolated.
  static const float kStops[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                     {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                     {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
  t = std::clamp(std::isfinite(t) ? t : 0.f, 0.f, 1.f) * 8.f;
  const int i = std::min(7, static_cast<int>(t));
  const float f = t - i;
  glm::u8vec3 c;
  for (int k = 0; k < 3; ++k)
    c[k] = static_cast<std::uint8_t>(std::lround(kStops[i][k] * (1 - f) + kStops[i + 1][k] * f));
  return c;
}

glm::u8vec3 keyframeColor(int keyframe) {
  const float h = std::fmod(0.13f + 0.6180339887f * static_cast<float>(keyframe), 1.f) * 6.f;
  const float s = 0.65f, v = 0.95f;
  const int sector = static_cast<int>(h) % 6;
  const float f = h - std::floor(h), p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  glm::vec3 rgb;
  switch (sector) {
    case 0: rgb = {v, t, p}; break;
    case 1: rgb = {q, v, p}; break;
    case 2: rgb = {p, v, t}; break;
    case 3: rgb = {p, q, v}; break;
    case 4: rgb = {t, p, v}; break;
    default: rgb = {v, p, q}; break;
  }
  return glm::u8vec3(glm::round(rgb * 255.f));
}

std::pair<float, float> heightRange(std::span<const EllipsoidInstance> ellipsoids, const HeightFrame& frame,
                                    const HeightSlice& slice) {
  if (slice.on) return {slice.lo_m, slice.hi_m};
  if (ellipsoids.empty()) return {0.f, 1.f};
  std::vector<float> h;
  h.reserve(ellipsoids.size());
  for (const auto& e : ellipsoids) h.push_back(frame.height(e.mean));
  const std::size_t a = h.size() * 2 / 100, b = std::min(h.size() - 1, h.size() * 98 / 100);
  std::nth_element(h.begin(), h.begin() + static_cast<long>(a), h.end());
  const float lo = h[a];
  std::nth_element(h.begin(), h.begin() + static_cast<long>(b), h.end());
  return {lo, std::max(h[b], lo + 1e-3f)};
}

std::vector<glm::u8vec4> ellipsoidColors(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode,
                                         const HeightFrame& frame, const HeightSlice& slice) {
  std::vector<float> values;
  std::vector<glm::u8vec4> colors;
  switch (mode) {
    case ColorMode::kRgb:
      for (const auto& e : ellipsoids) colors.emplace_back(e.rgb, 255);
      return colors;
    case ColorMode::kKeyframe:
      for (const auto& e : ellipsoids) colors.emplace_back(keyframeColor(e.keyframe), 255);
      return colors;
    case ColorMode::kUncertainty:
      for (const auto& e : ellipsoids) values.push_back(std::log10(lambdaMax(e.cov)));
      return rampColors(values);
    case ColorMode::kCount:
      for (const auto& e : ellipsoids) values.push_back(std::log(std::max<float>(1.f, e.count)));
      return rampColors(values);
    case ColorMode::kHeight: {
      const auto [lo, hi] = heightRange(ellipsoids, frame, slice);
      const float span = hi - lo > 1e-6f ? hi - lo : 1.f;
      for (const auto& e : ellipsoids) colors.emplace_back(colormap((frame.height(e.mean) - lo) / span), 255);
      return colors;
    }
  }
  return colors;
}

const char* colorModeName(ColorMode mode) { return kColorModeNames.at(static_cast<std::size_t>(mode)); }

ColorMode parseColorMode(const std::string& name) {
  std::string expected;  // "rgb, keyframe, uncertainty, count or height"
  for (std::size_t i = 0; i < kColorModeNames.size(); ++i) {
    if (name == kColorModeNames[i]) return static_cast<ColorMode>(i);
    expected += std::string(i == 0 ? "" : i + 1 == kColorModeNames.size() ? " or " : ", ") + kColorModeNames[i];
  }
  throw std::invalid_argument("unknown colour mode '" + name + "' (expected " + expected + ")");
}

}  // namespace vdmap::render
