#pragma once
// Synthetic RGB-D sequences: a coloured mesh rendered along a trajectory (OSMesa), depth passed
// through the sensor model of mapping/synth/depth_noise.h, written in the TUM layout.
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/files/ply_reader.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/synth/builtin_scene.h"
#include "mapping/synth/depth_noise.h"
#include "render/context.h"

namespace vdmap::render {

/// One rendered view: rgb (CV_8UC3, RGB order, unshaded vertex colours), and CV_32FC2 with
/// camera z in metres (0 where no surface) and |cos| of the incidence angle.
struct SyntheticView {
  cv::Mat rgb;
  cv::Mat z_cos;
};

/// Renders a mesh from camera poses at the camera's resolution and intrinsics. Needs the given
/// context current; owns its GPU resources.
class MeshViewRenderer {
 public:
  MeshViewRenderer(Context& context, const ColoredTriangleMesh& mesh, const PinholeCamera& camera);
  ~MeshViewRenderer();
  SyntheticView render(const Transform& T_W_C);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct SynthOptions {
  PinholeCamera camera;
  DepthNoiseParams noise;
  int first_frame = 0;  ///< of the trajectory, half-open [first, last)
  int last_frame = -1;  ///< -1: to the end
  /// Written into the folder as camera.yaml so the sequence opens with the right intrinsics.
  bool write_camera_file = true;
  /// Also mesh.ply, the rendered mesh (the built-in scene's is made in code: with it `vdmap eval
  /// --mesh` scores maps of the sequence).
  bool write_mesh = false;
  /// Called after each frame with (done, total).
  std::function<void(std::size_t, std::size_t)> progress;
  /// Asked before each frame is rendered: true stops the rendering (SynthCancelled).
  std::function<bool()> cancelled;
};

/// Thrown by synthesizeSequence when SynthOptions::cancelled says so; nothing is left behind.
struct SynthCancelled : std::runtime_error {
  std::size_t done = 0, total = 0;  ///< frames rendered when it stopped, of those asked for
  SynthCancelled(std::size_t done_frames, std::size_t total_frames)
      : std::runtime_error("cancelled after " + std::to_string(done_frames) + " of " + std::to_string(total_frames) +
                           " frames"),
        done(done_frames), total(total_frames) {}
};

/// Renders `trajectory` (T_W_C with timestamps) into the TUM folder `out_dir`: rgb/NNNNNN.png,
/// depth/NNNNNN.png (16-bit), rgb.txt, depth.txt, groundtruth.txt, camera.yaml (mesh.ply with
/// SynthOptions::write_mesh). Everything is
/// written into a sibling temporary folder first and renamed at the end, so a failure or a
/// cancel leaves nothing behind. Throws std::invalid_argument when `out_dir` exists and is not
/// empty or the frame range selects nothing, SynthCancelled when cancelled, std::runtime_error
/// on rendering/IO failures.
void synthesizeSequence(const ColoredTriangleMesh& mesh, const std::vector<StampedPose>& trajectory,
                        const SynthOptions& options, const std::filesystem::path& out_dir);

/// Writes the built-in scene (mapping/synth/builtin_scene.h) as a sequence into `out_dir`
/// with the nguyen2012 sensor model; `params` choose the walk (default: one lap of 300 frames;
/// e.g. `.laps = 8`: 2400 frames, a long run).
void writeBuiltinSequence(const std::filesystem::path& out_dir, const BuiltinSceneParams& params = {},
                          std::function<void(std::size_t, std::size_t)> progress = {},
                          std::function<bool()> cancelled = {});

}  // namespace vdmap::render
