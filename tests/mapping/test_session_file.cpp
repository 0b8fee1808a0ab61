// The .vdmap session file: round trip (byte-identical re-save, identical global map), every way a
// file can be damaged gives one InputError naming what is wrong, and a writer killed at random
// moments always leaves a file that loads.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cstring>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "mapping/core/error.h"
#include "mapping/files/session_file.h"
#include "mapping/pipeline/parameters.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

using test::readFile;
using test::TempDir;

struct Saved {
  Mapper mapper;
  SessionInfo info;
  std::string bytes;
};

Saved makeSession(int frames) {
  Mapper mapper = test::mapTurningBoxRoom(frames);
  GlobalMapParams global;
  global.merge_distance_m = 0.2;
  SessionInfo info = sessionInfo(mapper, global);
  std::string bytes = encodeSession(mapper.graph(), info);
  return Saved{std::move(mapper), info, std::move(bytes)};
}

// A session with several keyframes, edges and a revisit, with non-default global settings.
const Saved& session() {
  static const Saved saved = makeSession(66);
  return saved;
}

// Two keyframes and an edge: enough to damage every kind of section, quick to decode.
const Saved& smallSession() {
  static const Saved saved = makeSession(10);
  return saved;
}

// `graph` without what its frames saw free (formats before 7 did not store it).
KeyframeGraph withoutFramesFree(KeyframeGraph graph) {
  for (std::size_t i = 0; i < graph.size(); ++i) graph.keyframe(static_cast<int>(i)).frames_free.clear();
  return graph;
}

// The InputError message of decoding `bytes`, or "" when it decodes.
std::string decodeError(const std::string& bytes) {
  try {
    decodeSession(bytes, "s.vdmap");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void putU32(std::string* bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) (*bytes)[at + i] = static_cast<char>(v >> (8 * i));
}
// Rewrites the header checksum after a deliberate header change.
void resealHeader(std::string* bytes) { putU32(bytes, 20, crc32(std::string_view(*bytes).substr(0, 20))); }

TEST(SessionFile, Crc32MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32("123456789"), 0xCBF43926u);  // the CRC-32/ISO-HDLC check value
  EXPECT_EQ(crc32("6789", crc32("12345")), 0xCBF43926u);
}

TEST(SessionFile, ReloadedSessionIsEqualReSavesByteIdenticalAndMergesIdentically) {
  const Saved& s = session();
  const KeyframeGraph& graph = s.mapper.graph();
  ASSERT_GE(graph.size(), 4u);
  ASSERT_GT(graph.edges().size(), 0u);
  TempDir dir;
  saveSession(dir / "a.vdmap", graph, s.info);
  EXPECT_EQ(readFile(dir / "a.vdmap"), s.bytes);
  const Session loaded = loadSession(dir / "a.vdmap");
  EXPECT_EQ(encodeSession(loaded.graph, loaded.info), s.bytes);

  EXPECT_EQ(loaded.info.camera.fx, s.info.camera.fx);
  EXPECT_EQ(loaded.info.global.merge_distance_m, 0.2);
  EXPECT_EQ(loaded.info.state.frames_mapped, 66);
  EXPECT_EQ(loaded.info.state.revisits, s.mapper.revisits());
  ASSERT_EQ(loaded.graph.size(), graph.size());
  for (std::size_t i = 0; i < graph.size(); ++i) {
    const Keyframe &a = graph.keyframes()[i], &b = loaded.graph.keyframes()[i];
    EXPECT_EQ(a.T_W_K.matrix(), b.T_W_K.matrix());
    EXPECT_EQ(a.timestamp, b.timestamp);
    EXPECT_EQ(cv::norm(a.rgb(), b.rgb(), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.depth(), b.depth(), cv::NORM_INF), 0.0);
    ASSERT_EQ(a.features.size(), b.features.size());
    EXPECT_EQ(cv::norm(a.features.descriptors, b.features.descriptors, cv::NORM_INF), 0.0);
    ASSERT_EQ(a.frames_free.size(), b.frames_free.size());
    EXPECT_GE(a.frames_free.size(), 1u);
    EXPECT_LE(a.frames_free.size(), static_cast<std::size_t>(a.frames_integrated));
    for (std::size_t f = 0; f < a.frames_free.size(); ++f) {
      EXPECT_EQ(a.frames_free[f].T_K_C.matrix(), b.frames_free[f].T_K_C.matrix());
      EXPECT_EQ(a.frames_free[f].near_mm, b.frames_free[f].near_mm);
      EXPECT_EQ(a.frames_free[f].cols, b.frames_free[f].cols);
    }
    ASSERT_EQ(a.container.size(), b.container.size());
    for (std::size_t c = 0; c < a.container.size(); ++c) {
      const StoredCell &x = a.container.cells()[c], &y = b.container.cells()[c];
      ASSERT_EQ(x.grid_index, y.grid_index);
      ASSERT_EQ(b.container.find(y.grid_index), &y);
      ASSERT_EQ(x.mean, y.mean);
      ASSERT_EQ(x.n, y.n);
    }
  }
  const auto edges = loaded.graph.edges().edges();
  ASSERT_EQ(edges.size(), graph.edges().size());
  for (const CovisibilityEdge& e : edges) EXPECT_EQ(e.weight, graph.edges().weight(e.a, e.b));

  const GlobalMap before = buildGlobalMap(graph, s.info.global);
  const GlobalMap after = buildGlobalMap(loaded.graph, loaded.info.global);
  ASSERT_GT(before.ellipsoids.size(), 0u);
  ASSERT_EQ(after.ellipsoids.size(), before.ellipsoids.size());
  for (std::size_t i = 0; i < before.ellipsoids.size(); ++i) {
    ASSERT_EQ(after.ellipsoids[i].mean, before.ellipsoids[i].mean);
    ASSERT_EQ(after.ellipsoids[i].cov, before.ellipsoids[i].cov);
    ASSERT_EQ(after.ellipsoids[i].keyframe, before.ellipsoids[i].keyframe);
  }
}

// The verbs that only draw or query drop what they never read; the local maps, poses and the
// global map stay exactly those of a full load.
TEST(SessionFile, ImagesAndFeaturesCanBeLeftOut) {
  const Saved& s = smallSession();
  const Session full = decodeSession(s.bytes, "s.vdmap");
  const Session lean =
      decodeSession(s.bytes, "s.vdmap", {.decode_images = false, .keep_images = false, .keep_features = false});
  ASSERT_EQ(lean.graph.size(), full.graph.size());
  for (std::size_t i = 0; i < full.graph.size(); ++i) {
    const Keyframe &a = full.graph.keyframes()[i], &b = lean.graph.keyframes()[i];
    EXPECT_GT(a.memory().images, 0u);
    EXPECT_GT(a.features.size(), 0u);
    EXPECT_EQ(b.memory().images, 0u);
    EXPECT_EQ(b.memory().features, 0u);
    EXPECT_EQ(a.T_W_K.matrix(), b.T_W_K.matrix());
    EXPECT_EQ(a.memory().ellipsoids, b.memory().ellipsoids);
  }
  const GlobalMap a = buildGlobalMap(full.graph, full.info.global), b = buildGlobalMap(lean.graph, lean.info.global);
  ASSERT_EQ(a.ellipsoids.size(), b.ellipsoids.size());
  for (std::size_t i = 0; i < a.ellipsoids.size(); ++i) {
    ASSERT_EQ(a.ellipsoids[i].mean, b.ellipsoids[i].mean);
    ASSERT_EQ(a.ellipsoids[i].cov, b.ellipsoids[i].cov);
  }
}

TEST(SessionFile, EmptySessionRoundTrips) {
  const SessionInfo info;
  const std::string bytes = encodeSession(KeyframeGraph{}, info);
  const Session loaded = decodeSession(bytes, "empty.vdmap");
  EXPECT_EQ(loaded.graph.size(), 0u);
  EXPECT_EQ(encodeSession(loaded.graph, loaded.info), bytes);
}

// A keyframe that found no features stores 0 descriptor rows of 32 bytes; it loads (the fuzzer
// found that reading it copied into a null image under UBSan).
TEST(SessionFile, AKeyframeWithoutFeaturesRoundTrips) {
  Mapper mapper = test::mapTurningBoxRoom(10);
  FrameFeatures& f = mapper.graph().keyframe(0).features;
  f.keypoints.clear();
  f.depth_m.clear();
  f.descriptors = cv::Mat(0, 32, CV_8UC1);
  const std::string bytes = encodeSession(mapper.graph(), sessionInfo(mapper, GlobalMapParams{}));
  const Session loaded = decodeSession(bytes, "nofeatures.vdmap");
  EXPECT_EQ(loaded.graph.keyframe(0).features.size(), 0u);
  EXPECT_EQ(loaded.graph.keyframe(0).features.descriptors.rows, 0);
  EXPECT_EQ(encodeSession(loaded.graph, loaded.info), bytes);
}

std::uint64_t u64At(const std::string& bytes, std::size_t at) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= std::uint64_t{static_cast<unsigned char>(bytes[at + i])} << (8 * i);
  return v;
}

// Removes `n` bytes at `at` of the payload of the section starting at `section`, and fixes the
// section's length and checksum.
void eraseInSection(std::string* bytes, std::size_t section, std::size_t at, std::size_t n) {
  const std::size_t payload = section + 16;
  const std::uint64_t length = u64At(*bytes, section + 4) - n;
  bytes->erase(payload + at, n);
  for (int i = 0; i < 8; ++i) (*bytes)[section + 4 + i] = static_cast<char>(length >> (8 * i));
  const std::string_view view(*bytes);
  putU32(bytes, section + 12, crc32(view.substr(payload, length), crc32(view.substr(section, 12))));
}

std::size_t stateSection(const std::string& bytes) {
  constexpr std::size_t kParm = 24;
  const std::size_t msta = kParm + 16 + u64At(bytes, kParm + 4);
  EXPECT_EQ(bytes.substr(msta, 4), "MSTA");
  return msta;
}

// Little-endian appends, as the format writes its fields.
template <typename T>
void putLe(std::string* out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out->append(raw, sizeof(T));
}

// An image as format 5 stored it: rows, cols, type, then the pixels row by row.
void putMat(std::string* out, const cv::Mat& m) {
  putLe(out, m.rows), putLe(out, m.cols), putLe(out, m.type());
  const cv::Mat c = m.isContinuous() ? m : m.clone();
  if (!c.empty()) out->append(reinterpret_cast<const char*>(c.data), c.total() * c.elemSize());
}

// `bytes` (the current format) as format 5 wrote it: each loop closure with its optimisation's
// wall time after its correction (here 12.5 ms), and each KFRM with the images' pixels and the records
// as they are rather than the image files and the packed records.
std::string asFormat5(const std::string& bytes) {
  const Session s = decodeSession(bytes, "v6.vdmap");
  std::string old = bytes.substr(0, 24);
  putU32(&old, 8, 5);
  resealHeader(&old);
  std::size_t at = 24;
  for (int section = 0; at < bytes.size(); ++section) {
    const std::string tag = bytes.substr(at, 4);
    const std::uint64_t length = u64At(bytes, at + 4);
    std::string payload = bytes.substr(at + 16, length);
    if (tag == "MSTA") {  // the loops (24 bytes each) end 8 bytes before the payload's end
      const std::size_t loops = s.info.state.loops.size(), first = payload.size() - 8 - 24 * loops;
      std::string time;
      putLe(&time, 12.5);
      for (std::size_t l = loops; l-- > 0;) payload.insert(first + 24 * l + 24, time);
    } else if (tag == "KFRM") {
      const Keyframe& k = s.graph.keyframe(section - 2);
      std::string kf = payload.substr(0, 4 + 4 + 8 + 12 * 8 + 4);  // id .. frames_integrated, unchanged
      putMat(&kf, k.rgb());
      putMat(&kf, k.depth());
      putLe(&kf, static_cast<std::uint32_t>(k.features.keypoints.size()));
      for (std::size_t i = 0; i < k.features.keypoints.size(); ++i) {
        const cv::KeyPoint& p = k.features.keypoints[i];
        for (float v : {p.pt.x, p.pt.y, p.size, p.angle, p.response}) putLe(&kf, v);
        putLe(&kf, p.octave), putLe(&kf, p.class_id), putLe(&kf, k.features.depth_m[i]);
      }
      putMat(&kf, k.features.descriptors);
      putLe(&kf, static_cast<std::uint32_t>(k.container.size()));
      for (const StoredCell& c : k.container.cells()) {
        for (float v : c.mean) putLe(&kf, v);
        for (float v : c.scatter) putLe(&kf, v);
        for (float v : c.color) putLe(&kf, v);
        putLe(&kf, c.n), putLe(&kf, c.grid_index);
      }
      payload = kf;
    }
    std::string head = tag;
    putLe(&head, static_cast<std::uint64_t>(payload.size()));
    putLe(&head, crc32(payload, crc32(head)));
    old += head + payload;
    at += 16 + length;
  }
  return old;
}

// Format 5 stored the pixels and the records as they are, and the loop closures' wall times:
// such a file loads as the same session (the times dropped) and re-saves as the current format.
TEST(SessionFile, Format5FilesLoadAsTheSameSession) {
  const Saved& s = smallSession();
  SessionInfo info = s.info;
  info.state.loops.push_back({8, 1, 0, 40, 0.01, 0.0});
  const std::string bytes = encodeSession(s.mapper.graph(), info);
  const std::string v5 = asFormat5(bytes);
  EXPECT_GT(v5.size(), bytes.size());
  const Session old = decodeSession(v5, "v5.vdmap");
  EXPECT_EQ(old.info.format_version, 5u);
  ASSERT_EQ(old.info.state.loops.size(), 1u);
  EXPECT_EQ(old.info.state.loops[0].correction_m, 0.01);
  EXPECT_EQ(old.info.state.loops[0].pose_graph_ms, 0.0) << "a wall time is not part of the session";
  EXPECT_EQ(encodeSession(old.graph, old.info), encodeSession(withoutFramesFree(s.mapper.graph()), info));
  for (std::size_t k = 0; k < old.graph.size(); ++k) {
    EXPECT_EQ(cv::norm(old.graph.keyframe(static_cast<int>(k)).rgb(),
                       s.mapper.graph().keyframe(static_cast<int>(k)).rgb(), cv::NORM_INF),
              0);
    EXPECT_EQ(cv::norm(old.graph.keyframe(static_cast<int>(k)).depth(),
                       s.mapper.graph().keyframe(static_cast<int>(k)).depth(), cv::NORM_INF),
              0);
  }
}

// Format 6 stored no frame's free space: each KFRM ends with the packed features and cells (here
// the current format's without the frames' free space, its zero count cut off). It loads with
// none, and the map then answers free from the keyframes' views alone.
TEST(SessionFile, Format6FilesLoadWithoutTheFramesFreeSpace) {
  const Saved& s = smallSession();
  ASSERT_FALSE(s.mapper.graph().keyframe(0).frames_free.empty());
  const std::string bare = encodeSession(withoutFramesFree(s.mapper.graph()), s.info);
  std::string v6 = bare;
  putU32(&v6, 8, 6);
  resealHeader(&v6);
  for (std::size_t at = 24; at < v6.size(); at += 16 + u64At(v6, at + 4))
    if (v6.substr(at, 4) == "KFRM") eraseInSection(&v6, at, u64At(v6, at + 4) - 4, 4);
  EXPECT_LT(v6.size(), bare.size());
  const Session old = decodeSession(v6, "v6.vdmap");
  EXPECT_EQ(old.info.format_version, 6u);
  for (const Keyframe& k : old.graph.keyframes()) EXPECT_TRUE(k.frames_free.empty());
  EXPECT_EQ(encodeSession(old.graph, old.info), bare);
}

// The session holds no wall-clock time: runs that differ only in how long the loop closures'
// optimisations took give the same bytes (docs/vdmap-format.md, MSTA).
TEST(SessionFile, LoopClosureTimesAreNotStored) {
  const Saved& s = smallSession();
  SessionInfo fast = s.info, slow = s.info;
  fast.state.loops.push_back({8, 1, 0, 40, 0.01, 1.5});
  slow.state.loops.push_back({8, 1, 0, 40, 0.01, 250.0});
  EXPECT_EQ(encodeSession(s.mapper.graph(), fast), encodeSession(s.mapper.graph(), slow));
}

// `bytes` as format 4 wrote it: MSTA without the weak and relocalised counts (i32, i32) at its end.
std::string asFormat4(const std::string& current) {
  std::string old = asFormat5(current);
  const std::size_t msta = stateSection(old);
  eraseInSection(&old, msta, u64At(old, msta + 4) - 8, 8);
  putU32(&old, 8, 4);
  resealHeader(&old);
  return old;
}

// `bytes` as format 3 wrote it: PARM without the pose source (u32 after keyframe_every, 133
// bytes into it) and MSTA without what version 4 added after the sequence folder.
std::string asFormat3(const std::string& bytes) {
  constexpr std::size_t kParm = 24, kPoseSourceAt = 48 + 85;
  std::string old = asFormat5(bytes);
  eraseInSection(&old, kParm, kPoseSourceAt, 4);
  const std::size_t msta = stateSection(old);
  std::uint32_t folder = 0;
  for (int i = 0; i < 4; ++i) folder |= std::uint32_t{static_cast<unsigned char>(old[msta + 16 + 16 + i])} << (8 * i);
  const std::size_t kept = 20 + folder;
  eraseInSection(&old, msta, kept, u64At(old, msta + 4) - kept);
  putU32(&old, 8, 3);
  resealHeader(&old);
  return old;
}

// `bytes` as format 2 wrote it: format 3's PARM without the two fusion fields (bool, f64) that
// format 3 added before the frame counts (i32, i32, u32).
std::string asFormat2(const std::string& bytes) {
  constexpr std::size_t kParm = 24, kFusionBytes = 9, kTailBytes = 12;
  std::string old = asFormat3(bytes);
  eraseInSection(&old, kParm, u64At(old, kParm + 4) - kTailBytes - kFusionBytes, kFusionBytes);
  putU32(&old, 8, 2);
  resealHeader(&old);
  return old;
}

// Format 4 had no weak and relocalised counts: they load as 0; re-saved, the file is current.
TEST(SessionFile, Format4FilesLoadWithoutTheWeakCounts) {
  const Saved& s = smallSession();
  SessionInfo counted = s.info;
  counted.state.frames_weak = 2;
  counted.state.frames_relocalised = 1;
  const std::string bytes = encodeSession(s.mapper.graph(), counted);
  const Session now = decodeSession(bytes, "v5.vdmap");
  EXPECT_EQ(now.info.state.frames_weak, 2);
  EXPECT_EQ(now.info.state.frames_relocalised, 1);
  const Session old = decodeSession(asFormat4(bytes), "v4.vdmap");
  EXPECT_EQ(old.info.format_version, 4u);
  EXPECT_EQ(old.info.state.frames_weak, 0);
  EXPECT_EQ(old.info.state.frames_relocalised, 0);
  EXPECT_EQ(old.info.state.frame_poses.size(), s.info.state.frame_poses.size());
  EXPECT_EQ(encodeSession(old.graph, old.info), encodeSession(withoutFramesFree(s.mapper.graph()), s.info));
  // More weak and relocalised frames than placed ones is a damaged state.
  counted.state.frames_weak = static_cast<int>(s.info.state.frame_poses.size());
  EXPECT_THROW(encodeSession(s.mapper.graph(), counted), std::invalid_argument);
}

// Format 3 (before tracking): ground-truth poses, no trajectory; re-saved as the current format
// it is the same session (the small session has ground-truth poses).
TEST(SessionFile, Format3FilesLoadWithGroundTruthPoses) {
  const Saved& s = smallSession();
  const Session old = decodeSession(asFormat3(s.bytes), "v3.vdmap");
  EXPECT_EQ(old.info.format_version, 3u);
  EXPECT_EQ(old.info.mapper.poses, PoseSource::kGroundTruth);
  EXPECT_TRUE(old.info.state.frame_poses.empty());
  EXPECT_EQ(old.info.state.current_keyframe, s.info.state.current_keyframe);
  SessionInfo info = old.info;
  info.state.frame_poses = s.info.state.frame_poses;
  EXPECT_EQ(encodeSession(old.graph, info), encodeSession(withoutFramesFree(s.mapper.graph()), s.info));
}

TEST(SessionFile, Format2FilesLoadWithFusionOffAsTheyWereBuilt) {
  const Saved& s = smallSession();
  ASSERT_TRUE(s.info.global.fuse_across_groups);
  const Session old = decodeSession(asFormat2(s.bytes), "v2.vdmap");
  EXPECT_EQ(old.info.format_version, 2u);
  EXPECT_FALSE(old.info.global.fuse_across_groups);
  EXPECT_EQ(old.info.global.merge_distance_m, 0.2);
  EXPECT_EQ(old.graph.size(), s.mapper.graph().size());
  SessionInfo info = old.info;
  info.global.fuse_across_groups = true;
  info.state.frame_poses = s.info.state.frame_poses;  // format 4 added the trajectory
  EXPECT_EQ(encodeSession(old.graph, info), encodeSession(withoutFramesFree(s.mapper.graph()), s.info))
      << "re-saved in the current format";
}

TEST(SessionFile, DamagedHeadersNameWhatIsWrong) {
  const std::string& good = smallSession().bytes;
  EXPECT_NE(decodeError("").find("wrong magic"), std::string::npos);
  EXPECT_NE(decodeError("solid\n" + good).find("wrong magic"), std::string::npos);
  EXPECT_NE(decodeError(good.substr(0, 12)).find("truncated"), std::string::npos);

  std::string newer = good;
  putU32(&newer, 8, kSessionFormatVersion + 1);
  resealHeader(&newer);
  const std::string expected = "format version " + std::to_string(kSessionFormatVersion + 1) +
                               " is newer than this vdmap reads (" + std::to_string(kSessionFormatVersion) + ")";
  EXPECT_NE(decodeError(newer).find(expected), std::string::npos) << decodeError(newer);

  std::string big_endian = good;
  putU32(&big_endian, 12, 0x04030201);
  resealHeader(&big_endian);
  EXPECT_NE(decodeError(big_endian).find("not a little-endian"), std::string::npos);

  std::string sections = good;
  putU32(&sections, 16, 3);
  resealHeader(&sections);
  EXPECT_NE(decodeError(sections).find("sections, the header says 3"), std::string::npos) << decodeError(sections);
}

TEST(SessionFile, EveryTruncationIsAnError) {
  const std::string& good = smallSession().bytes;
  ASSERT_GE(smallSession().mapper.graph().size(), 2u);
  std::mt19937 rng(3);
  std::vector<std::size_t> cuts = {0, 1, 8, 23, 24, 25, 39, 40, good.size() - 1};
  for (int i = 0; i < 200; ++i) cuts.push_back(std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(rng));
  for (std::size_t cut : cuts) {
    const std::string message = decodeError(good.substr(0, cut));
    ASSERT_NE(message, "") << "cut at " << cut << " decoded";
    ASSERT_EQ(message.find("s.vdmap: "), 0u) << message;
  }
  EXPECT_NE(decodeError(good.substr(0, good.size() - 100)).find("truncated"), std::string::npos);
  EXPECT_NE(decodeError(good + "x").find("1 unexpected bytes at the end"), std::string::npos);
}

TEST(SessionFile, EveryFlippedByteIsAnError) {
  const std::string& good = smallSession().bytes;
  std::mt19937 rng(5);
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < 300; ++i) at.push_back(i);  // header, parameters, first section head
  for (int i = 0; i < 300; ++i) at.push_back(std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(rng));
  for (std::size_t i : at) {
    std::string bad = good;
    bad[i] = static_cast<char>(bad[i] ^ (1 << (i % 8)));
    ASSERT_NE(decodeError(bad), "") << "flipped byte " << i << " decoded";
  }
  std::string bad = good;
  bad[good.size() / 2] ^= 0x10;
  EXPECT_NE(decodeError(bad).find("checksum mismatch (the file is corrupted)"), std::string::npos);
  EXPECT_NE(decodeError(bad).find("section "), std::string::npos);
}

TEST(SessionFile, InconsistentContentWithValidChecksumsIsRejected) {
  const Saved& s = smallSession();
  KeyframeGraph graph;
  graph.add(Keyframe{0, 0, 0.0, Transform::Identity(), {}, {}, {}, KeyframeContainer(s.info.camera, 5), 0, {}});
  graph.edges().strengthen(0, 3, 0.5);  // keyframe 3 does not exist
  SessionInfo info = s.info;
  info.state = {};  // a state that fits one keyframe
  EXPECT_NE(decodeError(encodeSession(graph, info)).find("edge 0-3 does not join two of the 1 keyframes"),
            std::string::npos)
      << decodeError(encodeSession(graph, info));

  SessionInfo bad_params = info;
  bad_params.mapper.keyframes.tau = 2.0;
  EXPECT_NE(decodeError(encodeSession(KeyframeGraph{}, bad_params)).find("tau and tau_edge must be within 0..1"),
            std::string::npos);
}

TEST(SessionFile, MissingFileAndUnwritableFolder) {
  TempDir dir;
  EXPECT_THROW(loadSession(dir / "absent.vdmap"), InputError);
  const Saved& s = smallSession();
  EXPECT_THROW(saveSession(dir / "no" / "such" / "a.vdmap", s.mapper.graph(), s.info), std::runtime_error);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "a failed save leaves nothing behind";
  // Saving over a folder fails at the rename: the message gives that reason (it said "Success").
  std::filesystem::create_directory(dir / "folder.vdmap");
  try {
    saveSession(dir / "folder.vdmap", s.mapper.graph(), s.info);
    ADD_FAILURE() << "saved over a folder";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("folder.vdmap: cannot write (Is a directory)"), std::string::npos) << message;
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1) << "only the folder is left";
}

// A child process saves two different sessions in turn as fast as it can; the parent kills it
// with SIGKILL after a random delay. Whatever moment the kill hits (encoding, writing, fsync,
// rename), the file on disk must load and be exactly one of the two sessions.
TEST(SessionFile, WriterKilledAtRandomMomentsLeavesALoadableFile) {
  const Saved& s = session();
  const Mapper& small = smallSession().mapper;
  const SessionInfo& small_info = smallSession().info;
  const std::string& small_bytes = smallSession().bytes;
  TempDir dir;
  const std::filesystem::path file = dir / "map.vdmap";
  // Kill delays span about three saves, so kills land in every stage of both saves.
  const auto start = std::chrono::steady_clock::now();
  saveSession(file, s.mapper.graph(), s.info);
  saveSession(file, small.graph(), small_info);
  const auto two_saves_us =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();

  std::mt19937 rng(17);
  int saw_big = 0, saw_small = 0;
  for (int round = 0; round < 30; ++round) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      try {
        for (int i = round;; ++i) {
          if (i % 2 == 0) saveSession(file, s.mapper.graph(), s.info);
          else saveSession(file, small.graph(), small_info);
        }
      } catch (...) {
      }
      _exit(1);
    }
    std::this_thread::sleep_for(
        std::chrono::microseconds(std::uniform_int_distribution<long>(0, 2 * two_saves_us)(rng)));
    kill(child, SIGKILL);
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the writer must have been killed, not have failed";
    Session loaded = loadSession(file);  // throws (fails the test) on a broken file
    const std::string bytes = encodeSession(loaded.graph, loaded.info);
    ASSERT_TRUE(bytes == s.bytes || bytes == small_bytes) << "round " << round;
    (bytes == s.bytes ? saw_big : saw_small)++;
  }
  // Not a timing assertion: a mix only shows that kills landed at different moments.
  RecordProperty("rounds_with_big_session", saw_big);
  RecordProperty("rounds_with_small_session", saw_small);
}

TEST(SessionFile, MapVerbSavesTheSessionItMapped) {
  TempDir dir;
  test::writeTinySequence(dir / "seq", 6);
  const test::RunResult r =
      test::runVdmap("map '" + (dir / "seq").string() + "' --out '" + (dir / "out").string() + "' --save '" +
                     (dir / "s.vdmap").string() + "' --keyframe-every 2 --merge-distance 0.3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Session s = loadSession(dir / "s.vdmap");
  EXPECT_EQ(s.graph.size(), 3u);
  EXPECT_EQ(s.info.state.frames_mapped, 6);
  EXPECT_EQ(s.info.mapper.keyframe_every, 2);
  EXPECT_EQ(s.info.global.merge_distance_m, 0.3);
  EXPECT_EQ(s.info.camera.width, 64);
}

// The same session in format 1 (before the mapper state): format 2's with the MSTA section cut
// out, the version and the section count set back, the header resealed.
std::string asFormat1(const std::string& current) {
  const std::string v2 = asFormat2(current);
  const std::size_t parm = 24, msta = parm + 16 + u64At(v2, parm + 4), after = msta + 16 + u64At(v2, msta + 4);
  EXPECT_EQ(v2.substr(msta, 4), "MSTA");
  std::string v1 = v2.substr(0, msta) + v2.substr(after);
  putU32(&v1, 8, 1);
  std::uint32_t sections = 0;
  for (int i = 0; i < 4; ++i) sections |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(v2[16 + i])) << (8 * i);
  putU32(&v1, 16, sections - 1);
  resealHeader(&v1);
  return v1;
}

// Old files still load (docs/vdmap-format.md): a format-1 session reads with its keyframes and
// counts, cannot continue mapping (it never stored the current keyframe), and re-saves in the
// current format, which stays non-continuable rather than guessing.
TEST(SessionFile, Format1FilesLoadAndCannotContinue) {
  const Saved& s = smallSession();
  const Session old = decodeSession(asFormat1(s.bytes), "old.vdmap");
  EXPECT_EQ(old.info.format_version, 1u);
  EXPECT_EQ(old.graph.size(), s.mapper.graph().size());
  EXPECT_EQ(old.info.state.frames_mapped, 10);
  EXPECT_EQ(old.info.state.current_keyframe, -1);
  Mapper mapper(old.info.camera, old.info.mapper, old.graph, old.info.state);
  EXPECT_FALSE(mapper.canContinue());
  try {
    mapper.addFrame(test::turningBoxRoomFrame(old.info.camera, 10, 6.0));
    ADD_FAILURE() << "mapped on without a current keyframe";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cannot continue"), std::string::npos) << e.what();
  }
  const Session resaved = decodeSession(encodeSession(old.graph, old.info), "resaved.vdmap");
  EXPECT_EQ(resaved.info.format_version, kSessionFormatVersion);
  EXPECT_EQ(resaved.info.state.current_keyframe, -1);
  EXPECT_EQ(encodeSession(resaved.graph, resaved.info), encodeSession(old.graph, old.info));
}

// A saved session continues mapping where it stopped. Frames 0:70 in one run and
// 0:35 then 35:70 from the saved session give the same keyframes, graph, local maps and state,
// byte for byte, so the same global map (the walk revisits its start past frame 60).
TEST(SessionFile, ASavedSessionContinuesAsIfItHadNotStopped) {
  const PinholeCamera camera{160, 120, 131.25, 131.25, 79.5, 59.5, 5000.0};
  Mapper whole(camera);
  Mapper first(camera);
  for (int i = 0; i < 70; ++i) whole.addFrame(test::turningBoxRoomFrame(camera, i, 6.0));
  for (int i = 0; i < 35; ++i) first.addFrame(test::turningBoxRoomFrame(camera, i, 6.0));
  ASSERT_GT(whole.revisits(), 0);
  const Session saved = decodeSession(encodeSession(first.graph(), sessionInfo(first, {})), "half.vdmap");
  EXPECT_EQ(saved.info.state.current_keyframe, first.currentKeyframe());
  EXPECT_EQ(saved.info.state.last_frame_index, 34);
  Mapper rest(saved.info.camera, saved.info.mapper, saved.graph, saved.info.state);
  ASSERT_TRUE(rest.canContinue());
  for (int i = 35; i < 70; ++i) rest.addFrame(test::turningBoxRoomFrame(camera, i, 6.0));
  EXPECT_EQ(rest.revisits(), whole.revisits());
  EXPECT_EQ(encodeSession(rest.graph(), sessionInfo(rest, {})), encodeSession(whole.graph(), sessionInfo(whole, {})));
  const GlobalMap a = buildGlobalMap(whole.graph(), {}), b = buildGlobalMap(rest.graph(), {});
  ASSERT_EQ(a.ellipsoids.size(), b.ellipsoids.size());
  for (std::size_t i = 0; i < a.ellipsoids.size(); ++i) {
    ASSERT_EQ(a.ellipsoids[i].mean, b.ellipsoids[i].mean);
    ASSERT_EQ(a.ellipsoids[i].cov, b.ellipsoids[i].cov);
  }
}

// A damaged state section is one clear error, like every other field.
TEST(SessionFile, AStateThatDoesNotFitTheGraphIsRejected) {
  const Saved& s = smallSession();
  SessionInfo info = s.info;
  const int keyframes = static_cast<int>(s.mapper.graph().size());
  info.state.current_keyframe = keyframes;  // one past the last
  EXPECT_THROW(encodeSession(s.mapper.graph(), info), std::invalid_argument) << "the writer refuses it too";
  info.state.current_keyframe = 0;
  info.sequence = "/data/seq";
  const std::string bytes = encodeSession(s.mapper.graph(), info);
  EXPECT_EQ(decodeSession(bytes, "s.vdmap").info.sequence, "/data/seq");
  std::string bad = bytes;
  const std::size_t msta = bad.find("MSTA");
  ASSERT_NE(msta, std::string::npos);
  putU32(&bad, msta + 16, 7 + keyframes);  // the current keyframe, first in the payload
  const std::uint64_t length = u64At(bad, msta + 4);
  putU32(&bad, msta + 12,
         crc32(std::string_view(bad).substr(msta + 16, length), crc32(std::string_view(bad).substr(msta, 12))));
  const std::string expected = "section 1 'MSTA': mapper state: current keyframe " + std::to_string(7 + keyframes) +
                               " is not one of the " + std::to_string(keyframes) + " keyframes";
  EXPECT_NE(decodeError(bad).find(expected), std::string::npos) << decodeError(bad);
}

// vdmap map --load continues a saved session on the sequence, byte-identical to one
// run over all the frames; a run on frames the session has mapped, other mapping parameters or a
// format-1 session are clear errors.
TEST(SessionFile, MapVerbContinuesASavedSession) {
  TempDir dir;
  test::writeBoxRoomSequence(dir / "seq", 70);
  const std::string seq = "map '" + (dir / "seq").string() + "'";
  const auto out = [&](const char* name) { return " --out '" + (dir / name).string() + "'"; };
  const auto file = [&](const char* name) { return "'" + (dir / name).string() + "'"; };
  ASSERT_EQ(test::runVdmap(seq + out("whole") + " --save " + file("whole.vdmap")).exit_code, 0);
  ASSERT_EQ(test::runVdmap(seq + " --frames 0:35" + out("a") + " --save " + file("a.vdmap")).exit_code, 0);
  const test::RunResult r =
      test::runVdmap(seq + " --load " + file("a.vdmap") + out("b") + " --save " + file("b.vdmap"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readFile(dir / "b.vdmap"), readFile(dir / "whole.vdmap"));
  EXPECT_EQ(readFile(dir / "b" / "global_ellipsoids.ply"), readFile(dir / "whole" / "global_ellipsoids.ply"));
  EXPECT_NE(r.out.find("70 frames"), std::string::npos) << r.out;

  const test::RunResult overlap = test::runVdmap(seq + " --load " + file("a.vdmap") + " --frames 30:70" + out("c"));
  EXPECT_EQ(overlap.exit_code, 1);
  EXPECT_NE(overlap.err.find("has mapped frames up to 34; continue from 35"), std::string::npos) << overlap.err;
  const test::RunResult params = test::runVdmap(seq + " --load " + file("a.vdmap") + " --cell-size 7" + out("c"));
  EXPECT_EQ(params.exit_code, 1);
  EXPECT_NE(params.err.find("the mapping parameters are the session's"), std::string::npos) << params.err;
  test::writeText(dir / "old.vdmap", asFormat1(readFile(dir / "a.vdmap")));
  const test::RunResult old = test::runVdmap(seq + " --load " + file("old.vdmap") + out("c"));
  EXPECT_EQ(old.exit_code, 1);
  EXPECT_NE(old.err.find("does not store the mapper's state"), std::string::npos) << old.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "c"));
}

// Tracked runs save the same session byte for byte, run after run and whatever the thread count:
// the session stores what was computed, never how long it took (the loop closures'
// optimisation times stay in stats.json).
TEST(SessionFile, TrackedRunsSaveTheSameBytesWhateverTheThreadCount) {
  TempDir dir;
  test::writeBoxRoomSequence(dir / "seq", 70);
  const auto run = [&](const std::string& name, int threads) {
    const test::RunResult r =
        test::runVdmap("map '" + (dir / "seq").string() + "' --poses track --threads " + std::to_string(threads) +
                       " --out '" + (dir / name).string() + "' --save '" + (dir / (name + ".vdmap")).string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return readFile(dir / (name + ".vdmap"));
  };
  const std::string first = run("a", 1);
  ASSERT_FALSE(first.empty());
  ASSERT_GE(decodeSession(first, "a.vdmap").info.state.loops.size(), 1u) << "the walk closes a loop (timed)";
  EXPECT_EQ(run("b", 1), first);
  EXPECT_EQ(run("c", 2), first);
}

// The PARM section is read and written from the parameter table: its bytes are still those
// docs/vdmap-format.md lays out, field by field, and every value comes back.
TEST(SessionFile, ParmSectionIsTheDocumentedLayout) {
  SessionInfo info;
  info.camera = smallSession().info.camera;
  MapperParams& m = info.mapper;
  m.local_map = {7, {0.25, 6.5}};
  m.features.orb_features = 900;
  m.keyframes.tau = 0.3;
  m.keyframes.tau_edge = 0.15;
  m.keyframes.prefilter = {false, 2.5, 75.0};
  m.keyframes.min_frame_features = 11;
  m.keyframes.covisibility = {50, 0.7, 6.0};
  m.keyframe_every = 4;
  m.poses = PoseSource::kTrack;
  GlobalMapParams& g = info.global;
  g.filter = {SensorModel::kBelter2018, 2.5, 9};
  g.tau_group = 0.2;
  g.merge_distance_m = 0.3;
  g.occlusion_removal = false;
  g.occlusion_distance_m = 0.75;
  g.occlusion_angle_deg = 40;
  g.fuse_across_groups = false;
  g.fusion_max_distance = 2.0;

  std::string expected;
  const auto little = [&expected](auto v, int bytes) {
    std::uint64_t u = 0;
    if constexpr (std::is_same_v<decltype(v), double>) u = std::bit_cast<std::uint64_t>(v);
    else u = static_cast<std::uint64_t>(v);
    for (int i = 0; i < bytes; ++i) expected.push_back(static_cast<char>(u >> (8 * i)));
  };
  const auto i32 = [&](int v) { little(static_cast<std::uint32_t>(v), 4); };
  const auto f64 = [&](double v) { little(v, 8); };
  const auto boolean = [&](bool v) { little(v ? 1 : 0, 1); };
  const PinholeCamera& c = info.camera;
  i32(c.width), i32(c.height), f64(c.fx), f64(c.fy), f64(c.cx), f64(c.cy), f64(c.depth_scale);
  i32(7), f64(0.25), f64(6.5), i32(900), f64(0.3), f64(0.15), boolean(false), f64(2.5), f64(75.0), i32(11), i32(50),
      f64(0.7), f64(6.0), i32(4), i32(1);
  i32(1), f64(2.5), i32(9), f64(0.2), f64(0.3), boolean(false), f64(0.75), f64(40), boolean(false), f64(2.0);
  i32(0), i32(0), i32(0);  // frames mapped, revisits, keyframes

  const std::string bytes = encodeSession(KeyframeGraph{}, info);
  ASSERT_EQ(bytes.substr(24, 4), "PARM");
  EXPECT_EQ(bytes.substr(24 + 16, u64At(bytes, 24 + 4)), expected);
  const Session loaded = decodeSession(bytes, "parm.vdmap");
  EXPECT_TRUE(sameMapperParams(loaded.info.mapper, m));
  EXPECT_TRUE((ParameterValues{loaded.info.mapper, loaded.info.global} == ParameterValues{m, g}));
  EXPECT_EQ(loaded.info.mapper.poses, PoseSource::kTrack);
}

}  // namespace
}  // namespace vdmap
