#pragma once
// The built-in scene: a procedurally generated, textured room and a camera walk around it that
// returns to its start. Generated in code (no files in the repository); rendered into a TUM
// sequence by render/sequence_synth.h. World frame: z up, metres; the room spans
// x in [-2.5, 2.5], y in [-2, 2], z in [0, 2.6].
#include <vector>

#include "mapping/core/camera.h"
#include "mapping/files/ply_reader.h"
#include "mapping/io/trajectory_io.h"

namespace vdmap {

struct BuiltinSceneParams {
  int frames = 300;  ///< poses per lap (10 s at 30 fps); a lap's last is next to its first
  /// Laps of the walk. Lap 0 is the default walk; every further lap circles the table at
  /// another radius, height and gaze (a cycle of 8 variants), so that it sees the room from new
  /// viewpoints: a long run that keeps making keyframes (for the loop-closure cost) while still
  /// revisiting earlier ones.
  int laps = 1;
  double fps = 30.0;
  double texture_tile_m = 0.05;  ///< size of one flat-coloured texture tile
};

struct BuiltinScene {
  ColoredTriangleMesh mesh;
  std::vector<StampedPose> trajectory;  ///< T_W_C per frame, timestamps i / fps
  PinholeCamera camera;                 ///< tum-default, 640 x 480, depth scale 5000
};

/// Floor, walls and ceiling, a table, boxes, a shelf, a ball and a cylinder, each textured
/// with deterministic multi-scale blocky patterns (rich in ORB corners); the camera walks an
/// ellipse around the table looking outwards-forwards and ends where it began (a revisit).
/// Throws std::invalid_argument when frames < 2 or laps < 1.
BuiltinScene makeBuiltinScene(const BuiltinSceneParams& params = {});

}  // namespace vdmap
