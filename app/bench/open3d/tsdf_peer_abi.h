#pragma once
// The C interface of the optional Open3D TSDF peer (app/bench/open3d/open3d_tsdf_peer.cpp), a plugin that
// `vdmap bench` loads with dlopen. Open3D links GLFW, GLEW, GLX and libOpenGL; keeping it out
// of the vdmap binary keeps their gl* symbols away from the OSMesa renderer, and keeps the core
// free of the dependency. Plain C types only, so the plugin and vdmap share no C++ ABI.
#include <cstddef>
#include <cstdint>

extern "C" {

/// One TSDF volume. Camera intrinsics in pixels, depth raw units per metre, truncation and
/// voxel edge in metres; depth beyond depth_max_m is ignored. Returns null on failure.
typedef void* (*VdmapTsdfCreateFn)(double voxel_m, double sdf_trunc_m, int width, int height, double fx, double fy,
                                   double cx, double cy, double depth_scale, double depth_max_m);
/// Integrates one frame (rgb: 8-bit RGB rows, depth: 16-bit rows, both width x height packed;
/// T_W_C: column-major 4x4 camera-to-world). Returns the process CPU time of Open3D's own work
/// in milliseconds (the RGBD image conversion and the integration), OpenMP pinned to one thread.
typedef double (*VdmapTsdfIntegrateFn)(void* volume, const std::uint8_t* rgb, const std::uint16_t* depth,
                                       const double* T_W_C);
/// Extracts the volume's surface points (world frame, metres): calls sink once with n points
/// as x y z doubles. Returns the number of points.
typedef std::size_t (*VdmapTsdfExtractFn)(void* volume, void (*sink)(void* ctx, const double* xyz, std::size_t n),
                                          void* ctx);
/// Extracts the volume's triangle mesh (marching cubes; world frame, metres): calls sink once with the
/// vertices as x y z doubles, their colours as r g b doubles in 0..1 and the triangles as vertex
/// index triples. Returns the number of triangles.
typedef std::size_t (*VdmapTsdfExtractMeshFn)(void* volume,
                                              void (*sink)(void* ctx, const double* xyz, const double* rgb,
                                                           std::size_t vertices, const int* triangles,
                                                           std::size_t triangle_count),
                                              void* ctx);
typedef void (*VdmapTsdfDestroyFn)(void* volume);
}
