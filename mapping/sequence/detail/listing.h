#pragma once
// What each kind of sequence lists before Sequence::open() applies what is common to all kinds:
// --frames, drops, continuation checks. One function per kind (folder_layouts.cpp).
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mapping/io/camera_config.h"
#include "mapping/sequence/sequence.h"

namespace vdmap::detail {

/// An image a kind's list names, with where it was named (for errors; line 0: no line).
struct ListedImage {
  double t = 0.0;  ///< s
  std::filesystem::path path;
  std::filesystem::path list;
  int line = 0;
};

/// One depth frame as listed, in time order.
struct ListedFrame {
  ListedImage depth;
  std::optional<ListedImage> rgb;  ///< none: no colour frame matched
  std::optional<Transform> pose;   ///< the recorded T_W_C at the depth stamp, if any
};

/// How a kind whose frames are not image files (a recording) decodes listed frame `listed`:
/// depth as CV_16UC1 in the camera's raw units, colour as CV_8UC3 RGB at the colour camera's
/// size (the depth camera's when registered) and, when the colour came encoded, its file bytes.
/// Throws InputError naming the recording and topic. Safe to call from several threads.
class FrameDecoder {
 public:
  virtual ~FrameDecoder() = default;
  virtual void decode(int listed, cv::Mat* depth, cv::Mat* rgb, std::string* rgb_file) const = 0;
};

struct Listing {
  SequenceKind kind = SequenceKind::kTumFolder;  ///< what recogniseSequence() found
  std::string reason;                            ///< why the folder is this kind
  CameraChoice camera;
  std::vector<ListedFrame> frames;
  bool has_poses = false;                       ///< the sequence records poses at all
  std::string poses_source;                     ///< "groundtruth.txt", ...
  std::filesystem::path poses_file;             ///< what a missing-poses error names
  std::filesystem::path list_file;              ///< what "lists no frames" names
  std::shared_ptr<const FrameDecoder> decoder;  ///< recordings; null: the images are files
  std::vector<std::string> notes;               ///< what was chosen and why (topics, frames), for `vdmap info`
};

/// The kind of the folder `folder` by what it holds, with the reason; nullopt when none fits.
std::optional<std::pair<SequenceKind, std::string>> recogniseFolder(const std::filesystem::path& folder);

/// Each folder kind's listing. `options` gives the camera override and the association and pose
/// windows. Throw InputError naming the file and line of anything malformed.
Listing listTumFolder(const std::filesystem::path& folder, const SequenceOptions& options);
Listing listSevenScenes(const std::filesystem::path& folder, const SequenceOptions& options);
Listing listReplica(const std::filesystem::path& folder, const SequenceOptions& options);
Listing listScanNet(const std::filesystem::path& folder, const SequenceOptions& options);
/// A ROS 1 bag or an MCAP (recording_frames.cpp).
Listing listRecording(const std::filesystem::path& file, const SequenceOptions& options);

}  // namespace vdmap::detail
