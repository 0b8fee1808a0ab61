// vdmap mesh (S.vdmap | DIR) --out FILE: the surface mesh of a map's local maps (docs/method.md 14), as
// binary PLY or OBJ by the file's extension.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "app/cli/command_line.h"
#include "app/cli/mesh_options.h"
#include "app/verbs.h"
#include "mapping/core/error.h"
#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"
#include "mapping/files/map_file.h"
#include "mapping/files/ply_writer.h"
#include "mapping/files/session_file.h"
#include "mapping/io/json_text.h"

namespace vdmap::app {
namespace {

struct MeshArgs {
  std::string map;
  std::string out;
  std::string keyframe_poses;
  bool json = false;
  MeshOptions options;
  int threads = 0;
};

// The graph and the cells the map keeps: a session's local maps through its filter, a map folder's
// local_maps.ply (kept already).
struct MeshInput {
  KeyframeGraph graph;
  std::vector<std::vector<bool>> kept;
  SensorModel model = SensorModel::kNguyen2012;
};

MeshInput readMeshInput(const std::string& path, int threads) {
  namespace fs = std::filesystem;
  MeshInput in;
  if (isSessionPath(path)) {
    SessionDecodeOptions decode;
    decode.decode_images = false;  // the mesh needs the local maps and poses only
    Session session = loadSession(path, decode);
    in.graph = std::move(session.graph);
    in.model = session.info.global.filter.model;
    in.kept.resize(in.graph.size());
    parallelFor(threads, in.graph.size(), [&](std::size_t k) {
      in.kept[k] = keptCells(in.graph.keyframe(static_cast<int>(k)).container, session.info.global.filter);
    });
    return in;
  }
  if (!fs::exists(path))
    throw InputError(path, "no such file or folder (expected a session .vdmap or a `vdmap map` folder)");
  if (!fs::is_directory(path) || detectMapFile(path) != MapFileKind::kMapFolder)
    throw InputError(path, "not a session (.vdmap) or a `vdmap map` folder");
  in.graph = readMapFolderLocalMaps(path, &in.model);
  for (const Keyframe& k : in.graph.keyframes()) in.kept.emplace_back(k.container.size(), true);
  return in;
}

void runMesh(const MeshArgs& args) {
  namespace fs = std::filesystem;
  MeshParams params = args.options.over({});
  params.threads = args.threads;
  params.validate();
  checkMeshFileName(args.out);
  checkOutputFile(args.out, "--out");
  checkNotAnInput(args.out, "--out", {{"MAP", args.map}, {"--keyframe-poses", args.keyframe_poses}});
  const auto start = std::chrono::steady_clock::now();
  MeshInput in = readMeshInput(args.map, params.threads);
  if (!args.keyframe_poses.empty()) applyTrajectoryFile(in.graph, args.keyframe_poses);
  const double load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  params.model = in.model;
  MeshStats stats;
  ColoredTriangleMesh mesh;
  // The process's CPU time too: on a busy machine the wall time says little of the work.
  const double cpu_ms = cpuTimeMs([&] { mesh = buildSurfaceMesh(in.graph, in.kept, params, &stats); });
  if (mesh.triangles.empty())
    std::cerr << "vdmap mesh: note: " << args.map
              << (in.graph.size() ? " has no surface the filter kept" : " has no keyframes") << ": the mesh is empty\n";
  writeMeshFile(args.out, mesh);
  if (args.json) {
    const nlohmann::json out = {{"map", args.map},
                                {"out", args.out},
                                {"keyframes", in.graph.size()},
                                {"vertices", mesh.positions.size()},
                                {"triangles", mesh.triangles.size()},
                                {"piece_triangles", stats.piece_triangles},
                                {"covered_triangles", stats.covered_triangles},
                                {"estimate", meshEstimate(in.graph, in.kept, params.stride)},
                                {"load_ms", load_ms},
                                {"mesh_ms", stats.ms},
                                {"mesh_cpu_ms", cpu_ms}};
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::printf(
      "%zu vertices, %zu triangles from %zu keyframes (%zu of %zu piece triangles covered by better-supported keyframes); "
      "read in %.0f ms, meshed in %.0f ms (CPU %.0f ms) -> %s\n",
      mesh.positions.size(), mesh.triangles.size(), stats.keyframes, stats.covered_triangles, stats.piece_triangles,
      load_ms, stats.ms, cpu_ms, args.out.c_str());
}

}  // namespace

void addMeshCommand(CLI::App& app) {
  auto* verb = app.add_subcommand(
      "mesh", "A triangle mesh of a map's surfaces (docs/method.md 14): binary PLY, or OBJ for a .obj --out");
  auto args = std::make_shared<MeshArgs>();
  verb->add_option("MAP", args->map, "a session (.vdmap, vdmap map --save) or a `vdmap map` output folder")->required();
  verb->add_option("--out", args->out, "the mesh file: .ply (binary, colour and normal per vertex) or .obj")
      ->required();
  verb->add_option("--keyframe-poses", args->keyframe_poses,
                   "corrected keyframe poses (TUM, matched by keyframe timestamp): the mesh follows them, "
                   "nothing is re-integrated");
  addMeshOptions(*verb, args->options);
  verb->add_option("--threads", args->threads,
                   "threads, 0.." + std::to_string(kMaxThreads) + " (0: all); the mesh does not depend on it")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  verb->add_flag("--json", args->json, "print the figures as JSON");
  verb->callback([args] { runMesh(*args); });
}

}  // namespace vdmap::app
