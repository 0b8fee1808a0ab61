#pragma once
// Binary little-endian PLY exports (docs/method.md 11).

#include <filesystem>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "mapping/files/ply_reader.h"
#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap {

/// The covariance as the ellipsoid PLY stores it: rounded to float and positive semi-definite in
/// that form (computed in double). A flat cell's smallest eigenvalue can fall a few 1e-12 m^2
/// below zero through float accumulation or rounding; such a matrix is rebuilt from its
/// eigen-decomposition with the eigenvalues clamped at 1e-7 of the largest (raised tenfold until
/// the float matrix passes). Any other matrix is only rounded to float.
Eigen::Matrix3f storedCovariance(const Eigen::Matrix3d& cov);

/// Writes ellipsoids as binary little-endian PLY: x y z float, red green blue uchar,
/// cxx cxy cxz cyy cyz czz float (storedCovariance), count uint, keyframe int (docs/method.md 11). Writes to a
/// temporary name in the same folder and renames it, so an interrupted export leaves no
/// half-written file. Throws std::runtime_error naming the file on an I/O failure.
void writeEllipsoidPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids);

using EllipsoidVisitor = std::function<void(const Ellipsoid&)>;
/// Calls its argument with each ellipsoid in order.
using EllipsoidSource = std::function<void(const EllipsoidVisitor&)>;

/// writeEllipsoidPly of the `count` ellipsoids `source` visits, written as they come (the local
/// maps need not be gathered into one vector first). Throws std::logic_error when the source
/// visits another number.
void writeEllipsoidPly(const std::filesystem::path& file, std::size_t count, const EllipsoidSource& source);

/// Writes a coloured triangle mesh as readPlyMesh reads it: binary little-endian PLY, vertices x y
/// z float, red green blue uchar (then nx ny nz float when mesh.normals is not empty), faces as uint
/// vertex_indices lists. Atomic like writeEllipsoidPly.
void writeMeshPly(const std::filesystem::path& file, const ColoredTriangleMesh& mesh);

/// Writes the mesh as Wavefront OBJ text: `v x y z r g b` (colour 0..1), `vn` when mesh.normals is not
/// empty, faces `f a//a b//b c//c` (1-based). Atomic like writeEllipsoidPly.
void writeMeshObj(const std::filesystem::path& file, const ColoredTriangleMesh& mesh);

/// writeMeshObj for a name ending in .obj (any case), else writeMeshPly.
void writeMeshFile(const std::filesystem::path& file, const ColoredTriangleMesh& mesh);

/// Writes the ellipsoid means as a coloured point cloud: binary little-endian PLY, x y z float,
/// red green blue uchar (docs/method.md 11). Atomic like writeEllipsoidPly.
void writePointPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids);

/// Opacity written into the Gaussian PLY before the viewers' sigmoid: alpha = 0.9. docs/method.md 11 is
/// silent; nearly opaque splats show the surface, 0.9 rather than 1 lets overlaps blend.
inline constexpr float kGaussianOpacityLogit = 2.1972246f;  // log(0.9 / 0.1)
/// Smallest principal standard deviation written (m): a perfectly flat cell would give log(0).
inline constexpr double kGaussianMinSigma = 1e-5;

/// Higher-band spherical-harmonic coefficients per Gaussian (degree 3: 3 x 15), written as zeros.
inline constexpr int kGaussianRestCoefficients = 45;

/// Writes ellipsoids as 3-D Gaussian splats in the layout Gaussian-splatting viewers read
/// (docs/method.md 11): binary little-endian PLY, all float: x y z, nx ny nz (the axis of least
/// spread, the surface normal up to sign), f_dc_0..2 = (rgb/255 - 0.5) / 0.28209479,
/// f_rest_0..44 = 0 (kGaussianRestCoefficients), opacity
/// (kGaussianOpacityLogit), scale_0..2 = log(sigma) per principal axis (sigma clamped to
/// kGaussianMinSigma), rot_0..3 = unit quaternion w x y z of the proper rotation R whose columns
/// are the principal axes, so Sigma = R diag(exp(2 scale)) R^T. Atomic like writeEllipsoidPly.
void writeGaussianPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids);

}  // namespace vdmap
