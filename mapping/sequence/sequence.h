#pragma once
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <optional>

#include "mapping/core/colour_registration.h"
#include "mapping/core/rgbd_frame.h"

namespace vdmap {

namespace detail {
class FrameDecoder;
}

/// What a sequence was read from. Sequence::open() recognises it by content.
enum class SequenceKind {
  kTumFolder,    ///< TUM RGB-D layout: rgb.txt + depth.txt (or associations.txt), groundtruth.txt
  kSevenScenes,  ///< a 7-Scenes sequence folder: frame-NNNNNN.{color.png|color.jpg,depth.png,pose.txt}
  kReplica,      ///< Replica as NICE-SLAM renders it: results/frameNNNNNN.jpg, results/depthNNNNNN.png, traj.txt
  kScanNet,      ///< ScanNet's exported frames: color/N.jpg, depth/N.png, pose/N.txt, intrinsic/
  kRos1Bag,      ///< a ROS 1 bag
  kMcap,         ///< a ROS 2 recording in MCAP
};

/// "TUM RGB-D folder", "7-Scenes sequence folder", ...: for messages and `vdmap info`.
std::string sequenceKindName(SequenceKind kind);

/// The kind of sequence at `path` by its content (a folder's files, a file's first bytes) and
/// why, e.g. {kTumFolder, "has associations.txt"}; nullopt when it is none (or does not exist).
std::optional<std::pair<SequenceKind, std::string>> recogniseSequence(const std::filesystem::path& path);

/// Which frames of a sequence to use: indices into the depth list (depth.txt, or
/// associations.txt when present), half-open [first, last). last < 0 means to the end.
struct FrameRange {
  int first = 0;
  int last = -1;
};

/// Parses "A:B", "A:", ":B" or "N". A plain N means the first N frames, 0:N, wherever --frames
/// is read (vdmap has one meaning of --frames; frame K alone is K:K+1). Throws
/// std::invalid_argument on bad text or an empty range.
FrameRange parseFrameRange(const std::string& text);

/// "A:B", or "A:" for a range to the end.
std::string frameRangeText(const FrameRange& range);

/// Where a saved mapping session stopped, for a sequence that is to continue it: the sequence
/// must be the recording the session was mapped on.
struct SequenceContinuation {
  std::string session;           ///< what stopped there (the session file), for messages
  std::filesystem::path folder;  ///< the folder the session was mapped on ("": unknown)
  int last_frame_index = -1;     ///< depth-list index of the last frame mapped (-1: none)
  double last_timestamp = 0.0;   ///< s, its depth timestamp
};

struct SequenceOptions {
  std::string camera_preset;  ///< empty: choose from the folder (chooseCamera)
  FrameRange frames;          ///< which depth frames to keep
  /// A range that ends past the last listed frame is an error (it names the sequence's range);
  /// true cuts it there instead (for a verb's default range, such as bench's 0:30).
  bool cut_range_at_end = false;
  double max_rgb_dt_s = 0.02;  ///< depth-rgb association window (docs/method.md 1; --rgb-window)
  double max_pose_dt_s = 0.1;  ///< pose interpolation window
  /// Whose poses the frames get (the recorded ones: groundtruth.txt, a data set's pose files).
  enum class Poses {
    kRecorded,  ///< (--poses gt) the sequence must record poses; frames without one are dropped
    kOptional,  ///< (--poses track) every frame is kept, those without a recorded pose with has_pose = false
    kAuto,      ///< (no --poses) kRecorded when the sequence records poses, else kOptional
  };
  Poses poses = Poses::kRecorded;
  /// Recordings (ROS 1 bags, MCAP): the topics to read, each found by type and name when empty
  /// (docs/cli.md, Sequences), and where poses come from.
  struct Topics {
    std::string depth, rgb, info;           ///< --depth-topic, --rgb-topic, --info-topic
    std::string pose;                       ///< --pose-topic: geometry_msgs/PoseStamped or nav_msgs/Odometry
    std::string world_frame, camera_frame;  ///< --pose-frames WORLD:CAMERA (tf)
  } topics;
  /// Set: the sequence continues a session, so its folder must have the session's folder name
  /// (a moved recording continues) and its depth frame last_frame_index the session's
  /// last_timestamp; else open() throws InputError saying what differs.
  std::optional<SequenceContinuation> continues;
};

/// One usable frame: an rgb/depth pair with its recorded (interpolated) pose. Paths are those of
/// the images (folder kinds).
struct FrameEntry {
  int index = 0;         ///< position in the depth list
  double t_depth = 0.0;  ///< s
  double t_rgb = 0.0;    ///< s
  std::filesystem::path rgb_path;
  std::filesystem::path depth_path;
  Transform T_W_C = Transform::Identity();  ///< ground truth; the identity when !has_pose
  bool has_pose = true;
};

/// How many listed depth frames were not kept, by reason.
struct DropCounts {
  int no_rgb = 0;                              ///< no rgb frame within max_rgb_dt_s
  int no_pose = 0;                             ///< no ground-truth poses within max_pose_dt_s on both sides
  int outside_range = 0;                       ///< outside --frames
  double max_rgb_dt_s = 0, max_pose_dt_s = 0;  ///< the windows they were judged by (SequenceOptions)
};

/// The one source of RGB-D frames (docs/cli.md "Sequences"): a folder in one of the layouts of
/// SequenceKind, recognised by its content. Opening lists the depth frames in time order,
/// associates colour, takes (interpolates) the recorded poses and checks that every image file
/// exists; images are decoded lazily by load(), which is const and safe to call from several
/// threads.
class Sequence {
 public:
  /// Throws InputError ("<file>:<line>: <what was expected>") on any malformed input,
  /// ("PATH: --frames ...") for a range outside the listed frames, and ("PATH: ...") for a
  /// sequence that is not the one options.continues stopped on, or that it already covers.
  static Sequence open(const std::filesystem::path& path, const SequenceOptions& options = {});

  /// The folder (or recording file) the sequence was opened from.
  const std::filesystem::path& folder() const { return folder_; }
  SequenceKind kind() const { return kind_; }
  /// Why open() took it for that kind, e.g. "has rgb.txt and depth.txt".
  const std::string& kindReason() const { return kind_reason_; }
  const PinholeCamera& camera() const { return camera_; }
  const std::string& cameraSource() const { return camera_source_; }
  /// True when no --camera or camera file chose the camera: a preset was guessed (chooseCamera).
  bool cameraGuessed() const { return camera_guessed_; }
  /// The colour camera when the colour images are not registered to the depth (load() registers
  /// them; see colour_registration.h), else nothing.
  const std::optional<ColourCamera>& colourCamera() const { return colour_; }
  const std::vector<FrameEntry>& entries() const { return entries_; }
  std::size_t size() const { return entries_.size(); }
  int listedDepthFrames() const { return listed_; }
  /// True when the sequence records poses (groundtruth.txt, a data set's pose files; they are in
  /// the entries that have one).
  bool hasGroundTruth() const { return has_ground_truth_; }
  /// Where the recorded poses come from ("groundtruth.txt", "frame-NNNNNN.pose.txt", ...), empty
  /// when there are none.
  const std::string& posesSource() const { return poses_source_; }
  /// What was chosen and why, a line each (a recording's topics and frames), for `vdmap info`.
  const std::vector<std::string>& notes() const { return notes_; }
  /// The depth-list range the sequence was opened with, its end resolved: [first, last) with
  /// last <= listedDepthFrames(). What verbs echo as "frames A:B".
  FrameRange frameRange() const { return range_; }
  const DropCounts& dropped() const { return dropped_; }

  /// Decodes frame i (0 <= i < size()) through image_codec.h. Throws InputError naming the file
  /// on a damaged or truncated image, a depth image that is not 16-bit single channel, or an
  /// image whose size differs from its camera's. With a colour camera, the colour image is
  /// registered to the depth (and rgb_file left empty: the file holds the unregistered pixels).
  RgbdFrame load(std::size_t i) const;

 private:
  std::filesystem::path folder_;
  SequenceKind kind_ = SequenceKind::kTumFolder;
  std::string kind_reason_;
  std::string poses_source_;
  std::vector<std::string> notes_;
  std::shared_ptr<const detail::FrameDecoder> decoder_;  // recordings; null: image files
  PinholeCamera camera_;
  std::string camera_source_;
  bool camera_guessed_ = false;
  std::optional<ColourCamera> colour_;
  std::vector<FrameEntry> entries_;
  int listed_ = 0;
  FrameRange range_;
  DropCounts dropped_;
  bool has_ground_truth_ = false;
};

}  // namespace vdmap
