#pragma once
// The .vdmap session file: a whole mapping session (camera, parameters, keyframes with their
// poses, images, ORB features and local maps, and the covisibility graph) in one versioned
// binary file. docs/vdmap-format.md describes the layout.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "mapping/core/atomic_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap {

/// The format version this build writes and the newest it reads. 2 added the mapper's state
/// (current keyframe, last frame) and the sequence folder, so a session can continue mapping;
/// version 1 files still load (MapperState without a current keyframe: they cannot continue).
/// 3 added fusion across groups' parameters (versions 1 and 2 load with fusion off). 4 added the
/// pose source (ground truth or tracked) and, in the mapper state, the lost frames, every mapped
/// frame's pose in its keyframe (the trajectory), the tracker's motion state and the keyframe
/// pose graph (edges, loop closures), so a tracked session continues as if it had not stopped.
/// 5 added the counts of frames placed on a weak estimate and relocalised (4 loads them as 0).
/// 6 stores each keyframe image as the PNG or JPEG file the keyframe holds and packs the
/// keypoints, descriptors and cells with zlib (a third of the size), and no longer stores the
/// loop closures' wall-clock optimisation times, so equal runs give equal files (4 and 5 load
/// with those times dropped). 7 adds, per keyframe, what each integrated frame saw free (its
/// pose in the keyframe and its blocks' nearest depths; 6 and older load without: free space then
/// comes from the keyframes' views alone).
inline constexpr std::uint32_t kSessionFormatVersion = 7;

/// Everything of a session besides the keyframe graph.
struct SessionInfo {
  PinholeCamera camera;
  MapperParams mapper;
  GlobalMapParams global;  ///< the live global-map settings when saved (threads not stored)
  MapperState state;       ///< what the Mapper needs to continue (Mapper::state())
  std::string sequence;    ///< the folder the frames came from (absolute; "" when unknown)
  std::uint32_t format_version = kSessionFormatVersion;  ///< of the file it was read from
};

/// A loaded session. The graph is what buildGlobalMap(), the renderer and the workbench use.
struct Session {
  SessionInfo info;
  KeyframeGraph graph;
};

/// The info of a Mapper's session with the given global-map settings and sequence folder (made
/// absolute).
SessionInfo sessionInfo(const Mapper& mapper, const GlobalMapParams& global,
                        const std::filesystem::path& sequence = {});

/// True when the parameters store as the same bytes (every field equal), e.g. to check that a
/// run's parameters are a loaded session's.
bool sameMapperParams(const MapperParams& a, const MapperParams& b);

/// The file's bytes, always in the current format. Deterministic: the same graph and info give
/// the same bytes, and encodeSession(decodeSession(b)) == b for a file of the current format.
std::string encodeSession(const KeyframeGraph& graph, const SessionInfo& info);

/// encodeSession handing the bytes to `sink` a section at a time (a header, then each section
/// whole), so that the file is never held in memory at once.
void encodeSession(const KeyframeGraph& graph, const SessionInfo& info, const ByteSink& sink);

/// Writes the session atomically (temporary file, fsync, rename, fsync of the folder): an
/// interrupted save leaves the previous file or the new one. Section by section: memory holds one
/// keyframe's section at a time, not the file. Throws std::runtime_error naming
/// the file when it cannot be written.
void saveSession(const std::filesystem::path& file, const KeyframeGraph& graph, const SessionInfo& info);

struct SessionDecodeOptions {
  /// Off only for the fuzzer, so that mutations reach the section parsers; never for files.
  bool verify_checksums = true;
  /// Decode every keyframe's colour and depth image (format 6 stores the files) to prove that
  /// they decode. Off for the headless renderer, which needs no image for the global and keyframe
  /// views: it decodes a container view's image when it draws it (keyframeImage()), so a damaged
  /// image is still one error naming the session and the keyframe. The workbench stays eager.
  bool decode_images = true;
  /// Keep each keyframe's image files (checked as decode_images says either way). Off for
  /// `vdmap query`, which reads the local maps and poses alone: its keyframes then have empty images.
  bool keep_images = true;
  /// Keep each keyframe's keypoints and descriptors (checked either way). Off for the verbs that
  /// neither track nor close loops (render, query): their keyframes then have no features.
  bool keep_features = true;
};

/// Parses a session from memory; `name` is what errors call it. Throws InputError with one line
/// naming what is wrong (wrong magic, newer format version, other endianness, truncation,
/// a checksum mismatch and the section it is in, a malformed or inconsistent field). Every
/// field is validated before a Session is returned: there is never a partial map.
Session decodeSession(std::string_view bytes, const std::string& name, const SessionDecodeOptions& options = {});

/// True when `file` is a regular file that starts with the session magic ('VDMAPSES'), so a
/// verb can take a session where it takes a sequence folder or a map. Reads 8 bytes.
bool isSessionFile(const std::filesystem::path& file);

/// True when `file` is a regular file that starts with the session magic or is named *.vdmap:
/// what a verb that takes a session besides other things reads as a session, so that a damaged
/// session (empty, its magic overwritten) is reported as one by loadSession().
bool isSessionPath(const std::filesystem::path& file);

/// Reads and decodes a session file (InputError as decodeSession, or when it cannot be read; a
/// file named *.vdmap without the session magic is "a damaged session file").
Session loadSession(const std::filesystem::path& file, const SessionDecodeOptions& options = {});

/// Keyframe `k`'s colour image (CV_8UC3) of a session named `session` (its file): throws
/// InputError "SESSION: keyframe K: rgb image: ..." when it does not decode (a session loaded
/// with decode_images off was not checked).
cv::Mat keyframeImage(const Keyframe& k, const std::string& session);

/// CRC-32 (IEEE 802.3, the zlib polynomial) of `bytes`, continuing from `crc`.
std::uint32_t crc32(std::string_view bytes, std::uint32_t crc = 0);

}  // namespace vdmap
