#include "tests/support/render_scenes.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "render/sequence_synth.h"
#include "tests/support/test_util.h"

namespace vdmap::test {

glm::mat3 covariance(float sx, float sy, float sz, float yaw) {
  const glm::mat3 R = glm::mat3(glm::rotate(glm::mat4(1.f), yaw, glm::vec3(0, 0, 1)));
  const glm::mat3 D(sx * sx, 0, 0, 0, sy * sy, 0, 0, 0, sz * sz);
  return R * D * glm::transpose(R);
}

std::vector<render::EllipsoidInstance> gridEllipsoids() {
  std::vector<render::EllipsoidInstance> out;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 5; ++i) {
      render::EllipsoidInstance e;
      e.mean = {-1.f + 0.5f * i, -0.75f + 0.5f * j, 0.05f * ((i + j) % 3)};
      e.cov = covariance(0.09f, 0.03f + 0.012f * j, 0.015f + 0.005f * i, 0.35f * (i + 2 * j));
      e.rgb = {static_cast<std::uint8_t>(40 + 50 * i), static_cast<std::uint8_t>(60 + 60 * j),
               static_cast<std::uint8_t>(220 - 40 * i)};
      e.keyframe = (i + j) % 4;
      e.count = 1u + 37u * static_cast<unsigned>(i * 4 + j);
      out.push_back(e);
    }
  return out;
}

std::vector<Ellipsoid> gridMap() {
  std::vector<Ellipsoid> out;
  for (const render::EllipsoidInstance& g : gridEllipsoids()) {
    Ellipsoid e;
    e.mean = {g.mean.x, g.mean.y, g.mean.z};
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) e.cov(r, c) = g.cov[c][r];
    e.color = {float(g.rgb.r), float(g.rgb.g), float(g.rgb.b)};
    e.keyframe = g.keyframe;
    e.count = g.count;
    out.push_back(e);
  }
  return out;
}

PinholeCamera smallCamera() {
  PinholeCamera c;
  c.width = 160;
  c.height = 120;
  c.fx = c.fy = 150.0;
  c.cx = 79.5;
  c.cy = 59.5;
  return c;
}

cv::Mat testCard() {
  cv::Mat img(120, 160, CV_8UC3);
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      const bool check = ((u / 10) + (v / 10)) % 2 == 0;
      img.at<cv::Vec3b>(v, u) =
          cv::Vec3b(static_cast<uchar>(u * 255 / 159), static_cast<uchar>(v * 255 / 119), check ? 200 : 60);
    }
  return img;
}

render::ColoredMesh cubeOnFloor() {
  render::ColoredMesh m;
  auto quad = [&m](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::u8vec3 color) {
    const unsigned base = static_cast<unsigned>(m.positions.size());
    m.positions.insert(m.positions.end(), {a, b, c, d});
    m.colors.insert(m.colors.end(), 4, color);
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  };
  quad({-1.5f, -1.5f, 0}, {1.5f, -1.5f, 0}, {1.5f, 1.5f, 0}, {-1.5f, 1.5f, 0}, {150, 150, 140});
  const float h = 0.5f;
  const glm::vec3 o(0, 0, h);
  auto v = [&](float x, float y, float z) { return o + glm::vec3(x, y, z) * h; };
  quad(v(-1, -1, 1), v(1, -1, 1), v(1, 1, 1), v(-1, 1, 1), {230, 60, 50});       // top
  quad(v(-1, -1, -1), v(1, -1, -1), v(1, -1, 1), v(-1, -1, 1), {60, 200, 80});   // -y
  quad(v(1, -1, -1), v(1, 1, -1), v(1, 1, 1), v(1, -1, 1), {50, 90, 230});       // +x
  quad(v(-1, 1, -1), v(-1, -1, -1), v(-1, -1, 1), v(-1, 1, 1), {230, 200, 40});  // -x
  quad(v(1, 1, -1), v(-1, 1, -1), v(-1, 1, 1), v(1, 1, 1), {200, 60, 200});      // +y
  return m;
}

std::vector<Transform> ringOfKeyframes(int n) {
  std::vector<Transform> poses;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    const Eigen::Vector3d eye(1.5 * std::cos(a), 1.5 * std::sin(a), 1.0);
    const Eigen::Vector3d z = (-eye).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Transform T = Transform::Identity();
    T.linear() << x, y, z;
    T.translation() = eye;
    poses.push_back(T);
  }
  return poses;
}

std::filesystem::path builtinSequence(int frames) {
  namespace fs = std::filesystem;
  const fs::path folder = sharedCache() / ("sequence-" + std::to_string(frames));
  if (fs::exists(folder / "rgb.txt")) return folder;
  try {
    render::writeBuiltinSequence(folder, {.frames = frames});  // written beside, renamed into place
  } catch (const std::exception&) {
    if (!fs::exists(folder / "rgb.txt")) throw;  // another test process put it there first
  }
  return folder;
}

}  // namespace vdmap::test
