// The folder kinds of sequence: what each lists (detail/listing.h).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>

#include "mapping/core/error.h"
#include "mapping/core/message_text.h"
#include "mapping/io/image_codec.h"
#include "mapping/io/text_list.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/sequence/detail/listing.h"

namespace fs = std::filesystem;

namespace vdmap::detail {
namespace {

// The data sets without timestamps (7-Scenes, NICE-SLAM's Replica, ScanNet's export) were
// recorded (or rendered) at 30 Hz: frame N is at N / 30 s, as our TUM-layout copies of them say.
constexpr double kDataSetFrameRateHz = 30.0;

std::vector<ListedImage> readImageList(const fs::path& folder, const char* name) {
  const fs::path file = folder / name;
  std::vector<ListedImage> list;
  double previous = -INFINITY;
  for (const ListLine& line : readListFile(file, 2, "timestamp path")) {
    const double t = parseListNumber(line.tokens[0], file, line.number, "the timestamp");
    checkIncreasing(t, &previous, file, line.number);
    list.push_back({t, folder / line.tokens[1], file, line.number});
  }
  return list;
}

// A camera-to-world matrix, 16 numbers row by row. A matrix with a non-finite entry is no pose
// (ScanNet writes -inf for the frames its tracking lost). The rotation is made exactly orthonormal
// (through its quaternion, as a TUM trajectory stores it); one that is far from a rotation, or a
// last row other than 0 0 0 1, is an error naming `file` (and `line` when > 0).
std::optional<Transform> poseFromMatrix(const std::vector<double>& m, const fs::path& file, int line) {
  auto fail = [&](const std::string& what) -> InputError {
    return line > 0 ? InputError(file.string(), line, what) : InputError(file.string(), what);
  };
  if (!std::all_of(m.begin(), m.end(), [](double v) { return std::isfinite(v); })) return std::nullopt;
  Eigen::Matrix4d M;
  for (int i = 0; i < 16; ++i) M(i / 4, i % 4) = m[i];
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
    throw fail("the last row of the 4x4 camera-to-world matrix must be 0 0 0 1");
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-2 || R.determinant() < 0)
    throw fail("the 4x4 camera-to-world matrix does not hold a rotation");
  if (M.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > kMaxPoseDistanceM)
    throw fail("the camera position lies more than " + std::to_string(static_cast<int>(kMaxPoseDistanceM)) +
               " m from the origin");
  Transform T = Transform::Identity();
  T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

std::vector<double> readNumbers(const fs::path& file, std::size_t count, const char* expected) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "cannot be read");
  std::vector<double> values;
  for (std::string token; in >> token;) {
    if (values.size() == count) throw InputError(file.string(), std::string("holds more numbers than ") + expected);
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);  // strtod reads ScanNet's "-inf"
    if (end != token.c_str() + token.size())
      throw InputError(file.string(), "expected a number, found " + printable(token) + " (" + expected + ")");
    values.push_back(v);
  }
  if (values.size() != count)
    throw InputError(file.string(),
                     "holds " + counted(static_cast<long long>(values.size()), "number") + "; expected " + expected);
  return values;
}

std::optional<Transform> readPoseFile(const fs::path& file) {
  return poseFromMatrix(readNumbers(file, 16, "16, a 4x4 camera-to-world matrix row by row"), file, 0);
}

// The files in `folder` named PREFIX<number>SUFFIX, by number.
std::map<int, fs::path> numberedFiles(const fs::path& folder, const std::string& prefix, const std::string& suffix) {
  std::map<int, fs::path> files;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const char* first = name.data() + prefix.size();
    const char* last = name.data() + name.size() - suffix.size();
    int number = 0;
    const auto [ptr, err] = std::from_chars(first, last, number);
    if (err == std::errc() && ptr == last && number >= 0) files.emplace(number, entry.path());
  }
  if (ec) throw InputError(folder.string(), "cannot be listed: " + ec.message());
  return files;
}

bool hasNumberedFile(const fs::path& folder, const std::string& prefix, const std::string& suffix) {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > prefix.size() + suffix.size() && name.starts_with(prefix) && name.ends_with(suffix)) return true;
  }
  return false;
}

// A data set's camera: --camera, else a camera file in the folder, else the data set's preset.
CameraChoice dataSetCamera(const fs::path& folder, const SequenceOptions& options, const std::string& preset,
                           const std::string& why) {
  if (!options.camera_preset.empty()) return chooseCamera(folder, options.camera_preset);
  for (const char* file : {"camera.yaml", "camera.yml", "camera.json", "cam_params.json"})
    if (fs::exists(folder / file)) return chooseCamera(folder, "");
  return {cameraPreset(preset), "preset " + preset + " (" + why + ")", cameraPresetColour(preset)};
}

ListedImage numberedImage(int number, const fs::path& path) { return {number / kDataSetFrameRateHz, path, path, 0}; }

}  // namespace

std::optional<std::pair<SequenceKind, std::string>> recogniseFolder(const fs::path& folder) {
  if (fs::exists(folder / "associations.txt"))
    return std::pair{SequenceKind::kTumFolder, std::string("has associations.txt")};
  for (const char* list : {"depth.txt", "rgb.txt", "groundtruth.txt"})
    if (fs::exists(folder / list)) return std::pair{SequenceKind::kTumFolder, "has " + std::string(list)};
  if (hasNumberedFile(folder, "frame-", ".depth.png"))
    return std::pair{SequenceKind::kSevenScenes, std::string("holds frame-NNNNNN.depth.png files")};
  if (fs::is_directory(folder / "results") && fs::exists(folder / "traj.txt"))
    return std::pair{SequenceKind::kReplica, std::string("holds results/ and traj.txt")};
  if (fs::is_directory(folder / "color") && fs::is_directory(folder / "depth"))
    return std::pair{SequenceKind::kScanNet, std::string("holds color/ and depth/ folders")};
  return std::nullopt;
}

Listing listTumFolder(const fs::path& folder, const SequenceOptions& options) {
  Listing listing;
  try {
    listing.camera = chooseCamera(folder, options.camera_preset);
  } catch (const std::invalid_argument& e) {
    throw InputError("--camera", e.what());
  }
  // Depth list with its rgb partner: from associations.txt when present, else by timestamps.
  const fs::path assoc_file = folder / "associations.txt";
  if (fs::exists(assoc_file)) {
    listing.list_file = assoc_file;
    double previous = -INFINITY;
    for (const ListLine& line : readListFile(assoc_file, 4, "t_rgb rgb_path t_depth depth_path")) {
      const double t_rgb = parseListNumber(line.tokens[0], assoc_file, line.number, "the rgb timestamp");
      const double t_depth = parseListNumber(line.tokens[2], assoc_file, line.number, "the depth timestamp");
      checkTimestamp(t_rgb, assoc_file, line.number);
      checkIncreasing(t_depth, &previous, assoc_file, line.number);
      listing.frames.push_back({{t_depth, folder / line.tokens[3], assoc_file, line.number},
                                ListedImage{t_rgb, folder / line.tokens[1], assoc_file, line.number},
                                std::nullopt});
    }
  } else {
    listing.list_file = folder / "depth.txt";
    const std::vector<ListedImage> rgb = readImageList(folder, "rgb.txt");
    if (rgb.empty()) throw InputError((folder / "rgb.txt").string(), "lists no frames");
    for (const ListedImage& depth : readImageList(folder, "depth.txt")) {
      auto it =
          std::lower_bound(rgb.begin(), rgb.end(), depth.t, [](const ListedImage& s, double t) { return s.t < t; });
      std::optional<ListedImage> best;
      for (auto c : {it, it == rgb.begin() ? rgb.end() : std::prev(it)}) {
        if (c == rgb.end() || std::abs(c->t - depth.t) > options.max_rgb_dt_s) continue;
        if (!best || std::abs(c->t - depth.t) < std::abs(best->t - depth.t)) best = *c;
      }
      listing.frames.push_back({depth, best, std::nullopt});
    }
  }
  listing.poses_file = folder / "groundtruth.txt";
  listing.has_poses = fs::exists(listing.poses_file);
  if (listing.has_poses) {
    listing.poses_source = "groundtruth.txt";
    const std::vector<StampedPose> poses = readTumTrajectory(listing.poses_file);
    for (ListedFrame& frame : listing.frames) frame.pose = interpolatePose(poses, frame.depth.t, options.max_pose_dt_s);
  }
  return listing;
}

Listing listSevenScenes(const fs::path& folder, const SequenceOptions& options) {
  Listing listing;
  listing.camera = dataSetCamera(folder, options, "7scenes", "a 7-Scenes folder");
  listing.list_file = folder;
  const std::map<int, fs::path> poses = numberedFiles(folder, "frame-", ".pose.txt");
  std::map<int, fs::path> colour = numberedFiles(folder, "frame-", ".color.png");
  // 7-Scenes ships PNG colour; copies re-encoded as JPEG keep the name otherwise.
  colour.merge(numberedFiles(folder, "frame-", ".color.jpg"));
  listing.has_poses = !poses.empty();
  listing.poses_source = "frame-NNNNNN.pose.txt";
  listing.poses_file = folder / "frame-000000.pose.txt";
  for (const auto& [number, depth] : numberedFiles(folder, "frame-", ".depth.png")) {
    ListedFrame frame{numberedImage(number, depth), std::nullopt, std::nullopt};
    if (auto c = colour.find(number); c != colour.end()) frame.rgb = numberedImage(number, c->second);
    if (auto p = poses.find(number); p != poses.end()) frame.pose = readPoseFile(p->second);
    listing.frames.push_back(std::move(frame));
  }
  return listing;
}

Listing listReplica(const fs::path& folder, const SequenceOptions& options) {
  Listing listing;
  // NICE-SLAM keeps cam_params.json beside the scene folders.
  const fs::path parent = fs::absolute(folder).lexically_normal().parent_path();
  const bool parent_camera = options.camera_preset.empty() && !fs::exists(folder / "cam_params.json") &&
                             fs::exists(parent / "cam_params.json");
  listing.camera = parent_camera ? chooseCamera(parent, "")
                                 : dataSetCamera(folder, options, "replica", "NICE-SLAM's Replica layout");
  if (parent_camera) listing.camera.source += " (beside the scene folder)";
  const fs::path results = folder / "results";
  listing.list_file = results;
  const fs::path traj = folder / "traj.txt";
  listing.has_poses = true;
  listing.poses_source = "traj.txt";
  listing.poses_file = traj;
  std::vector<ListLine> rows = readListFile(traj, 16, "a 4x4 camera-to-world matrix, row by row");
  const std::map<int, fs::path> colour = numberedFiles(results, "frame", ".jpg");
  for (const auto& [number, depth] : numberedFiles(results, "depth", ".png")) {
    ListedFrame frame{numberedImage(number, depth), std::nullopt, std::nullopt};
    if (auto c = colour.find(number); c != colour.end()) frame.rgb = numberedImage(number, c->second);
    if (static_cast<std::size_t>(number) < rows.size()) {
      const ListLine& row = rows[number];
      std::vector<double> m;
      for (const std::string& token : row.tokens)
        m.push_back(parseListNumber(token, traj, row.number, "a matrix entry"));
      frame.pose = poseFromMatrix(m, traj, row.number);
    }
    listing.frames.push_back(std::move(frame));
  }
  return listing;
}

Listing listScanNet(const fs::path& folder, const SequenceOptions& options) {
  Listing listing;
  listing.list_file = folder / "depth";
  const std::map<int, fs::path> depth = numberedFiles(folder / "depth", "", ".png");
  const std::map<int, fs::path> colour = numberedFiles(folder / "color", "", ".jpg");
  const std::map<int, fs::path> poses =
      fs::is_directory(folder / "pose") ? numberedFiles(folder / "pose", "", ".txt") : std::map<int, fs::path>{};
  if (!options.camera_preset.empty()) {
    listing.camera = dataSetCamera(folder, options, "", "");
  } else if (!depth.empty()) {
    // The export's intrinsics: 4x4 matrices; the image sizes are the first images'.
    const fs::path intrinsic = folder / "intrinsic";
    auto matrix = [&](const char* name) {
      const fs::path file = intrinsic / name;
      if (!fs::exists(file))
        throw InputError(file.string(), "no such file; a ScanNet export needs its intrinsics (or give --camera)");
      return readNumbers(file, 16, "16, a 4x4 matrix row by row");
    };
    auto bytes = [](const fs::path& file) {
      std::ifstream in(file, std::ios::binary);
      return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::vector<double> K = matrix("intrinsic_depth.txt");
    const cv::Mat first_depth = decodeDepthImage(bytes(depth.begin()->second), depth.begin()->second.string());
    PinholeCamera& cam = listing.camera.camera;
    cam = PinholeCamera{first_depth.cols, first_depth.rows, K[0], K[5], K[2], K[6], 1000.0};
    listing.camera.source = "intrinsic/intrinsic_depth.txt, depth in millimetres";
    if (!colour.empty()) {
      const std::vector<double> Kc = matrix("intrinsic_color.txt");
      const cv::Mat first_colour = decodeColorImage(bytes(colour.begin()->second), colour.begin()->second.string());
      ColourCamera c;
      c.fx = Kc[0], c.fy = Kc[5], c.cx = Kc[2], c.cy = Kc[6];
      c.width = first_colour.cols, c.height = first_colour.rows;
      // Each extrinsic maps its camera into the sensor's frame: depth -> colour is E_colour^-1 E_depth.
      auto extrinsic = [&](const char* name) {
        Eigen::Matrix4d E = Eigen::Matrix4d::Identity();
        if (!fs::exists(intrinsic / name)) return E;
        const std::vector<double> m = readNumbers(intrinsic / name, 16, "16, a 4x4 matrix row by row");
        for (int i = 0; i < 16; ++i) E(i / 4, i % 4) = m[i];
        return E;
      };
      c.T_colour_depth.matrix() = extrinsic("extrinsic_color.txt").inverse() * extrinsic("extrinsic_depth.txt");
      // A colour camera that is the depth camera needs no registering.
      const bool same = c.fx == cam.fx && c.fy == cam.fy && c.cx == cam.cx && c.cy == cam.cy && c.width == cam.width &&
                        c.height == cam.height && c.T_colour_depth.matrix().isIdentity(0.0);
      if (!same) listing.camera.colour = c;
    }
  }
  listing.has_poses = !poses.empty();
  listing.poses_source = "pose/N.txt";
  listing.poses_file = folder / "pose";
  for (const auto& [number, path] : depth) {
    ListedFrame frame{numberedImage(number, path), std::nullopt, std::nullopt};
    if (auto c = colour.find(number); c != colour.end()) frame.rgb = numberedImage(number, c->second);
    if (auto p = poses.find(number); p != poses.end()) frame.pose = readPoseFile(p->second);
    listing.frames.push_back(std::move(frame));
  }
  return listing;
}

}  // namespace vdmap::detail
