// The .vdmap session file: round trip (byte-identical re-save, identical global map), every way a
// file can be damaged gives one InputError naming what is wrong, and a writer killed at random
// moments always leaves a file that loads.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "mapping/core/error.h"
#include "mapping/io/session_file.h"
#include "tests/test_util.h"

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
  EXPECT_EQ(loaded.info.frames_mapped, 66);
  EXPECT_EQ(loaded.info.revisits, s.mapper.revisits());
  ASSERT_EQ(loaded.graph.size(), graph.size());
  for (std::size_t i = 0; i < graph.size(); ++i) {
    const Keyframe &a = graph.keyframes()[i], &b = loaded.graph.keyframes()[i];
    EXPECT_EQ(a.T_W_K.matrix(), b.T_W_K.matrix());
    EXPECT_EQ(a.timestamp, b.timestamp);
    EXPECT_EQ(cv::norm(a.rgb, b.rgb, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.depth, b.depth, cv::NORM_INF), 0.0);
    ASSERT_EQ(a.features.size(), b.features.size());
    EXPECT_EQ(cv::norm(a.features.descriptors, b.features.descriptors, cv::NORM_INF), 0.0);
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

TEST(SessionFile, EmptySessionRoundTrips) {
  const SessionInfo info;
  const std::string bytes = encodeSession(KeyframeGraph{}, info);
  const Session loaded = decodeSession(bytes, "empty.vdmap");
  EXPECT_EQ(loaded.graph.size(), 0u);
  EXPECT_EQ(encodeSession(loaded.graph, loaded.info), bytes);
}

TEST(SessionFile, DamagedHeadersNameWhatIsWrong) {
  const std::string& good = smallSession().bytes;
  EXPECT_NE(decodeError("").find("wrong magic"), std::string::npos);
  EXPECT_NE(decodeError("solid\n" + good).find("wrong magic"), std::string::npos);
  EXPECT_NE(decodeError(good.substr(0, 12)).find("truncated"), std::string::npos);

  std::string newer = good;
  putU32(&newer, 8, kSessionFormatVersion + 1);
  resealHeader(&newer);
  EXPECT_NE(decodeError(newer).find("format version " + std::to_string(kSessionFormatVersion + 1) + " is newer than this vdmap reads (" + std::to_string(kSessionFormatVersion) + ")"), std::string::npos)
      << decodeError(newer);

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
  graph.add(Keyframe{0, 0, 0.0, Transform::Identity(), {}, {}, {}, KeyframeContainer(s.info.camera, 5), 0});
  graph.edges().strengthen(0, 3, 0.5);  // keyframe 3 does not exist
  EXPECT_NE(decodeError(encodeSession(graph, s.info)).find("edge 0-3 does not join two of the 1 keyframes"),
            std::string::npos)
      << decodeError(encodeSession(graph, s.info));

  SessionInfo bad_params = s.info;
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
    std::this_thread::sleep_for(std::chrono::microseconds(std::uniform_int_distribution<long>(0, 2 * two_saves_us)(rng)));
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
  EXPECT_EQ(s.info.frames_mapped, 6);
  EXPECT_EQ(s.info.mapper.keyframe_every, 2);
  EXPECT_EQ(s.info.global.merge_distance_m, 0.3);
  EXPECT_EQ(s.info.camera.width, 64);
}

}  // namespace
}  // namespace vdmap
