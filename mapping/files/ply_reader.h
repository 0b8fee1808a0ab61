#pragma once
// PLY input: triangle meshes with vertex colours (ascii or binary, either endianness) and the
// ellipsoid layout of docs/method.md 11.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace vdmap {

/// A triangle mesh with one colour per vertex (world frame, metres).
struct ColoredTriangleMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<std::uint8_t, 3>> colors;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<Eigen::Vector3f> normals;  ///< one unit normal per vertex, or empty (readPlyMesh leaves it empty)
};

/// One ellipsoid as exported (docs/method.md 11): mean, colour, covariance, point count, keyframe.
struct EllipsoidRecord {
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  std::array<std::uint8_t, 3> rgb{};
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  std::uint32_t count = 0;
  std::int32_t keyframe = 0;
};

/// Reads a mesh: `vertex` with x y z and red green blue (uchar, or float in [0, 1]; alpha is
/// ignored) and `face` with a vertex_indices list (polygons are fan-triangulated). Throws
/// InputError naming the file when the header is malformed, the file is truncated, the mesh
/// has no faces or no vertex colours, or a face indexes a missing vertex.
ColoredTriangleMesh readPlyMesh(const std::filesystem::path& file);

/// Reads the vertex positions of any PLY with a `vertex` element holding x y z: a point cloud,
/// an ellipsoid export (its means) or a mesh (its vertices). Throws InputError as readPlyMesh.
std::vector<Eigen::Vector3f> readPlyPoints(const std::filesystem::path& file);

/// Reads ellipsoids: `vertex` with x y z, red green blue, cxx cxy cxz cyy cyz czz, and
/// optionally count and keyframe. Throws InputError as readPlyMesh.
std::vector<EllipsoidRecord> readPlyEllipsoids(const std::filesystem::path& file);

/// The scalar properties of a PLY's `vertex` element, whatever they are, every value as double.
struct PlyVertexTable {
  std::vector<std::string> names;  ///< scalar property names, in file order
  std::size_t count = 0;           ///< vertices
  std::vector<double> values;      ///< count x names.size(), row-major
  /// Column of `name`, or -1.
  int column(const std::string& name) const;
  double at(std::size_t row, int column) const { return values[row * names.size() + static_cast<std::size_t>(column)]; }
};

/// Reads the `vertex` element of any PLY (e.g. points or 3-D Gaussians). Throws InputError as
/// readPlyMesh.
PlyVertexTable readPlyVertices(const std::filesystem::path& file);

/// readPlyVertices one vertex at a time, so that a file of any size is read in the memory of one
/// vertex (elements before and after the vertices are read, checked and dropped). Throws
/// InputError as readPlyMesh: a malformed header on construction, bad data when reached.
class PlyVertexReader {
 public:
  explicit PlyVertexReader(const std::filesystem::path& file);
  ~PlyVertexReader();
  const std::vector<std::string>& names() const { return names_; }  ///< scalar properties, in file order
  std::size_t count() const { return count_; }                      ///< vertices
  /// Column of `name`, or -1.
  int column(const std::string& name) const;
  /// Reads the next vertex into row(); false after the last one (the rest of the file read and
  /// checked by then).
  bool next();
  /// The vertex next() read: names().size() values.
  const std::vector<double>& row() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
  std::vector<std::string> names_;
  std::size_t count_ = 0, read_ = 0;
  bool rest_checked_ = false;
};

}  // namespace vdmap
