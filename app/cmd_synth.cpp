// vdmap synth: renders a coloured mesh along a trajectory into a TUM RGB-D sequence, or writes
// the built-in scene.
#include <cstdint>
#include <cstdio>

#include "app/cli/command_line.h"
#include "app/cli/sequence_args.h"
#include "app/verbs.h"
#include "app/view/progress.h"
#include "mapping/io/camera_config.h"
#include "mapping/synth/builtin_scene.h"
#include "render/sequence_synth.h"

namespace vdmap::app {
namespace {

struct SynthArgs {
  std::string mesh, trajectory, camera, noise = "nguyen2012", frames, out;
  bool builtin = false;
  int builtin_frames = BuiltinSceneParams{}.frames;
  int builtin_laps = BuiltinSceneParams{}.laps;
  std::uint64_t seed = DepthNoiseParams{}.seed;
};

// The built-in walk's bounds: a lap needs 2 poses (its first and last are neighbours); a million
// poses a lap (9 hours at 30 fps) and 1000 laps keep every pose's index within an int.
constexpr int kMaxBuiltinFrames = 1'000'000;
constexpr int kMaxBuiltinLaps = 1000;

void runSynth(const SynthArgs& args) {
  render::SynthOptions options;
  options.noise.model = parseDepthNoiseModel(args.noise);
  options.noise.seed = args.seed;
  if (!args.frames.empty()) {
    const FrameRange range = parseFrameRange(args.frames);
    options.first_frame = range.first;
    options.last_frame = range.last;
  }
  ColoredTriangleMesh mesh;
  std::vector<StampedPose> trajectory;
  if (args.builtin) {
    BuiltinSceneParams params;
    params.frames = args.builtin_frames;
    params.laps = args.builtin_laps;
    BuiltinScene scene = makeBuiltinScene(params);
    mesh = std::move(scene.mesh);
    trajectory = std::move(scene.trajectory);
    options.camera = args.camera.empty() ? scene.camera : cameraPreset(args.camera);
    options.write_mesh = true;
  } else {
    if (args.mesh.empty() || args.trajectory.empty() || args.camera.empty())
      throw CLI::RequiredError("give --mesh PLY --trajectory TUM_TXT --camera PRESET (or --builtin)",
                               CLI::ExitCodes::RequiredError);
    options.camera = cameraPreset(args.camera);
    mesh = readPlyMesh(args.mesh);
    trajectory = readTumTrajectory(args.trajectory);
    if (trajectory.empty()) throw std::invalid_argument(args.trajectory + ": no poses");
  }
  if (options.noise.model == DepthNoiseModel::kNone) options.noise.max_range_m = 1e9;  // only the 16-bit limit
  // --frames counts poses of the trajectory, as it counts depth frames of a sequence: a range
  // past the end is an error, and the echo shows the range rendered.
  const int poses = static_cast<int>(trajectory.size());
  const FrameRange range{options.first_frame, options.last_frame < 0 ? poses : options.last_frame};
  if (range.first >= poses || range.last > poses)
    throw std::invalid_argument("--frames " + args.frames + " ends past the trajectory: it has " +
                                std::to_string(poses) + " poses (0:" + std::to_string(poses) + ")");
  options.last_frame = range.last;
  ProgressBar progress("rendering", static_cast<std::size_t>(range.last - range.first));
  options.progress = [&progress](std::size_t done, std::size_t) { progress.update(done); };
  render::synthesizeSequence(mesh, trajectory, options, args.out);
  std::printf("wrote %s: %s (poses %s of %d) %dx%d, noise %s, %s\n", args.out.c_str(),
              counted(range.last - range.first, "frame").c_str(), frameRangeText(range).c_str(), poses,
              options.camera.width, options.camera.height, args.noise.c_str(),
              counted(static_cast<long long>(mesh.triangles.size()), "triangle").c_str());
}

}  // namespace

void addSynthCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("synth", "Render a coloured mesh along a trajectory into a TUM RGB-D sequence");
  auto args = std::make_shared<SynthArgs>();
  CLI::Option* mesh = verb->add_option("--mesh", args->mesh, "triangle mesh PLY with vertex colours");
  CLI::Option* trajectory =
      verb->add_option("--trajectory", args->trajectory, "TUM trajectory (timestamp tx ty tz qx qy qz qw, T_W_C)");
  verb->add_option("--camera", args->camera, "camera preset: " + cameraPresetList())->check(cameraPresetCheck());
  verb->add_option("--noise", args->noise, "depth sensor model: none | nguyen2012")
      ->check(CLI::IsMember({"none", "nguyen2012"}))
      ->capture_default_str();
  verb->add_option("--frames", args->frames,
                   "poses A:B of the trajectory (B exclusive; A: or :B; a plain N means 0:N); a range past the end "
                   "is an error")
      ->check(frameRangeCheck());
  // CLI11 would take -1 as 2^64 - 1 (it wraps when converting to an unsigned integer).
  verb->add_option("--seed", args->seed,
                   "seed of the depth noise, 0..2^64-1 (another seed: another draw of the same noise)")
      ->check(parsedBy(
          [](const std::string& text) {
            if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos)
              throw std::invalid_argument("expected a whole number 0..2^64-1, got '" + text + "'");
          },
          "N >= 0"))
      ->capture_default_str();
  CLI::Option* builtin =
      verb->add_flag("--builtin", args->builtin, "write the built-in scene (procedural room and walk) and its mesh.ply")
          ->excludes(mesh)
          ->excludes(trajectory);
  verb->add_option("--builtin-frames", args->builtin_frames,
                   "poses per lap of the built-in walk, 2.." + std::to_string(kMaxBuiltinFrames))
      ->check(CLI::Range(2, kMaxBuiltinFrames))
      ->needs(builtin)
      ->capture_default_str();
  verb->add_option("--builtin-laps", args->builtin_laps,
                   "laps of the built-in walk, 1.." + std::to_string(kMaxBuiltinLaps) +
                       "; each further lap takes new viewpoints (8 laps: 133 keyframes)")
      ->check(CLI::Range(1, kMaxBuiltinLaps))
      ->needs(builtin)
      ->capture_default_str();
  verb->add_option("--out", args->out, "output folder (must not exist or be empty)")->required();
  verb->callback([args] { runSynth(*args); });
}

}  // namespace vdmap::app
