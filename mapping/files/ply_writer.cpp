#include "mapping/files/ply_writer.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "mapping/core/atomic_file.h"

namespace vdmap {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the PLY writer emits the host's bytes and declares binary_little_endian");

template <typename T>
void put(std::string& buffer, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  buffer.append(bytes, sizeof(T));
}

// A file's bytes built in pieces of about kPieceBytes, each handed to the sink when full: an
// export of a million ellipsoids is never held whole (local_maps.ply alone is tens of MB).
class Pieces {
 public:
  explicit Pieces(const ByteSink& sink) : sink_(sink) { bytes.reserve(kPieceBytes + 512); }
  /// Hands the bytes on when a piece is full (call between records).
  void next() {
    if (bytes.size() >= kPieceBytes) flush();
  }
  void flush() {
    sink_(bytes);
    bytes.clear();
  }
  std::string bytes;

 private:
  static constexpr std::size_t kPieceBytes = 1 << 16;
  const ByteSink& sink_;
};

// writeFileAtomically of the file `write` puts into its Pieces.
template <typename Write>
void writeInPieces(const std::filesystem::path& file, const Write& write) {
  writeFileAtomically(file, [&write](const ByteSink& sink) {
    Pieces pieces(sink);
    write(pieces);
    pieces.flush();
  });
}

std::uint8_t toByte(float c) { return static_cast<std::uint8_t>(std::clamp(std::lround(c), 0L, 255L)); }

// The header of a binary PLY of `count` vertices with x y z float, red green blue uchar and then
// the `extra` property lines.
std::string vertexHeader(const char* comment, std::size_t count, const char* extra) {
  return std::string("ply\nformat binary_little_endian 1.0\ncomment ") + comment + "\nelement vertex " +
         std::to_string(count) +
         "\nproperty float x\nproperty float y\nproperty float z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\n" +
         extra + "end_header\n";
}

double smallestEigenvalue(const Eigen::Matrix3f& m) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m.cast<double>(), Eigen::EigenvaluesOnly).eigenvalues()(0);
}

void putPointAndColor(std::string& bytes, const Ellipsoid& e) {
  for (int k = 0; k < 3; ++k) put(bytes, static_cast<float>(e.mean(k)));
  for (int k = 0; k < 3; ++k) put(bytes, toByte(e.color(k)));
}

}  // namespace

Eigen::Matrix3f storedCovariance(const Eigen::Matrix3d& cov) {
  Eigen::Matrix3f stored = cov.cast<float>();
  if (smallestEigenvalue(stored) >= 0.0) return stored;
  // Clamp the eigenvalues at a floor above float rounding (~6e-8 of the largest), raised until the
  // float matrix is positive semi-definite (once in practice).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Matrix3d& V = eig.eigenvectors();
  double floor = std::max(eig.eigenvalues()(2), 0.0) * 1e-7;
  for (int attempt = 0; attempt < 10; ++attempt, floor *= 10) {
    stored = (V * eig.eigenvalues().cwiseMax(floor).asDiagonal() * V.transpose()).cast<float>();
    if (smallestEigenvalue(stored) >= 0.0) return stored;
  }
  return Eigen::Matrix3f(stored.diagonal().cwiseMax(0.f).asDiagonal());  // unreachable for finite input
}

void writePointPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids) {
  writeInPieces(file, [&](Pieces& out) {
    out.bytes = vertexHeader("vdmap ellipsoid means", ellipsoids.size(), "");
    for (const Ellipsoid& e : ellipsoids) {
      putPointAndColor(out.bytes, e);
      out.next();
    }
  });
}

void writeMeshPly(const std::filesystem::path& file, const ColoredTriangleMesh& mesh) {
  const bool normals = !mesh.normals.empty();
  if (normals && mesh.normals.size() != mesh.positions.size())
    throw std::logic_error("a mesh's normals do not fit its vertices");
  std::string bytes = vertexHeader("vdmap mesh", mesh.positions.size(),
                                   normals ? "property float nx\nproperty float ny\nproperty float nz\n" : "");
  bytes.insert(bytes.size() - std::string("end_header\n").size(),
               "element face " + std::to_string(mesh.triangles.size()) + "\nproperty list uchar uint vertex_indices\n");
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) put(bytes, mesh.positions[i](k));
    for (int k = 0; k < 3; ++k)
      put(bytes, i < mesh.colors.size() ? mesh.colors[i][static_cast<std::size_t>(k)] : std::uint8_t{200});
    if (normals)
      for (int k = 0; k < 3; ++k) put(bytes, mesh.normals[i](k));
  }
  for (const auto& t : mesh.triangles) {
    put(bytes, std::uint8_t{3});
    for (std::uint32_t v : t) put(bytes, v);
  }
  writeFileAtomically(file, bytes);
}

void writeMeshObj(const std::filesystem::path& file, const ColoredTriangleMesh& mesh) {
  const bool normals = !mesh.normals.empty();
  if (normals && mesh.normals.size() != mesh.positions.size())
    throw std::logic_error("a mesh's normals do not fit its vertices");
  std::string text = "# vdmap mesh\n";
  char line[160];
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Eigen::Vector3f& p = mesh.positions[i];
    const std::array<std::uint8_t, 3> c =
        i < mesh.colors.size() ? mesh.colors[i] : std::array<std::uint8_t, 3>{200, 200, 200};
    text.append(line,
                static_cast<std::size_t>(std::snprintf(line, sizeof line, "v %.9g %.9g %.9g %.6g %.6g %.6g\n", p.x(),
                                                       p.y(), p.z(), c[0] / 255.0, c[1] / 255.0, c[2] / 255.0)));
  }
  if (normals)
    for (const Eigen::Vector3f& n : mesh.normals)
      text.append(
          line, static_cast<std::size_t>(std::snprintf(line, sizeof line, "vn %.7g %.7g %.7g\n", n.x(), n.y(), n.z())));
  for (const auto& t : mesh.triangles) {
    const unsigned a = t[0] + 1, b = t[1] + 1, c = t[2] + 1;
    const int len = normals ? std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c)
                            : std::snprintf(line, sizeof line, "f %u %u %u\n", a, b, c);
    text.append(line, static_cast<std::size_t>(len));
  }
  writeFileAtomically(file, text);
}

void writeMeshFile(const std::filesystem::path& file, const ColoredTriangleMesh& mesh) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".obj") writeMeshObj(file, mesh);
  else writeMeshPly(file, mesh);
}

void writeEllipsoidPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids) {
  writeEllipsoidPly(file, ellipsoids.size(), [&ellipsoids](const EllipsoidVisitor& visit) {
    for (const Ellipsoid& e : ellipsoids) visit(e);
  });
}

void writeEllipsoidPly(const std::filesystem::path& file, std::size_t count, const EllipsoidSource& source) {
  writeInPieces(file, [&](Pieces& out) {
    out.bytes = vertexHeader("vdmap ellipsoids", count,
                             "property float cxx\nproperty float cxy\nproperty float cxz\n"
                             "property float cyy\nproperty float cyz\nproperty float czz\n"
                             "property uint count\nproperty int keyframe\n");
    std::size_t written = 0;
    source([&](const Ellipsoid& e) {
      putPointAndColor(out.bytes, e);
      const Eigen::Matrix3f c = storedCovariance(e.cov);
      for (float v : {c(0, 0), c(0, 1), c(0, 2), c(1, 1), c(1, 2), c(2, 2)}) put(out.bytes, v);
      put(out.bytes, static_cast<std::uint32_t>(e.count));
      put(out.bytes, static_cast<std::int32_t>(e.keyframe));
      out.next();
      ++written;
    });
    if (written != count) throw std::logic_error("an ellipsoid PLY's source gave another count than its header's");
  });
}

void writeGaussianPly(const std::filesystem::path& file, const std::vector<Ellipsoid>& ellipsoids) {
  constexpr double kSh0 = 0.28209479177387814;  // the degree-0 spherical harmonic, 1 / (2 sqrt(pi))
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment vdmap 3-D Gaussians\nelement vertex " +
                       std::to_string(ellipsoids.size()) + "\n";
  // The reference 3DGS loader's order; it asserts 3 * ((degree + 1)^2 - 1) = 45 f_rest at its
  // default degree 3, so all 45 are written, zero: the colour has no view dependence.
  std::vector<std::string> names = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (int k = 0; k < kGaussianRestCoefficients; ++k) names.push_back("f_rest_" + std::to_string(k));
  for (const char* name : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    names.emplace_back(name);
  for (const std::string& name : names) header += "property float " + name + "\n";
  header += "end_header\n";
  writeInPieces(file, [&](Pieces& out) {
    out.bytes = header;
    std::string& bytes = out.bytes;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    for (const Ellipsoid& e : ellipsoids) {
      eig.compute(e.cov);  // ascending eigenvalues, orthonormal eigenvectors
      Eigen::Matrix3d R = eig.eigenvectors();
      if (R.determinant() < 0) R.col(0) = -R.col(0);  // a proper rotation
      const Eigen::Quaterniond q(R);
      for (int k = 0; k < 3; ++k) put(bytes, static_cast<float>(e.mean(k)));
      for (int k = 0; k < 3; ++k) put(bytes, static_cast<float>(R(k, 0)));
      for (int k = 0; k < 3; ++k) put(bytes, static_cast<float>((e.color(k) / 255.0 - 0.5) / kSh0));
      for (int k = 0; k < kGaussianRestCoefficients; ++k) put(bytes, 0.f);
      put(bytes, kGaussianOpacityLogit);
      for (int k = 0; k < 3; ++k)
        put(bytes,
            static_cast<float>(std::log(std::max(std::sqrt(std::max(eig.eigenvalues()(k), 0.0)), kGaussianMinSigma))));
      for (double v : {q.w(), q.x(), q.y(), q.z()}) put(bytes, static_cast<float>(v));
      out.next();
    }
  });
}

}  // namespace vdmap
