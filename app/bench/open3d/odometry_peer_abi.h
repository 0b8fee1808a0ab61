#pragma once
// The C interface of the optional Open3D odometry peer (app/bench/open3d/open3d_odometry_peer.cpp), built
// into the same plugin as the TSDF peer (app/bench/open3d/tsdf_peer_abi.h says why it is a plugin). Plain C
// types only.
#include <cstdint>

extern "C" {

/// Frame-to-frame RGB-D odometry state. Camera intrinsics in pixels, depth raw units per metre.
/// Returns null on failure.
typedef void* (*VdmapOdometryCreateFn)(int width, int height, double fx, double fy, double cx, double cy,
                                       double depth_scale);
/// Registers the frame (rgb: 8-bit RGB rows, depth: 16-bit rows, packed) against the previous
/// one, OpenMP pinned to one thread: T_prev_cur receives the column-major 4x4 pose of this frame
/// in the previous frame's camera (identity for the first frame, or when registration fails).
/// Returns 1, or 0 when registration failed.
typedef int (*VdmapOdometryTrackFn)(void* odometry, const std::uint8_t* rgb, const std::uint16_t* depth,
                                    double* T_prev_cur);
typedef void (*VdmapOdometryDestroyFn)(void* odometry);
}
