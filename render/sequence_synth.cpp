#include "render/sequence_synth.h"

#include <cstdio>
#include <fstream>
#include <random>
#include <stdexcept>

#include <tbb/parallel_for_each.h>
#include <tbb/task_group.h>

#include "mapping/files/ply_writer.h"
#include "mapping/io/image_codec.h"
#include "mapping/synth/builtin_scene.h"
#include "render/framebuffer.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"

namespace vdmap::render {

namespace fs = std::filesystem;

struct MeshViewRenderer::Impl {
  Impl(Context& ctx, const PinholeCamera& cam)
      : context(ctx), camera(cam), framebuffer(ctx.gl(), cam.width, cam.height, true), mesh(ctx.gl()) {}
  Context& context;
  PinholeCamera camera;
  Framebuffer framebuffer;
  MeshRenderer mesh;
};

MeshViewRenderer::MeshViewRenderer(Context& context, const ColoredTriangleMesh& mesh, const PinholeCamera& camera) {
  context.makeCurrent();
  impl_ = std::make_unique<Impl>(context, camera);
  impl_->mesh.set(toColoredMesh(mesh));
  impl_->mesh.setShaded(false);
}

MeshViewRenderer::~MeshViewRenderer() = default;

SyntheticView MeshViewRenderer::render(const Transform& T_W_C) {
  ViewCamera view = ViewCamera::fromPinhole(impl_->camera, T_W_C, impl_->camera.width, impl_->camera.height);
  view.near_m = 0.02f;  // z itself comes from the float target; the planes only bound the scene
  view.far_m = 50.f;
  impl_->framebuffer.bindAndClear(0.f, 0.f, 0.f);
  impl_->mesh.draw(view);
  return {impl_->framebuffer.readRgb(), impl_->framebuffer.readFloat()};
}

namespace {

std::string frameName(int index) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", index);
  return name;
}

void writeCameraYaml(const fs::path& file, const PinholeCamera& c) {
  std::ofstream out(file);
  out.precision(10);
  out << "# written by vdmap synth\nfx: " << c.fx << "\nfy: " << c.fy << "\ncx: " << c.cx << "\ncy: " << c.cy
      << "\ndepth_scale: " << c.depth_scale << "\nwidth: " << c.width << "\nheight: " << c.height << "\n";
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

}  // namespace

void synthesizeSequence(const ColoredTriangleMesh& mesh, const std::vector<StampedPose>& trajectory,
                        const SynthOptions& options, const fs::path& out_dir) {
  options.camera.validate();
  const int n = static_cast<int>(trajectory.size());
  const int first = std::max(0, options.first_frame);
  const int last = options.last_frame < 0 ? n : std::min(n, options.last_frame);
  if (first >= last)
    throw std::invalid_argument("the frame range " + std::to_string(first) + ":" + std::to_string(last) +
                                " selects no pose of the " + std::to_string(n) + " in the trajectory");
  if (fs::exists(out_dir) && !fs::is_empty(out_dir))
    throw std::invalid_argument(out_dir.string() + ": exists and is not empty (choose a new folder)");
  // Everything goes into DIR.tmp-XXXXXX, renamed to DIR only when complete.
  std::random_device rd;
  char suffix[16];
  std::snprintf(suffix, sizeof suffix, ".tmp-%06x", static_cast<unsigned>(rd() & 0xffffff));
  const fs::path tmp = out_dir.string() + suffix;
  try {
    fs::create_directories(tmp / "rgb");
    fs::create_directories(tmp / "depth");
    std::unique_ptr<Context> context = createOffscreenContext();
    MeshViewRenderer renderer(*context, mesh, options.camera);
    std::ofstream rgb_list(tmp / "rgb.txt"), depth_list(tmp / "depth.txt");
    rgb_list << "# color images (vdmap synth)\n# timestamp filename\n";
    depth_list << "# depth images (vdmap synth), depth_scale " << options.camera.depth_scale
               << "\n# timestamp filename\n";
    rgb_list.precision(6);
    depth_list.precision(6);
    // The main thread renders (the GL context is current only there) while the previous batch
    // of frames gets its sensor noise and is written on the other threads. Each frame's noise
    // has its own seed, so the images do not depend on the thread count.
    constexpr int kBatch = 8;
    struct Pending {
      int index;
      SyntheticView view;
    };
    std::vector<Pending> writing;
    tbb::task_group writers;
    auto writeFrame = [&](const Pending& f) {
      const std::string name = frameName(f.index);
      writeImageFile(tmp / "rgb" / name, f.view.rgb);
      writeImageFile(tmp / "depth" / name,
                     simulateDepth(f.view.z_cos, options.camera.depth_scale, options.noise, f.index));
    };
    auto finishWriting = [&] {
      writers.wait();  // rethrows a writer's exception
      if (options.progress && !writing.empty()) options.progress(writing.back().index - first + 1, last - first);
      writing.clear();
    };
    try {
      for (int start = first; start < last; start += kBatch) {
        std::vector<Pending> batch;
        for (int i = start; i < std::min(last, start + kBatch); ++i) {
          if (options.cancelled && options.cancelled())  // within a frame of being asked
            throw SynthCancelled(static_cast<std::size_t>(i - first), static_cast<std::size_t>(last - first));
          batch.push_back({i, renderer.render(trajectory[i].T_W_C)});
        }
        finishWriting();
        writing = std::move(batch);
        writers.run([&] { tbb::parallel_for_each(writing.begin(), writing.end(), writeFrame); });
      }
      finishWriting();
    } catch (...) {
      writers.cancel();
      try {
        writers.wait();  // nothing may still write into tmp when it is removed
      } catch (...) {
      }
      throw;
    }
    std::vector<StampedPose> poses(trajectory.begin() + first, trajectory.begin() + last);
    for (int i = first; i < last; ++i) {
      const std::string name = frameName(i);
      rgb_list << std::fixed << trajectory[i].t << " rgb/" << name << "\n";
      depth_list << std::fixed << trajectory[i].t << " depth/" << name << "\n";
    }
    rgb_list.close();
    depth_list.close();
    if (!rgb_list || !depth_list) throw std::runtime_error(tmp.string() + ": cannot write the frame lists");
    writeTumTrajectory(tmp / "groundtruth.txt", poses, "ground truth T_W_C (vdmap synth)");
    if (options.write_camera_file) writeCameraYaml(tmp / "camera.yaml", options.camera);
    if (options.write_mesh) writeMeshPly(tmp / "mesh.ply", mesh);
    if (fs::exists(out_dir)) fs::remove(out_dir);  // an empty folder the caller made
    fs::rename(tmp, out_dir);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
}

void writeBuiltinSequence(const fs::path& out_dir, const BuiltinSceneParams& params,
                          std::function<void(std::size_t, std::size_t)> progress, std::function<bool()> cancelled) {
  const BuiltinScene scene = makeBuiltinScene(params);
  SynthOptions options;
  options.camera = scene.camera;
  options.progress = std::move(progress);
  options.cancelled = std::move(cancelled);
  options.write_mesh = true;
  synthesizeSequence(scene.mesh, scene.trajectory, options, out_dir);
}

}  // namespace vdmap::render
