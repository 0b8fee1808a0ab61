#include "mapping/files/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "mapping/core/atomic_file.h"

namespace vdmap {

const char* upAxisName(UpAxis up) {
  switch (up) {
    case UpAxis::kPlusZ: return "+z";
    case UpAxis::kMinusZ: return "-z";
    case UpAxis::kPlusY: return "+y";
    case UpAxis::kMinusY: return "-y";
    case UpAxis::kPlusX: return "+x";
    case UpAxis::kMinusX: return "-x";
  }
  return "?";
}

UpAxis parseUpAxis(const std::string& text) {
  for (const UpAxis up :
       {UpAxis::kPlusZ, UpAxis::kMinusZ, UpAxis::kPlusY, UpAxis::kMinusY, UpAxis::kPlusX, UpAxis::kMinusX})
    if (text == upAxisName(up)) return up;
  throw std::invalid_argument("expected one of +z, -z, +y, -y, +x, -x, got '" + text + "'");
}

std::pair<double, double> parseGridBand(const std::string& text) {
  const auto colon = text.find(':');
  const auto value = [&text](const std::string& part) {
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (part.empty() || *end != '\0' || !std::isfinite(v))
      throw std::invalid_argument("'" + text + "': expected LO:HI, two finite heights in metres with LO < HI");
    return v;
  };
  if (colon == std::string::npos) value("");
  const double lo = value(text.substr(0, colon)), hi = value(text.substr(colon + 1));
  if (!(lo < hi)) throw std::invalid_argument("'" + text + "': expected LO:HI with LO < HI");
  return {lo, hi};
}

void gridAxes(UpAxis up, Eigen::Vector3d* u, Eigen::Vector3d* v, Eigen::Vector3d* w) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  switch (up) {
    case UpAxis::kPlusZ: *u = x, *v = y, *w = z; break;
    case UpAxis::kMinusZ: *u = x, *v = -y, *w = -z; break;
    case UpAxis::kPlusY: *u = z, *v = x, *w = y; break;
    case UpAxis::kMinusY: *u = x, *v = z, *w = -y; break;
    case UpAxis::kPlusX: *u = y, *v = z, *w = x; break;
    case UpAxis::kMinusX: *u = z, *v = y, *w = -x; break;
  }
}

void OccupancyGridSpec::validate() const {
  if (!(resolution_m > 0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("the grid resolution must be a finite number > 0 m");
  if (!std::isfinite(band_lo_m) || !std::isfinite(band_hi_m) || !(band_lo_m < band_hi_m))
    throw std::invalid_argument("the grid band LO:HI must have finite ends and LO < HI");
}

OccupancyGridLayout layOutOccupancyGrid(const QueryMap& map, const OccupancyGridSpec& spec) {
  spec.validate();
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  if (!(lo.array() <= hi.array()).all())
    throw std::invalid_argument(
        "the map sees nothing (no keyframe with a kept cell): there is no extent to lay a grid over");
  Eigen::Vector3d au, av, aw;
  gridAxes(spec.up, &au, &av, &aw);
  // The seen box's extent along u, v and w (the axes are signed unit axes, so its corners' extremes).
  double u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY, w_lo = INFINITY, w_hi = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d c((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                            (corner & 4) ? hi.z() : lo.z());
    u_lo = std::min(u_lo, au.dot(c)), u_hi = std::max(u_hi, au.dot(c));
    v_lo = std::min(v_lo, av.dot(c)), v_hi = std::max(v_hi, av.dot(c));
    w_lo = std::min(w_lo, aw.dot(c)), w_hi = std::max(w_hi, aw.dot(c));
  }
  const double res = spec.resolution_m;
  OccupancyGridLayout g;
  g.seen_lo_m = std::floor(w_lo / res) * res;
  g.seen_hi_m = std::ceil(w_hi / res) * res;
  g.band_lo_m = std::max(spec.band_lo_m, g.seen_lo_m);
  g.band_hi_m = std::min(spec.band_hi_m, g.seen_hi_m);
  g.clipped = g.band_lo_m != spec.band_lo_m || g.band_hi_m != spec.band_hi_m;
  char text[320];
  if (!(g.band_lo_m < g.band_hi_m)) {
    std::snprintf(text, sizeof text,
                  "the band %g:%g m lies outside the map's %.2f:%.2f m along %s: give a band within it", spec.band_lo_m,
                  spec.band_hi_m, g.seen_lo_m, g.seen_hi_m, upAxisName(spec.up));
    throw std::invalid_argument(text);
  }
  g.origin_m = {std::floor(u_lo / res) * res, std::floor(v_lo / res) * res};
  const double width = std::max(1.0, std::ceil((u_hi - g.origin_m.x()) / res));
  const double height = std::max(1.0, std::ceil((v_hi - g.origin_m.y()) / res));
  if (width * height > static_cast<double>(kMaxGridCells)) {
    std::snprintf(text, sizeof text,
                  "a grid of resolution %g m over the seen %.3g x %.3g m would have %.3g cells (at most %zu): give a "
                  "coarser resolution",
                  res, u_hi - u_lo, v_hi - v_lo, width * height, kMaxGridCells);
    throw std::invalid_argument(text);
  }
  // Sub-boxes: 2 x 2 per cell, `layers` along the band, each at most min(2 cm, res / 2) tall.
  const double layers = std::max(1.0, std::ceil((g.band_hi_m - g.band_lo_m) / std::min(0.02, res / 2) - 1e-9));
  g.samples = width * height * 4 * layers;
  if (g.samples > kMaxGridSamples) {
    std::snprintf(text, sizeof text,
                  "a grid of resolution %g m over the seen %.3g x %.3g m and the band %g:%g m would ask %.3g points "
                  "(at most %.3g): give a coarser resolution or a narrower band",
                  res, u_hi - u_lo, v_hi - v_lo, g.band_lo_m, g.band_hi_m, g.samples, kMaxGridSamples);
    throw std::invalid_argument(text);
  }
  g.width = static_cast<int>(width);
  g.height = static_cast<int>(height);
  g.layers = static_cast<int>(layers);
  return g;
}

std::string gridBandClipNote(const OccupancyGridSpec& spec, const OccupancyGridLayout& layout, const char* option) {
  if (!layout.clipped) return "";
  char text[256];
  std::snprintf(text, sizeof text, "%s %g:%g clipped to the map's %g:%g m along %s", option, spec.band_lo_m,
                spec.band_hi_m, layout.band_lo_m, layout.band_hi_m, upAxisName(spec.up));
  return text;
}

OccupancyGrid computeOccupancyGrid(const QueryMap& map, const OccupancyGridSpec& spec, const ExportProgress& progress) {
  const OccupancyGridLayout layout = layOutOccupancyGrid(map, spec);
  Eigen::Vector3d au, av, aw;
  gridAxes(spec.up, &au, &av, &aw);
  const double res = spec.resolution_m;
  OccupancyGrid grid;
  grid.resolution_m = res;
  grid.up = spec.up;
  grid.origin_m = layout.origin_m;
  grid.width = layout.width;
  grid.height = layout.height;
  grid.cells.assign(static_cast<std::size_t>(grid.width) * grid.height, kGridUnknown);

  const int layers = layout.layers;
  const double hz = (layout.band_hi_m - layout.band_lo_m) / layers, hxy = res / 2;
  const double half_diagonal = 0.5 * std::sqrt(2 * hxy * hxy + hz * hz);
  const std::size_t per_cell = 4 * static_cast<std::size_t>(layers);
  std::vector<Eigen::Vector3d> samples(static_cast<std::size_t>(grid.width) * per_cell);
  std::vector<DistanceResult> distances(samples.size());
  std::vector<Eigen::Vector3d> open_samples;
  std::vector<Classification> classes;
  std::vector<int> open_cells;
  for (int row = 0; row < grid.height; ++row) {
    const int j = grid.height - 1 - row;  // row 0 is the largest v
    for (int i = 0; i < grid.width; ++i)
      for (int s = 0; s < 4; ++s)
        for (int l = 0; l < layers; ++l) {
          const double u = grid.origin_m.x() + (i + 0.25 + 0.5 * (s & 1)) * res;
          const double v = grid.origin_m.y() + (j + 0.25 + 0.5 * (s >> 1)) * res;
          const double w = layout.band_lo_m + (l + 0.5) * hz;
          samples[static_cast<std::size_t>(i) * per_cell + s * layers + l] = u * au + v * av + w * aw;
        }
    // Distances stop early past twice the half-diagonal: beyond it only "farther" matters.
    map.distance(samples, distances, 2 * half_diagonal);
    grid.samples += samples.size();
    open_cells.clear();
    open_samples.clear();
    std::uint8_t* cells = grid.cells.data() + static_cast<std::size_t>(row) * grid.width;
    for (int i = 0; i < grid.width; ++i) {
      bool occupied = false;
      for (std::size_t k = 0; k < per_cell && !occupied; ++k)
        occupied = distances[static_cast<std::size_t>(i) * per_cell + k].distance_m <= half_diagonal;
      if (occupied) {
        cells[i] = kGridOccupied;
        continue;
      }
      open_cells.push_back(i);
      for (std::size_t k = 0; k < per_cell; ++k)
        open_samples.push_back(samples[static_cast<std::size_t>(i) * per_cell + k]);
    }
    classes.resize(open_samples.size());
    map.classify(open_samples, classes);
    grid.samples += open_samples.size();
    for (std::size_t c = 0; c < open_cells.size(); ++c)
      for (std::size_t k = 0; k < per_cell; ++k)
        if (classes[c * per_cell + k].state == Occupancy::kFree) {
          cells[open_cells[c]] = kGridFree;
          break;
        }
    if (progress) progress(static_cast<std::size_t>(row + 1), static_cast<std::size_t>(grid.height));
  }
  for (const std::uint8_t c : grid.cells) {
    grid.occupied += c == kGridOccupied;
    grid.free += c == kGridFree;
    grid.unknown += c == kGridUnknown;
  }
  return grid;
}

std::string occupancyGridPgm(const OccupancyGrid& grid) {
  std::string bytes = "P5\n# vdmap occupancy grid (docs/cli.md query)\n" + std::to_string(grid.width) + " " +
                      std::to_string(grid.height) + "\n255\n";
  bytes.append(reinterpret_cast<const char*>(grid.cells.data()), grid.cells.size());
  return bytes;
}

std::string occupancyGridYaml(const OccupancyGrid& grid, const std::string& image_name) {
  Eigen::Vector3d au, av, aw;
  gridAxes(grid.up, &au, &av, &aw);
  const auto axis = [](const Eigen::Vector3d& a) {
    const int k = a.cwiseAbs().maxCoeff() == std::abs(a.x()) ? 0 : (std::abs(a.y()) == 1 ? 1 : 2);
    return std::string(a[k] < 0 ? "-" : "+") + "xyz"[k];
  };
  char text[1024];
  std::snprintf(text, sizeof text,
                "# vdmap occupancy grid: up %s, grid x = world %s, grid y = world %s; %d x %d cells\n"
                "image: %s\nmode: trinary\nresolution: %.9g\norigin: [%.9g, %.9g, 0.0]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
                upAxisName(grid.up), axis(au).c_str(), axis(av).c_str(), grid.width, grid.height, image_name.c_str(),
                grid.resolution_m, grid.origin_m.x(), grid.origin_m.y());
  return text;
}

void writeOccupancyGrid(const std::filesystem::path& yaml_file, const OccupancyGrid& grid) {
  std::filesystem::path image = yaml_file;
  image.replace_extension(".pgm");
  writeFileAtomically(image, occupancyGridPgm(grid));
  writeFileAtomically(yaml_file, occupancyGridYaml(grid, image.filename().string()));
}

}  // namespace vdmap
