#include "mapping/files/map_file.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include "mapping/core/error.h"
#include "mapping/files/ply_reader.h"
#include "mapping/io/json_text.h"
#include "mapping/io/text_list.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/sequence/sequence.h"

namespace vdmap {
namespace fs = std::filesystem;

namespace {

const char kKinds[] =
    "expected a sequence (a TUM, 7-Scenes, Replica or ScanNet folder, a ROS 1 bag, an MCAP), a `vdmap map` folder (global_ellipsoids.ply), a session (.vdmap), an "
    "ellipsoid or point PLY, an OctoMap (.bt, .ot) or a view file (.json)";

// The property names of a PLY's vertex element, from its header only (at most 1000 lines).
// Throws InputError when the file does not start like a PLY.
std::vector<std::string> plyVertexProperties(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot open the file");
  std::string line;
  std::vector<std::string> names;
  bool in_vertex = false;
  for (int n = 1; n <= 1000 && std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (n == 1 && key != "ply") throw InputError(file.string(), 1, "not a PLY file (expected 'ply' on the first line)");
    if (key == "element") {
      std::string name;
      words >> name;
      in_vertex = name == "vertex";
    } else if (key == "property" && in_vertex) {
      std::string type, name;
      words >> type;
      if (type == "list") words >> type >> type;
      words >> name;
      names.push_back(name);
    } else if (key == "end_header") {
      return names;
    }
  }
  throw InputError(file.string(), "header does not end with 'end_header'");
}

// The first non-blank character of a file is '{' and the text holds the key "vdmap_view"
// (a view file; app/view/view_file.* reads it properly).
bool looksLikeViewFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  const std::size_t first = head.find_first_not_of(" \t\r\n");
  return first != std::string::npos && head[first] == '{' && head.find("\"vdmap_view\"") != std::string::npos;
}

// ---- OctoMap ------------------------------------------------------------------------------

// An OctoMap file's header (octomap's AbstractOcTree::write / writeBinary): the tree type, its
// resolution and the node data after "data".
struct OctomapFile {
  std::string id;
  double resolution_m = 0;
  std::string data;
};

OctomapFile readOctomapFile(const fs::path& file, bool binary) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "cannot open the file");
  OctomapFile f;
  std::string line;
  int n = 0;
  bool data = false;
  while (!data && std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (n == 1) {
      const std::string expected = binary ? "# Octomap OcTree binary file" : "# Octomap OcTree file";
      if (line.rfind(expected, 0) != 0)
        throw InputError(file.string(), 1,
                         "not an OctoMap " + std::string(binary ? ".bt" : ".ot") + " file (expected '" + expected +
                             "' on the first line)");
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "id") {
      words >> f.id;
    } else if (key == "res") {
      if (!(words >> f.resolution_m) || !(f.resolution_m > 0) || !std::isfinite(f.resolution_m))
        throw InputError(file.string(), n, "expected 'res R' with a resolution R > 0 (m)");
    } else if (key == "size") {
      // the node count octomap wrote; the data says it again
    } else if (key == "data") {
      data = true;
    } else {
      throw InputError(file.string(), n, "unexpected header line (expected id, size, res or data)");
    }
    if (n > 1000) break;
  }
  if (!data) throw InputError(file.string(), "the OctoMap header does not end with 'data' (truncated?)");
  if (f.resolution_m <= 0) throw InputError(file.string(), "the OctoMap header has no 'res' line");
  if (!binary && f.id.empty()) throw InputError(file.string(), "the OctoMap header has no 'id' line");
  std::ostringstream rest;
  rest << in.rdbuf();
  f.data = rest.str();
  return f;
}

// Walks the node stream as liboctomap's readers will (OccupancyOcTreeBase::readBinaryNode for .bt,
// OcTreeBaseImpl::readNodesRecurs for .ot with `node_bytes` of data per node), so a truncated
// or corrupt file is refused here, with its name, instead of reaching a reader that does not
// check its stream (it reads past the end and builds a tree from garbage).
class OctomapStreamCheck {
 public:
  OctomapStreamCheck(const fs::path& file, const std::string& data) : file_(file), data_(data) {}

  void binary() {
    if (data_.empty()) fail("has no tree data after 'data'");
    binaryNode(0);
    end();
  }
  void full(std::size_t node_bytes) {
    if (data_.empty()) fail("has no tree data after 'data'");
    fullNode(0, node_bytes);
    end();
  }

 private:
  static constexpr int kDepth = 16;  // octomap's tree_depth: leaves at depth 16 at most

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(file_.string(), "corrupt OctoMap: " + what);
  }

  std::uint8_t byte() {
    if (at_ >= data_.size()) fail("the tree data ends early (truncated?)");
    return static_cast<std::uint8_t>(data_[at_++]);
  }
  void end() const {
    if (at_ != data_.size())
      fail(std::to_string(data_.size() - at_) + " bytes follow the tree data (expected the file to end)");
  }

  // Two bits per child in two bytes: 01 occupied leaf, 10 free leaf, 11 inner node, 00 none.
  void binaryNode(int depth) {
    const std::uint8_t lo = byte(), hi = byte();
    for (int i = 0; i < 8; ++i) {
      const std::uint8_t bits = i < 4 ? lo : hi;
      const int k = (i % 4) * 2;
      if (((bits >> k) & 1) && ((bits >> (k + 1)) & 1)) {
        if (depth + 1 >= kDepth) fail("the tree is deeper than 16 levels");
        binaryNode(depth + 1);
      }
    }
  }
  // The node's value, then one byte with a bit per existing child.
  void fullNode(int depth, std::size_t node_bytes) {
    for (std::size_t i = 0; i < node_bytes; ++i) byte();
    const std::uint8_t children = byte();
    if (children != 0 && depth >= kDepth) fail("the tree is deeper than 16 levels");
    for (int i = 0; i < 8; ++i)
      if ((children >> i) & 1) fullNode(depth + 1, node_bytes);
  }

  const fs::path& file_;
  const std::string& data_;
  std::size_t at_ = 0;
};

// A colour for height t in [0, 1]: viridis, five stops (its ends and quarters), 0..255.
Eigen::Vector3f heightColor(double t) {
  static const std::array<Eigen::Vector3f, 5> kStops = {Eigen::Vector3f(68, 1, 84), Eigen::Vector3f(59, 82, 139),
                                                        Eigen::Vector3f(33, 145, 140), Eigen::Vector3f(94, 201, 98),
                                                        Eigen::Vector3f(253, 231, 37)};
  const double x = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const float f = static_cast<float>(x - i);
  return kStops[static_cast<std::size_t>(i)] * (1.f - f) + kStops[static_cast<std::size_t>(i) + 1] * f;
}

// The occupied leaves of a tree as ellipsoids (mean the leaf's centre, Sigma = size^2/12 I, the
// covariance of a uniform cube). `color` gives a leaf's colour, or nothing to colour by height.
template <class Tree, class ColorOf>
std::vector<Ellipsoid> occupiedLeaves(const Tree& tree, const ColorOf& color) {
  std::vector<Ellipsoid> out;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    Ellipsoid e;
    const octomap::point3d c = it.getCoordinate();
    e.mean = Eigen::Vector3d(c.x(), c.y(), c.z());
    const double size = it.getSize();
    e.cov = Eigen::Matrix3d::Identity() * (size * size / 12.0);
    e.count = 1;
    if (const std::optional<Eigen::Vector3f> rgb = color(*it)) e.color = *rgb;
    out.push_back(e);
  }
  return out;
}

// Colours by height (z, OctoMap's up) over the 2nd..98th percentile of the leaves' heights.
void colorByHeight(std::vector<Ellipsoid>& ellipsoids) {
  if (ellipsoids.empty()) return;
  std::vector<double> z;
  z.reserve(ellipsoids.size());
  for (const Ellipsoid& e : ellipsoids) z.push_back(e.mean.z());
  std::sort(z.begin(), z.end());
  const double lo = z[z.size() * 2 / 100], hi = z[z.size() * 98 / 100];
  for (Ellipsoid& e : ellipsoids) e.color = heightColor(hi > lo ? (e.mean.z() - lo) / (hi - lo) : 0.5);
}

StaticMap loadOctomap(const fs::path& file) {
  const bool binary = asciiLower(file.extension().string()) == ".bt";
  OctomapFile f = readOctomapFile(file, binary);
  StaticMap map;
  map.sigma_m = f.resolution_m;
  std::istringstream data(f.data, std::ios::binary);
  const auto none = [](const auto&) { return std::optional<Eigen::Vector3f>(); };
  if (binary) {
    OctomapStreamCheck(file, f.data).binary();
    octomap::OcTree tree(f.resolution_m);
    tree.readBinaryData(data);
    map.ellipsoids = occupiedLeaves(tree, none);
    colorByHeight(map.ellipsoids);
    map.height_colors = true;
  } else if (f.id == "OcTree") {
    OctomapStreamCheck(file, f.data).full(sizeof(float));
    octomap::OcTree tree(f.resolution_m);
    tree.readData(data);
    map.ellipsoids = occupiedLeaves(tree, none);
    colorByHeight(map.ellipsoids);
    map.height_colors = true;
  } else if (f.id == "ColorOcTree") {
    OctomapStreamCheck(file, f.data).full(sizeof(float) + 3);
    octomap::ColorOcTree tree(f.resolution_m);
    tree.readData(data);
    map.ellipsoids = occupiedLeaves(tree, [](const octomap::ColorOcTreeNode& n) {
      const octomap::ColorOcTreeNode::Color c = n.getColor();
      return std::optional<Eigen::Vector3f>(Eigen::Vector3f(c.r, c.g, c.b));
    });
  } else {
    throw InputError(file.string(), "an OctoMap of type '" + f.id + "' (expected OcTree or ColorOcTree)");
  }
  map.source_elements = map.ellipsoids.size();
  if (map.ellipsoids.empty()) throw InputError(file.string(), "the OctoMap has no occupied voxel");
  return map;
}

// ---- PLY ----------------------------------------------------------------------------------

Ellipsoid fromRecord(const EllipsoidRecord& r) {
  Ellipsoid e;
  e.mean = r.mean.cast<double>();
  e.cov = r.cov.cast<double>();
  e.color = {static_cast<float>(r.rgb[0]), static_cast<float>(r.rgb[1]), static_cast<float>(r.rgb[2])};
  e.count = r.count;
  e.keyframe = r.keyframe;
  return e;
}

std::vector<Ellipsoid> readEllipsoids(const fs::path& file) {
  std::vector<Ellipsoid> out;
  for (const EllipsoidRecord& r : readPlyEllipsoids(file)) out.push_back(fromRecord(r));
  if (out.empty()) throw InputError(file.string(), "has no vertices (expected at least one ellipsoid)");
  return out;
}

}  // namespace

double medianNearestNeighbourSpacing(const std::vector<Eigen::Vector3d>& points) {
  const std::size_t n = points.size();
  if (n < 2) return 0;
  Eigen::Vector3d lo = points[0], hi = points[0];
  for (const Eigen::Vector3d& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double extent = (hi - lo).maxCoeff();
  if (!(extent > 0)) return 0;
  // (cell >= extent 1e-6 keeps every axis within a key's 21 bits.) A first guess of the spacing as if the points covered a surface (n ~ extent^2 / spacing^2);
  // cells grow until most points find a neighbour within their 27 cells.
  double cell = std::max(extent / std::sqrt(static_cast<double>(n)), extent * 1e-6);
  for (int attempt = 0; attempt < 40; ++attempt, cell *= 2) {
    const auto axis = [&](double v, double l) { return static_cast<std::int64_t>(std::floor((v - l) / cell)); };
    const auto key = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
      return static_cast<std::uint64_t>(x) << 42 | static_cast<std::uint64_t>(y) << 21 | static_cast<std::uint64_t>(z);
    };
    std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted(n);
    for (std::size_t i = 0; i < n; ++i)
      sorted[i] = {
          key(axis(points[i].x(), lo.x()) + 1, axis(points[i].y(), lo.y()) + 1, axis(points[i].z(), lo.z()) + 1),
          static_cast<std::uint32_t>(i)};
    std::sort(sorted.begin(), sorted.end());
    std::vector<double> nearest;
    nearest.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d& p = points[i];
      const std::int64_t cx = axis(p.x(), lo.x()) + 1, cy = axis(p.y(), lo.y()) + 1, cz = axis(p.z(), lo.z()) + 1;
      double best = std::numeric_limits<double>::infinity();
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const std::uint64_t k = key(cx + dx, cy + dy, cz + dz);
            auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair<std::uint64_t, std::uint32_t>{k, 0});
            for (; it != sorted.end() && it->first == k; ++it)
              if (it->second != i) best = std::min(best, (points[it->second] - p).squaredNorm());
          }
      // Only a neighbour within one cell is sure to be the nearest.
      if (best <= cell * cell) nearest.push_back(std::sqrt(best));
    }
    // Points without a neighbour within a cell are farther than any found: the median of all is
    // among the found ones when more than half found one.
    const std::size_t mid = n / 2;
    if (nearest.size() <= mid) continue;
    std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(mid), nearest.end());
    return nearest[mid];
  }
  return 0;
}

KeyframeGraph readMapFolderLocalMaps(const fs::path& dir, SensorModel* model) {
  const fs::path stats_file = dir / "stats.json", local_file = dir / "local_maps.ply",
                 poses_file = dir / "keyframes.txt";
  for (const fs::path& f : {stats_file, local_file, poses_file})
    if (!fs::exists(f)) throw InputError(f.string(), "missing (expected a `vdmap map` output folder)");
  std::ifstream in(stats_file, std::ios::binary);
  nlohmann::json stats;
  try {
    stats = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(stats_file.string(), std::string("does not parse as JSON: ") + e.what());
  }
  PinholeCamera camera;
  int cell_size = 0;
  try {
    const nlohmann::json& c = stats.at("camera_intrinsics");
    camera.width = c.at("width").get<int>();
    camera.height = c.at("height").get<int>();
    camera.fx = c.at("fx").get<double>();
    camera.fy = c.at("fy").get<double>();
    camera.cx = c.at("cx").get<double>();
    camera.cy = c.at("cy").get<double>();
    camera.depth_scale = c.at("depth_scale").get<double>();
    cell_size = stats.at("parameters").at("cell_size").get<int>();
    if (model) *model = parseSensorModel(stats.at("parameters").at("sensor_model").get<std::string>());
  } catch (const std::exception& e) {
    throw InputError(stats_file.string(), std::string("expected camera_intrinsics and parameters (cell_size, "
                                                      "sensor_model) as `vdmap map` writes them: ") +
                                              e.what());
  }
  KeyframeGraph graph;
  try {
    for (const StampedPose& pose : readTumTrajectory(poses_file)) {
      Keyframe k{static_cast<int>(graph.size()),       0, pose.t, pose.T_W_C, {}, {}, {},
                 KeyframeContainer(camera, cell_size), 0, {}};
      graph.add(std::move(k));
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(stats_file.string(),
                     std::string("its camera or cell size does not make a container: ") + e.what());
  }
  for (const EllipsoidRecord& r : readPlyEllipsoids(local_file)) {
    if (r.keyframe < 0 || static_cast<std::size_t>(r.keyframe) >= graph.size())
      throw InputError(local_file.string(), "an ellipsoid of keyframe " + std::to_string(r.keyframe) +
                                                ", which keyframes.txt does not have");
    Keyframe& k = graph.keyframe(r.keyframe);
    const Transform T_K_W = k.T_W_K.inverse();
    const Eigen::Vector3d mean = T_K_W * r.mean.cast<double>();
    if (!(mean.z() > 0.0)) continue;
    const Eigen::Vector2d uv = camera.project(mean);
    const int grid = k.container.gridIndexOfPixel(uv.x(), uv.y());
    if (grid < 0 || k.container.find(grid)) continue;  // outside, or a second one rounded into a taken cell
    CellStats cell;
    cell.n = std::max<double>(r.count, 2.0);
    cell.mean = mean;
    cell.scatter = T_K_W.linear() * r.cov.cast<double>() * T_K_W.linear().transpose() * (cell.n - 1.0);
    cell.color = Eigen::Vector3d(r.rgb[0], r.rgb[1], r.rgb[2]);
    k.container.findOrCreate(grid).fromStats(cell);
  }
  return graph;
}

std::vector<FolderEntry> listFolder(const fs::path& dir) {
  std::error_code ec;
  fs::directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec);
  if (ec) throw InputError(dir.string(), "cannot be listed (" + ec.message() + ")");
  std::vector<FolderEntry> entries;
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) throw InputError(dir.string(), "cannot be listed (" + ec.message() + ")");
    const fs::path& p = it->path();
    const std::string name = p.filename().string();
    if (name.empty() || name[0] == '.') continue;
    FolderEntry e;
    e.path = p;
    e.folder = it->is_directory(ec);
    try {
      const MapFileKind kind = detectMapFile(p);
      e.kind = kind;
    } catch (const InputError&) {
      // a plain folder, or a file of no kind vdmap opens
    }
    entries.push_back(std::move(e));
  }
  std::sort(entries.begin(), entries.end(), [](const FolderEntry& a, const FolderEntry& b) {
    if (a.folder != b.folder) return a.folder;
    const std::string x = asciiLower(a.path.filename().string()), y = asciiLower(b.path.filename().string());
    return x != y ? x < y : a.path.filename() < b.path.filename();
  });
  return entries;
}

const char* mapFileKindName(MapFileKind kind) {
  switch (kind) {
    case MapFileKind::kSequence: return "sequence";
    case MapFileKind::kMapFolder: return "map folder";
    case MapFileKind::kSession: return "session";
    case MapFileKind::kEllipsoidPly: return "ellipsoid PLY";
    case MapFileKind::kPointPly: return "point PLY";
    case MapFileKind::kOctomap: return "OctoMap";
    case MapFileKind::kViewFile: return "view file";
  }
  return "?";
}

MapFileKind detectMapFile(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path.string(), "cannot open: no such file or folder");
  const std::string ext = asciiLower(path.extension().string());
  if (recogniseSequence(path)) return MapFileKind::kSequence;
  if (fs::is_directory(path, ec)) {
    if (fs::exists(path / "global_ellipsoids.ply", ec)) return MapFileKind::kMapFolder;
    // A saved session may be stored as a folder in a later format; today it is a file.
    throw InputError(path.string(),
                     std::string("is a folder that is neither a sequence nor a map folder (global_ellipsoids.ply) (") +
                         kKinds + ")");
  }
  if (ext == ".vdmap") return MapFileKind::kSession;
  if (ext == ".bt" || ext == ".ot") return MapFileKind::kOctomap;
  if (ext == ".ply") {
    const std::vector<std::string> names = plyVertexProperties(path);
    const auto has = [&](const char* name) { return std::find(names.begin(), names.end(), name) != names.end(); };
    if (has("cxx") && has("cyy") && has("czz")) return MapFileKind::kEllipsoidPly;
    if (has("x") && has("y") && has("z")) return MapFileKind::kPointPly;
    throw InputError(path.string(), "is a PLY without vertex x y z (expected points or ellipsoids)");
  }
  if (ext == ".json" && looksLikeViewFile(path)) return MapFileKind::kViewFile;
  throw InputError(path.string(), std::string("is of no kind vdmap opens (") + kKinds + ")");
}

StaticMap loadStaticMap(const fs::path& path) {
  const MapFileKind kind = detectMapFile(path);
  StaticMap map;
  switch (kind) {
    case MapFileKind::kMapFolder: {
      map.ellipsoids = readEllipsoids(path / "global_ellipsoids.ply");
      std::error_code ec;
      if (fs::exists(path / "keyframes.txt", ec)) map.keyframes = readTumTrajectory(path / "keyframes.txt");
      if (fs::exists(path / "trajectory.txt", ec)) map.trajectory = readTumTrajectory(path / "trajectory.txt");
      if (fs::exists(path / "graph.txt", ec)) {
        const fs::path file = path / "graph.txt";
        for (const ListLine& line : readListFile(file, 3, "keyframe_a keyframe_b weight")) {
          CovisibilityEdge e;
          const double a = parseListNumber(line.tokens[0], file, line.number, "keyframe_a");
          const double b = parseListNumber(line.tokens[1], file, line.number, "keyframe_b");
          e.weight = parseListNumber(line.tokens[2], file, line.number, "weight");
          const auto keyframes = static_cast<double>(map.keyframes.size());
          if (a != std::floor(a) || b != std::floor(b) || a < 0 || b < 0 || a >= keyframes || b >= keyframes)
            throw InputError(file.string(), line.number,
                             "expected keyframe ids 0.." + std::to_string(map.keyframes.size()) + " (keyframes.txt)");
          e.a = static_cast<int>(a);
          e.b = static_cast<int>(b);
          map.edges.push_back(e);
        }
      }
      if (fs::exists(path / "stats.json", ec)) {
        std::ifstream in(path / "stats.json", std::ios::binary);
        std::ostringstream text;
        text << in.rdbuf();
        map.stats_json = text.str();
      }
      map.source_elements = map.ellipsoids.size();
      break;
    }
    case MapFileKind::kEllipsoidPly:
      map.ellipsoids = readEllipsoids(path);
      map.source_elements = map.ellipsoids.size();
      break;
    case MapFileKind::kPointPly: {
      const PlyVertexTable table = readPlyVertices(path);
      if (table.count == 0) throw InputError(path.string(), "has no vertices (expected at least one point)");
      const int x = table.column("x"), y = table.column("y"), z = table.column("z");
      int r = table.column("red"), g = table.column("green"), b = table.column("blue");
      if (r < 0 || g < 0 || b < 0) r = g = b = -1;
      // Colours stored as floats are in [0, 1], as bytes in 0..255.
      double top = 0;
      if (r >= 0)
        for (std::size_t i = 0; i < table.count; ++i)
          top = std::max({top, table.at(i, r), table.at(i, g), table.at(i, b)});
      const double scale = top <= 1.0 ? 255.0 : 1.0;
      std::vector<Eigen::Vector3d> points(table.count);
      for (std::size_t i = 0; i < table.count; ++i) points[i] = {table.at(i, x), table.at(i, y), table.at(i, z)};
      // Half the median spacing: neighbouring points' 1-sigma spheres touch, so at the default
      // 2 sigma the surface reads as closed.
      map.sigma_m = 0.5 * medianNearestNeighbourSpacing(points);
      if (!(map.sigma_m > 0)) map.sigma_m = 0.005;  // one point, or all at one place
      map.ellipsoids.resize(table.count);
      for (std::size_t i = 0; i < table.count; ++i) {
        Ellipsoid& e = map.ellipsoids[i];
        e.mean = points[i];
        e.cov = Eigen::Matrix3d::Identity() * (map.sigma_m * map.sigma_m);
        e.count = 1;
        e.color = r >= 0 ? Eigen::Vector3f(static_cast<float>(table.at(i, r) * scale),
                                           static_cast<float>(table.at(i, g) * scale),
                                           static_cast<float>(table.at(i, b) * scale))
                         : Eigen::Vector3f(180, 180, 180);
      }
      map.source_elements = table.count;
      break;
    }
    case MapFileKind::kOctomap: {
      StaticMap octo = loadOctomap(path);
      map.ellipsoids = std::move(octo.ellipsoids);
      map.sigma_m = octo.sigma_m;
      map.source_elements = octo.source_elements;
      map.height_colors = octo.height_colors;
      break;
    }
    case MapFileKind::kSequence:
      throw InputError(path.string(), "is a sequence folder, not a map: it has no global_ellipsoids.ply (expected a "
                                      "`vdmap map` folder, a PLY or an OctoMap)");
    case MapFileKind::kSession:
    case MapFileKind::kViewFile:
      throw InputError(path.string(), std::string("is a ") + mapFileKindName(kind) +
                                          ", not a map file (expected a map folder, a PLY or an OctoMap)");
  }
  map.kind = kind;
  map.path = path;
  return map;
}

}  // namespace vdmap
