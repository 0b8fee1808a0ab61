#pragma once
// The data sets' own folder layouts (7-Scenes, NICE-SLAM's Replica, ScanNet's export) written from
// a TUM-layout folder's frames, so a test can check that each layout reads as the same frames.
#include <filesystem>

#include "mapping/sequence/sequence.h"

namespace vdmap::test {

struct LayoutOptions {
  int frames = 30;          ///< the first N frames of the TUM folder, numbered as there
  bool colour_png = false;  ///< 7-Scenes: frame-N.color.png (as the original) instead of .color.jpg
};

/// Writes frames 0..N-1 of `tum_folder` (opened with its own camera) into `out` in the layout of
/// `kind` (kSevenScenes, kReplica or kScanNet): images copied (re-encoded losslessly for a PNG),
/// poses as 4x4 matrices with every digit, the camera as the layout stores it.
void writeDataSetLayout(SequenceKind kind, const std::filesystem::path& tum_folder, const std::filesystem::path& out,
                        const LayoutOptions& options = {});

/// Writes a TUM folder of frames first, first + step, ... (< last) of `tum_folder`: its lists,
/// images (copied) and ground truth, so a recording of those frames can be compared with it.
void writeTumSubset(const std::filesystem::path& tum_folder, const std::filesystem::path& out, int first, int last,
                    int step);

}  // namespace vdmap::test
