#pragma once
// The .vdmap session file: a whole mapping session (camera, parameters, keyframes with their
// poses, images, ORB features and local maps, and the covisibility graph) in one versioned
// binary file. docs/vdmap-format.md describes the layout.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "mapping/global_map/global_map.h"
#include "mapping/keyframe/mapper.h"

namespace vdmap {

/// The format version this build writes and the newest it reads (it reads every older one).
inline constexpr std::uint32_t kSessionFormatVersion = 2;

/// Everything of a session besides the keyframe graph.
struct SessionInfo {
  PinholeCamera camera;
  MapperParams mapper;
  GlobalMapParams global;  ///< the live global-map settings when saved (threads not stored)
  int frames_mapped = 0;
  int revisits = 0;
};

/// A loaded session. The graph is what buildGlobalMap(), the renderer and the workbench use.
struct Session {
  SessionInfo info;
  KeyframeGraph graph;
};

/// The info of a Mapper's session with the given global-map settings.
SessionInfo sessionInfo(const Mapper& mapper, const GlobalMapParams& global);

/// The file's bytes. Deterministic: the same graph and info give the same bytes, and
/// encodeSession(decodeSession(b)) == b.
std::string encodeSession(const KeyframeGraph& graph, const SessionInfo& info);

/// Writes the session atomically (temporary file, fsync, rename, fsync of the folder): an
/// interrupted save leaves the previous file or the new one. Throws std::runtime_error naming
/// the file when it cannot be written.
void saveSession(const std::filesystem::path& file, const KeyframeGraph& graph, const SessionInfo& info);

struct SessionDecodeOptions {
  /// Off only for the fuzzer, so that mutations reach the section parsers; never for files.
  bool verify_checksums = true;
};

/// Parses a session from memory; `name` is what errors call it. Throws InputError with one line
/// naming what is wrong (wrong magic, newer format version, other endianness, truncation,
/// a checksum mismatch and the section it is in, a malformed or inconsistent field). Every
/// field is validated before a Session is returned: there is never a partial map.
Session decodeSession(std::string_view bytes, const std::string& name, const SessionDecodeOptions& options = {});

/// Reads and decodes a session file (InputError as decodeSession, or when it cannot be read).
Session loadSession(const std::filesystem::path& file);

/// CRC-32 (IEEE 802.3, the zlib polynomial) of `bytes`, continuing from `crc`.
std::uint32_t crc32(std::string_view bytes, std::uint32_t crc = 0);

}  // namespace vdmap
