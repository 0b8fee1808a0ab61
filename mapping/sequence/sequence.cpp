#include "mapping/io/tum_sequence.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include "mapping/core/error.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/image_codec.h"
#include "mapping/io/text_list.h"
#include "mapping/io/trajectory_io.h"

namespace fs = std::filesystem;

namespace vdmap {
namespace {

struct Stamped {
  double t;
  fs::path path;
  fs::path list;  // the list file that named it, for errors
  int line;
};

std::vector<Stamped> readImageList(const fs::path& folder, const char* name) {
  const fs::path file = folder / name;
  std::vector<Stamped> list;
  double previous = -INFINITY;
  for (const ListLine& line : readListFile(file, 2, "timestamp path")) {
    const double t = parseListNumber(line.tokens[0], file, line.number, "the timestamp");
    checkIncreasing(t, &previous, file, line.number);
    list.push_back({t, folder / line.tokens[1], file, line.number});
  }
  return list;
}

// Pose at time t: interpolated between the ground-truth poses around t (linear translation,
// slerp rotation), or nothing when either is more than max_dt away.
std::optional<Transform> poseAt(const std::vector<StampedPose>& poses, double t, double max_dt) {
  auto next =
      std::lower_bound(poses.begin(), poses.end(), t, [](const StampedPose& p, double time) { return p.t < time; });
  constexpr double kSameTime = 1e-6;
  if (next != poses.end() && next->t - t < kSameTime) return next->T_W_C;
  if (next != poses.begin() && t - std::prev(next)->t < kSameTime) return std::prev(next)->T_W_C;
  if (next == poses.end() || next == poses.begin()) return std::nullopt;
  const StampedPose& a = *std::prev(next);
  const StampedPose& b = *next;
  if (t - a.t > max_dt || b.t - t > max_dt) return std::nullopt;
  const double s = (t - a.t) / (b.t - a.t);
  Transform T = Transform::Identity();
  T.translation() = (1.0 - s) * a.T_W_C.translation() + s * b.T_W_C.translation();
  T.linear() = Eigen::Quaterniond(a.T_W_C.linear()).slerp(s, Eigen::Quaterniond(b.T_W_C.linear())).toRotationMatrix();
  return T;
}

// An image a list names must be a regular file. A name the file system cannot even look up (a
// symbolic-link loop, a name too long) is the list's error too, not a std::filesystem exception.
void checkImage(const Stamped& image, const fs::path& folder) {
  std::error_code ec;
  if (fs::is_regular_file(image.path, ec)) return;
  const bool missing = !ec || ec == std::errc::no_such_file_or_directory || ec == std::errc::not_a_directory;
  std::string what = missing ? "does not exist" : "cannot be read: " + ec.message();
  const fs::file_type type = fs::status(image.path, ec).type();
  if (type == fs::file_type::directory) what = "is a folder, not an image file";
  else if (!ec && type != fs::file_type::not_found) what = "is not a regular file";
  std::string name = image.path.lexically_relative(folder).string();
  if (name.size() > 80) name = name.substr(0, 77) + "...";
  throw InputError(image.list.string(), image.line, "image '" + name + "' " + what);
}

// The last part of a folder's path, "seq" for "/data/seq/" too.
std::string folderName(const fs::path& folder) {
  std::error_code ec;
  fs::path p = fs::absolute(folder, ec).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  return p.filename().string();
}

std::string seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6f s", t);
  return text;
}

// The sequence must be the recording the session was mapped on: the same folder name (its full
// path may have changed: a moved or copied recording continues) and, at the session's last
// frame, the same depth timestamp; timestamps increase, so the frames after it follow in time.
// `t_last`: the sequence's depth timestamp at that frame, none when it lists fewer frames.
void checkContinuation(const fs::path& folder, int listed, std::optional<double> t_last, int first,
                       const SequenceContinuation& c) {
  if (c.last_frame_index < 0) return;
  const std::string frame = "frame " + std::to_string(c.last_frame_index);
  const std::string mapped_on = c.folder.empty() ? std::string() : " (mapped on " + c.folder.string() + ")";
  if (!c.folder.empty() && folderName(c.folder) != folderName(folder))
    throw InputError(folder.string(), "is not the recording " + c.session + " was mapped on (" + c.folder.string() +
                                          "); continue it on that folder");
  if (!t_last)
    throw InputError(folder.string(), "lists " + std::to_string(listed) + " depth frames, but " + c.session +
                                          " stopped at its " + frame + " (t = " + seconds(c.last_timestamp) + ")" +
                                          mapped_on + ": not the recording it was mapped on");
  if (std::abs(*t_last - c.last_timestamp) > 1e-6)
    throw InputError(folder.string(), "depth " + frame + " is at t = " + seconds(*t_last) + ", but " + c.session +
                                          " stopped at its " + frame + " at t = " + seconds(c.last_timestamp) +
                                          mapped_on + ": not the recording it was mapped on");
  if (first >= listed && c.last_frame_index + 1 == listed)
    throw InputError(folder.string(), c.session + " already covers the whole sequence (its " + std::to_string(listed) +
                                          " depth frames): there is nothing left to continue");
}

}  // namespace

FrameRange parseFrameRange(const std::string& text) {
  auto number = [&](const std::string& s) {
    int value = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    // A number that does not fit an int is well-formed but past any sequence.
    if (ec == std::errc::result_out_of_range && ptr == s.data() + s.size() && s[0] != '-')
      throw std::invalid_argument("--frames '" + text + "': frame number " + s + " is out of range (0.." +
                                  std::to_string(std::numeric_limits<int>::max()) + ")");
    if (ec != std::errc() || ptr != s.data() + s.size() || value < 0)
      throw std::invalid_argument("--frames '" + text + "': expected A:B (or N for 0:N) with frame numbers >= 0");
    return value;
  };
  const auto colon = text.find(':');
  FrameRange range;
  if (colon == std::string::npos) {
    range.last = number(text);
    if (range.last == 0)
      throw std::invalid_argument("--frames '" + text + "': N means the first N frames (0:N); give N >= 1");
    return range;
  }
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  if (!a.empty()) range.first = number(a);
  if (!b.empty()) range.last = number(b);
  if (range.last >= 0 && range.last <= range.first)
    throw std::invalid_argument("--frames '" + text + "': the end must be after the start");
  return range;
}

std::string frameRangeText(const FrameRange& range) {
  return std::to_string(range.first) + ":" + (range.last < 0 ? std::string() : std::to_string(range.last));
}

// A function try block: whatever the file system refuses to look up (a symbolic-link loop in the
// folder's name, say) is reported as bad input like every other problem with the sequence.
TumSequence TumSequence::open(const fs::path& folder, const SequenceOptions& options) try {
  if (!fs::is_directory(folder))
    throw InputError(folder.string(), fs::exists(folder) ? "is not a folder (expected a TUM RGB-D sequence folder)"
                                                         : "no such sequence folder");
  TumSequence seq;
  seq.folder_ = folder;
  try {
    CameraChoice choice = chooseCamera(folder, options.camera_preset);
    seq.camera_ = choice.camera;
    seq.camera_source_ = choice.source;
    seq.camera_guessed_ = choice.guessed;
    seq.colour_ = choice.colour;
    if (seq.colour_) seq.camera_source_ += "; colour registered to depth";
  } catch (const std::invalid_argument& e) {
    throw InputError("--camera", e.what());
  }

  // Depth list with its rgb partner: from associations.txt when present, else by timestamps.
  struct Pair {
    Stamped depth;
    std::optional<Stamped> rgb;
  };
  std::vector<Pair> pairs;
  const fs::path assoc_file = folder / "associations.txt";
  if (fs::exists(assoc_file)) {
    double previous = -INFINITY;
    for (const ListLine& line : readListFile(assoc_file, 4, "t_rgb rgb_path t_depth depth_path")) {
      const double t_rgb = parseListNumber(line.tokens[0], assoc_file, line.number, "the rgb timestamp");
      const double t_depth = parseListNumber(line.tokens[2], assoc_file, line.number, "the depth timestamp");
      checkTimestamp(t_rgb, assoc_file, line.number);
      checkIncreasing(t_depth, &previous, assoc_file, line.number);
      pairs.push_back({{t_depth, folder / line.tokens[3], assoc_file, line.number},
                       Stamped{t_rgb, folder / line.tokens[1], assoc_file, line.number}});
    }
  } else {
    const std::vector<Stamped> rgb = readImageList(folder, "rgb.txt");
    if (rgb.empty()) throw InputError((folder / "rgb.txt").string(), "lists no frames");
    for (const Stamped& depth : readImageList(folder, "depth.txt")) {
      auto it = std::lower_bound(rgb.begin(), rgb.end(), depth.t, [](const Stamped& s, double t) { return s.t < t; });
      std::optional<Stamped> best;
      for (auto c : {it, it == rgb.begin() ? rgb.end() : std::prev(it)}) {
        if (c == rgb.end() || std::abs(c->t - depth.t) > options.max_rgb_dt_s) continue;
        if (!best || std::abs(c->t - depth.t) < std::abs(best->t - depth.t)) best = *c;
      }
      pairs.push_back({depth, best});
    }
  }
  const fs::path gt_file = folder / "groundtruth.txt";
  seq.has_ground_truth_ = fs::exists(gt_file);
  if (!seq.has_ground_truth_ && options.require_poses)
    throw InputError(gt_file.string(),
                     "no such file; --poses gt needs ground-truth poses (--poses track estimates them)");
  const std::vector<StampedPose> poses =
      seq.has_ground_truth_ ? readTumTrajectory(gt_file) : std::vector<StampedPose>{};

  seq.listed_ = static_cast<int>(pairs.size());
  if (pairs.empty())
    throw InputError((fs::exists(assoc_file) ? assoc_file : folder / "depth.txt").string(), "lists no frames");
  if (options.continues) {
    const int k = options.continues->last_frame_index;
    checkContinuation(folder, seq.listed_,
                      k >= 0 && k < seq.listed_ ? std::optional<double>(pairs[k].depth.t) : std::nullopt,
                      options.frames.first, *options.continues);
  }
  if (options.frames.first >= seq.listed_)
    throw InputError(folder.string(), "--frames starts at " + std::to_string(options.frames.first) +
                                          " but the sequence lists only " + std::to_string(seq.listed_) +
                                          " depth frames");
  if (options.frames.last > seq.listed_ && !options.cut_range_at_end)
    throw InputError(folder.string(), "--frames " + frameRangeText(options.frames) +
                                          " ends past the sequence: it lists " + std::to_string(seq.listed_) +
                                          " depth frames (0:" + std::to_string(seq.listed_) + ")");
  seq.range_ = {options.frames.first,
                options.frames.last < 0 ? seq.listed_ : std::min(options.frames.last, seq.listed_)};
  for (int i = 0; i < seq.listed_; ++i) {
    const Pair& pair = pairs[i];
    if (i < options.frames.first || (options.frames.last >= 0 && i >= options.frames.last)) {
      ++seq.dropped_.outside_range;
      continue;
    }
    if (!pair.rgb) {
      ++seq.dropped_.no_rgb;
      continue;
    }
    const std::optional<Transform> pose = poseAt(poses, pair.depth.t, options.max_pose_dt_s);
    if (!pose && options.require_poses) {
      ++seq.dropped_.no_pose;
      continue;
    }
    for (const Stamped* image : {&pair.depth, &*pair.rgb}) checkImage(*image, folder);
    seq.entries_.push_back({i, pair.depth.t, pair.rgb->t, pair.rgb->path, pair.depth.path,
                            pose.value_or(Transform::Identity()), pose.has_value()});
  }
  if (seq.entries_.empty())
    throw InputError(folder.string(),
                     "no usable frames: " + std::to_string(seq.listed_) + " listed, " +
                         std::to_string(seq.dropped_.no_rgb) + " without an rgb frame within " +
                         std::to_string(options.max_rgb_dt_s) + " s, " + std::to_string(seq.dropped_.no_pose) +
                         " without a ground-truth pose within " + std::to_string(options.max_pose_dt_s) + " s, " +
                         std::to_string(seq.dropped_.outside_range) + " outside --frames");
  return seq;
} catch (const fs::filesystem_error& e) {
  throw InputError(e.path1().string(), e.code().message());
}

RgbdFrame TumSequence::load(std::size_t i) const {
  const FrameEntry& e = entries_.at(i);
  RgbdFrame frame;
  frame.index = e.index;
  frame.timestamp = e.t_depth;
  frame.T_W_C = e.T_W_C;

  const cv::Size size(camera_.width, camera_.height);
  std::string rgb_bytes, depth_bytes;
  frame.rgb = readColorImage(e.rgb_path, size, colour_ ? nullptr : &rgb_bytes);
  frame.depth = readDepthImage(e.depth_path, size, &depth_bytes);
  if (colour_) {
    frame.rgb = registerColour(frame.rgb, frame.depth, camera_, *colour_);
    frame.rgb_resampled = true;
  } else {
    frame.rgb_file = std::make_shared<const std::string>(std::move(rgb_bytes));
  }
  frame.depth_file = std::make_shared<const std::string>(std::move(depth_bytes));
  return frame;
}

}  // namespace vdmap
