#include "app/bench/surface_timing.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>

#include "app/bench/tsdf_peer.h"
#include "app/bench/vdmap_timing.h"
#include "app/view/progress.h"
#include "mapping/core/timing.h"
#include "mapping/files/ply_writer.h"
#include "mapping/io/json_text.h"
#include "mapping/mesh/surface_mesh.h"

namespace vdmap::app {
namespace {

struct SurfaceRow {
  std::string name, file, note;
  double mesh_ms = 0;  ///< CPU time of the mesh extraction
  ColoredTriangleMesh mesh;
  std::optional<SurfaceAccuracyReport> accuracy;
};

SurfaceRow vdmapSurface(const BenchInput& in) {
  SurfaceRow row{"vdmap " + std::to_string(in.args.local_map.cell_size_px) + " px", "surface_vdmap.ply", "", 0, {}, {}};
  Mapper mapper(in.cam, pipelineParams(in.args));
  ProgressBar progress(row.name, in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    mapper.addFrame(in.frames[i]);
    progress.update(i + 1);
  }
  GlobalMapParams global;
  global.threads = 1;
  const GlobalMap map = buildGlobalMap(mapper.graph(), global);
  MeshParams params;
  params.threads = 1;
  params.model = global.filter.model;
  row.mesh_ms = cpuTimeMs([&] { row.mesh = buildSurfaceMesh(mapper.graph(), map.kept, params); });
  return row;
}

SurfaceRow open3dSurface(const BenchInput& in, double voxel_m) {
  char name[64];
  std::snprintf(name, sizeof name, "Open3D TSDF %.2f m", voxel_m);
  char file[64];
  std::snprintf(file, sizeof file, "surface_open3d_%.2f.ply", voxel_m);
  SurfaceRow row{name, file, "", 0, {}, {}};
  std::unique_ptr<TsdfVolume> volume =
      TsdfVolume::open(voxel_m, 4 * voxel_m, in.cam, in.args.local_map.depth_range.max_m, &row.note);
  if (!volume) return row;
  ProgressBar progress(row.name, in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    volume->integrate(in.frames[i]);
    progress.update(i + 1);
  }
  row.mesh_ms = cpuTimeMs([&] { row.mesh = volume->extractMesh(); });
  return row;
}

// The reference samples some frame saw: in front of its camera, inside its image, and within 5 cm
// (well above the depth noise, well below a room's depth steps) of the depth it measured there.
std::vector<bool> seenSamples(const BenchInput& in, const std::vector<Eigen::Vector3f>& samples) {
  std::vector<bool> seen(samples.size(), false);
  for (const RgbdFrame& f : in.frames) {
    const Transform T_C_W = f.T_W_C.inverse();
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (seen[i]) continue;
      const Eigen::Vector3d p = T_C_W * samples[i].cast<double>();
      if (!(p.z() > 0.0)) continue;
      const Eigen::Vector2d uv = in.cam.project(p);
      const long u = std::lround(uv.x()), v = std::lround(uv.y());
      if (u < 0 || v < 0 || u >= in.cam.width || v >= in.cam.height) continue;
      const double d = f.depth.at<std::uint16_t>(static_cast<int>(v), static_cast<int>(u)) / in.cam.depth_scale;
      seen[i] = d > 0.0 && std::abs(d - p.z()) < 0.05;
    }
  }
  return seen;
}

}  // namespace

void runSurfaceBench(const BenchInput& in, const std::filesystem::path& out_dir) {
  std::vector<SurfaceRow> rows;
  rows.push_back(vdmapSurface(in));
  for (const double voxel : {0.02, 0.01})
    if (!in.args.no_open3d) rows.push_back(open3dSurface(in, voxel));
  AccuracyParams accuracy;
  accuracy.completion_samples = in.args.completion_samples;
  accuracy.completion_within_m = 0.02;
  std::filesystem::create_directories(out_dir);
  const std::vector<bool> seen =
      in.mesh ? seenSamples(in, sampleMeshSurface(*in.mesh, accuracy.completion_samples, accuracy.seed))
              : std::vector<bool>{};
  nlohmann::json json = nlohmann::json::array();
  std::printf("%-22s %10s %10s %10s %12s %12s %10s  %s\n", "method", "triangles", "median mm", "p95 mm", "complete 2cm",
              "of the seen", "mesh ms", "file");
  for (SurfaceRow& row : rows) {
    if (!row.note.empty()) {
      std::printf("%-22s (did not run: %s)\n", row.name.c_str(), row.note.c_str());
      continue;
    }
    writeMeshPly(out_dir / row.file, row.mesh);
    if (in.mesh) row.accuracy = evaluateSurfaceAccuracy(row.mesh, *in.mesh, accuracy, seen);
    const SurfaceAccuracyReport a = row.accuracy.value_or(SurfaceAccuracyReport{});
    std::printf("%-22s %10zu %10.2f %10.2f %11.1f%% %11.1f%% %10.0f  %s\n", row.name.c_str(), row.mesh.triangles.size(),
                a.median_mm, a.p95_mm, 100 * a.completion_ratio, 100 * a.seen_completion_ratio, row.mesh_ms,
                (out_dir / row.file).c_str());
    nlohmann::json r = {{"method", row.name},
                        {"file", row.file},
                        {"triangles", row.mesh.triangles.size()},
                        {"mesh_ms", rounded(row.mesh_ms)}};
    if (row.accuracy)
      r.update({{"median_mm", rounded(a.median_mm)},
                {"p95_mm", rounded(a.p95_mm)},
                {"rmse_mm", rounded(a.rmse_mm)},
                {"completion_2cm", rounded(a.completion_ratio)},
                {"seen_completion_2cm", rounded(a.seen_completion_ratio)}});
    json.push_back(r);
  }
  std::ofstream(out_dir / "surfaces.json") << jsonText(json) << "\n";
}

}  // namespace vdmap::app
