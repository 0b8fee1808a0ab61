#include "mapping/sequence/sequence.h"
#include "mapping/core/message_text.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include "mapping/core/error.h"
#include "mapping/io/image_codec.h"
#include "mapping/ros/recording.h"
#include "mapping/sequence/detail/listing.h"

namespace fs = std::filesystem;

namespace vdmap {
namespace {

// An image a list names must be a regular file. A name the file system cannot even look up (a
// symbolic-link loop, a name too long) is the list's error too, not a std::filesystem exception.
void checkImage(const detail::ListedImage& image, const fs::path& folder) {
  std::error_code ec;
  if (fs::is_regular_file(image.path, ec)) return;
  const bool missing = !ec || ec == std::errc::no_such_file_or_directory || ec == std::errc::not_a_directory;
  std::string what = missing ? "does not exist" : "cannot be read: " + ec.message();
  const fs::file_type type = fs::status(image.path, ec).type();
  if (type == fs::file_type::directory) what = "is a folder, not an image file";
  else if (!ec && type != fs::file_type::not_found) what = "is not a regular file";
  std::string name = image.path.lexically_relative(folder).string();
  if (name.size() > 80) name = name.substr(0, 77) + "...";
  if (image.line == 0) throw InputError(image.path.string(), what);
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
    throw InputError(folder.string(), "lists " + counted(listed, "depth frame") + ", but " + c.session +
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

std::string sequenceKindName(SequenceKind kind) {
  switch (kind) {
    case SequenceKind::kTumFolder: return "TUM RGB-D folder";
    case SequenceKind::kSevenScenes: return "7-Scenes sequence folder";
    case SequenceKind::kReplica: return "Replica scene as NICE-SLAM renders it";
    case SequenceKind::kScanNet: return "ScanNet export";
    case SequenceKind::kRos1Bag: return "ROS 1 bag";
    case SequenceKind::kMcap: return "ROS 2 recording (MCAP)";
  }
  return "sequence";
}

std::optional<std::pair<SequenceKind, std::string>> recogniseSequence(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return detail::recogniseFolder(path);
  switch (ros::recordingFormat(path)) {
    case ros::RecordingFormat::kRos1Bag:
      return std::pair{SequenceKind::kRos1Bag, std::string("starts with #ROSBAG V2.0")};
    case ros::RecordingFormat::kMcap:
      return std::pair{SequenceKind::kMcap, std::string("starts with MCAP's magic bytes")};
    default: return std::nullopt;
  }
}

namespace {

detail::Listing listSequence(const fs::path& path, const SequenceOptions& options) {
  if (!fs::exists(path)) throw InputError(path.string(), "no such sequence folder or recording");
  const auto kind = recogniseSequence(path);
  if (!kind && !fs::is_directory(path))
    throw InputError(path.string(), "is neither a sequence folder nor a recording (a ROS 1 bag or an MCAP file)");
  if (!kind)
    throw InputError(
        path.string(),
        "is not a sequence vdmap reads: expected a TUM RGB-D folder (rgb.txt and depth.txt, or "
        "associations.txt), a 7-Scenes sequence (frame-NNNNNN.depth.png), NICE-SLAM's Replica (results/ "
        "and traj.txt), a ScanNet export (color/, depth/, pose/, intrinsic/), a ROS 1 bag or an MCAP file");
  detail::Listing listing;
  try {
    switch (kind->first) {
      case SequenceKind::kSevenScenes: listing = detail::listSevenScenes(path, options); break;
      case SequenceKind::kReplica: listing = detail::listReplica(path, options); break;
      case SequenceKind::kScanNet: listing = detail::listScanNet(path, options); break;
      case SequenceKind::kRos1Bag:
      case SequenceKind::kMcap: listing = detail::listRecording(path, options); break;
      case SequenceKind::kTumFolder: listing = detail::listTumFolder(path, options); break;
    }
  } catch (const std::invalid_argument& e) {
    throw InputError("--camera", e.what());
  }
  listing.kind = kind->first;
  listing.reason = kind->second;
  return listing;
}

}  // namespace

// A function try block: whatever the file system refuses to look up (a symbolic-link loop in the
// folder's name, say) is reported as bad input like every other problem with the sequence.
Sequence Sequence::open(const fs::path& folder, const SequenceOptions& options) try {
  detail::Listing listing = listSequence(folder, options);
  Sequence seq;
  seq.folder_ = folder;
  seq.dropped_.max_rgb_dt_s = options.max_rgb_dt_s;
  seq.dropped_.max_pose_dt_s = options.max_pose_dt_s;
  seq.kind_ = listing.kind;
  seq.kind_reason_ = listing.reason;
  seq.camera_ = listing.camera.camera;
  seq.camera_source_ = listing.camera.source;
  seq.camera_guessed_ = listing.camera.guessed;
  seq.colour_ = listing.camera.colour;
  if (seq.colour_) seq.camera_source_ += "; colour registered to depth";
  seq.has_ground_truth_ = listing.has_poses;
  if (listing.has_poses) seq.poses_source_ = listing.poses_source;
  seq.notes_ = listing.notes;
  seq.decoder_ = listing.decoder;
  const bool require_poses = options.poses == SequenceOptions::Poses::kRecorded ||
                             (options.poses == SequenceOptions::Poses::kAuto && listing.has_poses);
  if (!listing.has_poses && require_poses)
    throw InputError(listing.poses_file.string(),
                     "no such file; --poses gt needs ground-truth poses (--poses track estimates them)");

  const std::vector<detail::ListedFrame>& frames = listing.frames;
  seq.listed_ = static_cast<int>(frames.size());
  if (frames.empty()) throw InputError(listing.list_file.string(), "lists no frames");
  if (options.continues) {
    const int k = options.continues->last_frame_index;
    checkContinuation(folder, seq.listed_,
                      k >= 0 && k < seq.listed_ ? std::optional<double>(frames[k].depth.t) : std::nullopt,
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
    const detail::ListedFrame& frame = frames[i];
    if (i < options.frames.first || (options.frames.last >= 0 && i >= options.frames.last)) {
      ++seq.dropped_.outside_range;
      continue;
    }
    if (!frame.rgb) {
      ++seq.dropped_.no_rgb;
      continue;
    }
    if (!frame.pose && require_poses) {
      ++seq.dropped_.no_pose;
      continue;
    }
    for (const detail::ListedImage* image : {&frame.depth, &*frame.rgb}) checkImage(*image, folder);
    seq.entries_.push_back({i, frame.depth.t, frame.rgb->t, frame.rgb->path, frame.depth.path,
                            frame.pose.value_or(Transform::Identity()), frame.pose.has_value()});
  }
  if (seq.entries_.empty()) {
    char windows[128];
    std::snprintf(windows, sizeof windows,
                  " without an rgb frame within %g s, %d without a ground-truth pose within %g s", options.max_rgb_dt_s,
                  seq.dropped_.no_pose, options.max_pose_dt_s);
    throw InputError(folder.string(),
                     "no usable frames: " + std::to_string(seq.listed_) + " listed, " +
                         std::to_string(seq.dropped_.no_rgb) + windows + ", " +
                         std::to_string(seq.dropped_.outside_range) + " outside --frames" +
                         (seq.dropped_.no_rgb > 0 ? "; --rgb-window S pairs colour further away" : ""));
  }
  return seq;
} catch (const fs::filesystem_error& e) {
  throw InputError(e.path1().string(), e.code().message());
}

RgbdFrame Sequence::load(std::size_t i) const {
  const FrameEntry& e = entries_.at(i);
  RgbdFrame frame;
  frame.index = e.index;
  frame.timestamp = e.t_depth;
  frame.T_W_C = e.T_W_C;

  const cv::Size size(camera_.width, camera_.height);
  const cv::Size rgb_size = colour_ && colour_->width > 0 ? cv::Size(colour_->width, colour_->height) : size;
  std::string rgb_bytes, depth_bytes;
  if (decoder_) {
    decoder_->decode(e.index, &frame.depth, &frame.rgb, colour_ ? nullptr : &rgb_bytes);
  } else {
    frame.rgb = readColorImage(e.rgb_path, rgb_size, colour_ ? nullptr : &rgb_bytes);
    frame.depth = readDepthImage(e.depth_path, size, &depth_bytes);
  }
  if (colour_) {
    frame.rgb = registerColour(frame.rgb, frame.depth, camera_, *colour_);
    frame.rgb_resampled = true;
  } else {
    if (!rgb_bytes.empty()) frame.rgb_file = std::make_shared<const std::string>(std::move(rgb_bytes));
  }
  if (!depth_bytes.empty()) frame.depth_file = std::make_shared<const std::string>(std::move(depth_bytes));
  return frame;
}

}  // namespace vdmap
