// The MCAP reader (mapping/ros/mcap_file.h) on files a tiny writer here builds (chunks uncompressed,
// lz4 and zstd; with and without a summary; cut short, damaged), on the real ROS 2 recording in
// ../shared/data/bags, and the ROS 2 CDR decoders (mapping/ros/detail/decoders.h) against a tiny
// CDR writer.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "mapping/core/error.h"
#include "mapping/ros/detail/decoders.h"
#include "mapping/ros/mcap_file.h"
#include "tests/support/test_util.h"

namespace vdmap::ros {
namespace mcap_test {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

// ---------------------------------------------------------------------------------------------
// A tiny MCAP writer (spec https://mcap.dev/spec), enough for the reader's paths.

void putU16(Bytes* out, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) out->push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void putU32(Bytes* out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void putU64(Bytes* out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out->push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void putString(Bytes* out, const std::string& s) {
  putU32(out, static_cast<std::uint32_t>(s.size()));
  out->insert(out->end(), s.begin(), s.end());
}
void putRecord(Bytes* out, std::uint8_t opcode, const Bytes& content) {
  out->push_back(opcode);
  putU64(out, content.size());
  out->insert(out->end(), content.begin(), content.end());
}
std::uint32_t crcOf(const Bytes& bytes, std::size_t begin, std::size_t end) {
  return static_cast<std::uint32_t>(::crc32_z(0, bytes.data() + begin, end - begin));
}

struct TestMessage {
  std::uint16_t channel = 1;
  std::uint64_t log_time_ns = 0;
  Bytes data;
};

struct TestChannel {
  std::uint16_t id;
  std::uint16_t schema_id;
  std::string topic, encoding;
};

struct TestSchema {
  std::uint16_t id;
  std::string name;
};

const std::vector<TestSchema> kTestSchemas = {{1, "sensor_msgs/msg/Image"}, {2, "tf2_msgs/msg/TFMessage"}, {3, "foo"}};
const std::vector<TestChannel> kTestChannels = {
    {1, 1, "/camera/depth", "cdr"}, {2, 2, "/tf", "cdr"}, {3, 3, "/telemetry", "json"}};

struct WriterOptions {
  std::string compression;  ///< "", "lz4", "zstd" or anything (written as is, uncompressed)
  bool chunked = true;      ///< false: messages are records of the data section
  bool summary = true;      ///< summary section (schemas, channels, statistics, chunk indexes)
  bool crcs = true;         ///< chunk, data section and summary CRCs (0 when false)
  std::vector<TestSchema> schemas = kTestSchemas;
  std::vector<TestChannel> channels = kTestChannels;
};

Bytes compress(const Bytes& raw, const std::string& compression) {
  if (compression == "zstd") {
    Bytes out(ZSTD_compressBound(raw.size()));
    out.resize(ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), 3));
    return out;
  }
  if (compression == "lz4") {
    Bytes out(LZ4F_compressFrameBound(raw.size(), nullptr));
    out.resize(LZ4F_compressFrame(out.data(), out.size(), raw.data(), raw.size(), nullptr));
    return out;
  }
  return raw;
}

Bytes schemaRecord(const TestSchema& schema) {
  Bytes c;
  putU16(&c, schema.id);
  putString(&c, schema.name);
  putString(&c, "ros2msg");
  putString(&c, "# text");
  return c;
}

Bytes channelRecord(const TestChannel& channel) {
  Bytes c;
  putU16(&c, channel.id);
  putU16(&c, channel.schema_id);
  putString(&c, channel.topic);
  putString(&c, channel.encoding);
  Bytes metadata;
  putString(&metadata, "offered_qos_profiles");
  putString(&metadata, "");
  putU32(&c, static_cast<std::uint32_t>(metadata.size()));
  c.insert(c.end(), metadata.begin(), metadata.end());
  return c;
}

Bytes messageRecord(const TestMessage& message) {
  Bytes c;
  putU16(&c, message.channel);
  putU32(&c, 0);  // sequence
  putU64(&c, message.log_time_ns);
  putU64(&c, message.log_time_ns);
  c.insert(c.end(), message.data.begin(), message.data.end());
  return c;
}

/// An MCAP file of `chunks` (each a list of messages in file order); schemas and channels are
/// written in the first chunk (or before the first message when not chunked).
Bytes writeTestMcap(const std::vector<std::vector<TestMessage>>& chunks, const WriterOptions& options = {}) {
  Bytes file = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
  Bytes header;
  putString(&header, "ros2");
  putString(&header, "vdmap test writer");
  putRecord(&file, 0x01, header);

  struct IndexEntry {
    std::uint64_t start, end, offset, length, message_index_length, compressed, uncompressed;
    std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  };
  std::vector<IndexEntry> chunk_indexes;
  std::map<std::uint16_t, std::uint64_t> counts;
  std::uint64_t message_count = 0, first = ~0ull, last = 0;
  bool defined = false;
  for (const auto& messages : chunks) {
    Bytes records;
    if (!defined) {
      for (const auto& schema : options.schemas) putRecord(&records, 0x03, schemaRecord(schema));
      for (const auto& channel : options.channels) putRecord(&records, 0x04, channelRecord(channel));
      defined = true;
    }
    std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> index;
    std::uint64_t start = ~0ull, end = 0;
    for (const auto& message : messages) {
      index[message.channel].emplace_back(message.log_time_ns, records.size());
      putRecord(&records, 0x05, messageRecord(message));
      start = std::min(start, message.log_time_ns);
      end = std::max(end, message.log_time_ns);
      ++counts[message.channel];
      ++message_count;
    }
    if (messages.empty()) start = end = 0;
    first = std::min(first, start);
    last = std::max(last, end);
    if (!options.chunked) {
      file.insert(file.end(), records.begin(), records.end());
      continue;
    }
    const Bytes compressed = compress(records, options.compression);
    Bytes chunk;
    putU64(&chunk, start);
    putU64(&chunk, end);
    putU64(&chunk, records.size());
    putU32(&chunk, options.crcs ? crcOf(records, 0, records.size()) : 0);
    putString(&chunk, options.compression);
    putU64(&chunk, compressed.size());
    chunk.insert(chunk.end(), compressed.begin(), compressed.end());
    IndexEntry entry{start, end, file.size(), 9 + chunk.size(), 0, compressed.size(), records.size(), {}};
    putRecord(&file, 0x06, chunk);
    const std::size_t index_start = file.size();
    for (const auto& [channel, entries] : index) {
      entry.message_index_offsets[channel] = file.size();
      Bytes c;
      putU16(&c, channel);
      putU32(&c, static_cast<std::uint32_t>(entries.size() * 16));
      for (const auto& [time, offset] : entries) {
        putU64(&c, time);
        putU64(&c, offset);
      }
      putRecord(&file, 0x07, c);
    }
    entry.message_index_length = file.size() - index_start;
    chunk_indexes.push_back(entry);
  }
  Bytes data_end;
  putU32(&data_end, options.crcs ? crcOf(file, 0, file.size()) : 0);
  putRecord(&file, 0x0F, data_end);

  std::uint64_t summary_start = 0;
  if (options.summary) {
    summary_start = file.size();
    for (const auto& schema : options.schemas) putRecord(&file, 0x03, schemaRecord(schema));
    for (const auto& channel : options.channels) putRecord(&file, 0x04, channelRecord(channel));
    Bytes statistics;
    putU64(&statistics, message_count);
    putU16(&statistics, static_cast<std::uint16_t>(options.schemas.size()));
    putU32(&statistics, static_cast<std::uint32_t>(options.channels.size()));
    putU32(&statistics, 0);
    putU32(&statistics, 0);
    putU32(&statistics, static_cast<std::uint32_t>(chunk_indexes.size()));
    putU64(&statistics, message_count ? first : 0);
    putU64(&statistics, last);
    putU32(&statistics, static_cast<std::uint32_t>(counts.size() * 10));
    for (const auto& [channel, count] : counts) {
      putU16(&statistics, channel);
      putU64(&statistics, count);
    }
    putRecord(&file, 0x0B, statistics);
    for (const auto& entry : chunk_indexes) {
      Bytes c;
      putU64(&c, entry.start);
      putU64(&c, entry.end);
      putU64(&c, entry.offset);
      putU64(&c, entry.length);
      putU32(&c, static_cast<std::uint32_t>(entry.message_index_offsets.size() * 10));
      for (const auto& [channel, offset] : entry.message_index_offsets) {
        putU16(&c, channel);
        putU64(&c, offset);
      }
      putU64(&c, entry.message_index_length);
      putString(&c, options.compression);
      putU64(&c, entry.compressed);
      putU64(&c, entry.uncompressed);
      putRecord(&file, 0x08, c);
    }
  }
  Bytes content;
  putU64(&content, summary_start);
  putU64(&content, 0);  // no summary offset section
  file.push_back(0x02);
  putU64(&file, 20);
  file.insert(file.end(), content.begin(), content.end());
  const std::uint32_t summary_crc = options.summary && options.crcs ? crcOf(file, summary_start, file.size()) : 0;
  putU32(&file, summary_crc);
  file.insert(file.end(), {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'});
  return file;
}

fs::path writeBytes(const fs::path& file, const Bytes& bytes) {
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return file;
}

Bytes payload(int i, std::size_t size = 40) {
  Bytes data(size);
  for (std::size_t k = 0; k < size; ++k) data[k] = static_cast<std::uint8_t>(i * 31 + k);
  return data;
}

/// Three chunks, 0.1 s apart, one depth message and one tf message each 33 ms, plus telemetry.
std::vector<std::vector<TestMessage>> threeChunks() {
  std::vector<std::vector<TestMessage>> chunks(3);
  int i = 0;
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 4; ++k, ++i) {
      const std::uint64_t t = 1'600'000'000'000'000'000ull + static_cast<std::uint64_t>(i) * 33'000'000ull;
      chunks[c].push_back({1, t, payload(i, 200)});
      chunks[c].push_back({2, t + 1'000'000, payload(100 + i, 60)});
      if (k == 2) chunks[c].push_back({3, t, payload(200 + i, 10)});
    }
  return chunks;
}

struct Visited {
  int topic;
  std::int64_t log_time_ns;
  Bytes bytes;
  MessageRef ref;
  bool operator==(const Visited& o) const {
    return topic == o.topic && log_time_ns == o.log_time_ns && bytes == o.bytes;
  }
};

std::vector<int> allTopics(const Recording& recording) {
  std::vector<int> topics(recording.topics().size());
  for (std::size_t i = 0; i < topics.size(); ++i) topics[i] = static_cast<int>(i);
  return topics;
}

std::vector<Visited> scanAll(const Recording& recording, ScanEnd* end = nullptr, std::vector<int> topics = {}) {
  if (topics.empty()) topics = allTopics(recording);
  std::vector<Visited> visited;
  const ScanEnd result = recording.scan(topics, [&](const Message& m) {
    visited.push_back({m.topic, m.log_time_ns, *m.bytes, m.ref});
    return true;
  });
  if (end) *end = result;
  return visited;
}

/// The messages of `chunks` as a scan must give them: sorted by log time, ties in file order.
std::vector<std::pair<std::uint64_t, Bytes>> expectedOrder(const std::vector<std::vector<TestMessage>>& chunks) {
  std::vector<std::pair<std::uint64_t, Bytes>> all;
  for (const auto& chunk : chunks)
    for (const auto& m : chunk) all.emplace_back(m.log_time_ns, m.data);
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return all;
}

int topicIndex(const Recording& recording, const std::string& name) {
  for (std::size_t i = 0; i < recording.topics().size(); ++i)
    if (recording.topics()[i].name == name) return static_cast<int>(i);
  return -1;
}

// ---------------------------------------------------------------------------------------------
// MCAP files built here

class McapCompression : public ::testing::TestWithParam<std::string> {};

TEST_P(McapCompression, SummaryAndLinearReadingGiveTheSameMessagesInLogTimeOrder) {
  test::TempDir tmp;
  const auto chunks = threeChunks();
  WriterOptions options;
  options.compression = GetParam();
  const fs::path indexed = writeBytes(tmp / "indexed.mcap", writeTestMcap(chunks, options));
  options.summary = false;
  const fs::path plain = writeBytes(tmp / "plain.mcap", writeTestMcap(chunks, options));

  const auto a = McapFile::open(indexed);
  const auto b = McapFile::open(plain);
  const std::string kind = GetParam().empty() ? "uncompressed" : GetParam();
  EXPECT_EQ(a->describe(), "MCAP (profile ros2, " + kind + " chunks, with summary)");
  EXPECT_EQ(b->describe(), "MCAP (profile ros2, " + kind + " chunks, no summary: read linearly)");
  ASSERT_EQ(a->topics().size(), 3u);
  ASSERT_EQ(b->topics().size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(a->topics()[i].name, b->topics()[i].name);
    EXPECT_EQ(a->topics()[i].type, b->topics()[i].type);
    EXPECT_EQ(a->topics()[i].kind, b->topics()[i].kind);
    EXPECT_EQ(a->topics()[i].count, b->topics()[i].count);
  }
  const int depth = topicIndex(*a, "/camera/depth"), tf = topicIndex(*a, "/tf"), other = topicIndex(*a, "/telemetry");
  ASSERT_GE(depth, 0);
  ASSERT_GE(tf, 0);
  ASSERT_GE(other, 0);
  EXPECT_EQ(a->topics()[depth].type, "sensor_msgs/msg/Image");
  EXPECT_EQ(a->topics()[depth].kind, MessageType::kImage);
  EXPECT_EQ(a->topics()[depth].count, 12u);
  EXPECT_EQ(a->topics()[tf].kind, MessageType::kTfMessage);
  EXPECT_EQ(a->topics()[other].kind, MessageType::kOther);  // json: not an encoding vdmap decodes
  EXPECT_EQ(a->topics()[other].count, 3u);

  ScanEnd end_a, end_b;
  const auto from_a = scanAll(*a, &end_a);
  const auto from_b = scanAll(*b, &end_b);
  EXPECT_TRUE(end_a.complete) << end_a.damage;
  EXPECT_TRUE(end_b.complete) << end_b.damage;
  EXPECT_EQ(from_a, from_b);
  const auto expected = expectedOrder(chunks);
  ASSERT_EQ(from_a.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(static_cast<std::uint64_t>(from_a[i].log_time_ns), expected[i].first) << i;
    EXPECT_EQ(from_a[i].bytes, expected[i].second) << i;
  }
  // Each message again by its ref, backwards (no cache help) and in order.
  for (auto it = from_a.rbegin(); it != from_a.rend(); ++it) {
    const Message m = a->read(it->ref);
    EXPECT_EQ(m.topic, it->topic);
    EXPECT_EQ(m.log_time_ns, it->log_time_ns);
    EXPECT_EQ(*m.bytes, it->bytes);
    EXPECT_EQ(m.encoding, Encoding::kCdr);
  }
  for (const auto& v : from_b) EXPECT_EQ(*b->read(v.ref).bytes, v.bytes);
}

INSTANTIATE_TEST_SUITE_P(McapFile, McapCompression, ::testing::Values("", "lz4", "zstd"),
                         [](const auto& info) { return info.param.empty() ? std::string("none") : info.param; });

TEST(McapFile, TopicsGetAKindOnlyInEncodingsVdmapDecodes) {
  test::TempDir tmp;
  WriterOptions options;
  options.schemas = {{1, "sensor_msgs/msg/Image"}, {2, "sensor_msgs/Image"}, {3, "tf/tfMessage"}};
  // Two publishers on one topic (channels 1 and 4) make one Topic.
  options.channels = {{1, 1, "/depth", "cdr"}, {2, 2, "/depth_ros1", "ros1"}, {3, 3, "/tf", "ros1"},
                      {4, 1, "/depth", "cdr"}, {5, 1, "/depth_json", "json"}, {6, 7, "/no_schema", "cdr"}};
  const std::vector<std::vector<TestMessage>> chunks = {
      {{1, 10, payload(1)}, {2, 11, payload(2)}, {3, 12, payload(3)}, {4, 13, payload(4)}, {5, 14, payload(5)}}};
  const auto mcap = McapFile::open(writeBytes(tmp / "kinds.mcap", writeTestMcap(chunks, options)));
  const auto& topics = mcap->topics();
  ASSERT_EQ(topics.size(), 5u);
  const auto topic = [&](const std::string& name) { return topics[static_cast<std::size_t>(topicIndex(*mcap, name))]; };
  EXPECT_EQ(topic("/depth").kind, MessageType::kImage);
  EXPECT_EQ(topic("/depth").count, 2u);
  EXPECT_EQ(topic("/depth_ros1").kind, MessageType::kImage);
  EXPECT_EQ(topic("/depth_ros1").type, "sensor_msgs/Image");
  EXPECT_EQ(topic("/tf").kind, MessageType::kTfMessage);
  EXPECT_EQ(topic("/depth_json").kind, MessageType::kOther);
  EXPECT_EQ(topic("/no_schema").kind, MessageType::kOther);
  EXPECT_EQ(topic("/no_schema").type, "");
  std::map<std::string, Encoding> encodings;
  mcap->scan(allTopics(*mcap), [&](const Message& m) {
    encodings[topics[static_cast<std::size_t>(m.topic)].name] = m.encoding;
    return true;
  });
  EXPECT_EQ(encodings.size(), 4u);
  EXPECT_EQ(encodings["/depth"], Encoding::kCdr);
  EXPECT_EQ(encodings["/depth_ros1"], Encoding::kRos1);
  EXPECT_EQ(encodings["/tf"], Encoding::kRos1);
}

TEST(McapFile, ScansAndReadsFromSeveralThreadsAgree) {
  test::TempDir tmp;
  const auto mcap = McapFile::open(writeBytes(tmp / "a.mcap", writeTestMcap(threeChunks(), {"zstd"})));
  const auto expected = scanAll(*mcap);
  std::vector<std::vector<Visited>> scanned(4);
  std::vector<int> reads_equal(4, 0);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      scanned[t] = scanAll(*mcap);
      for (std::size_t i = t; i < expected.size(); i += 4)
        reads_equal[t] += *mcap->read(expected[i].ref).bytes == expected[i].bytes;
    });
  for (auto& thread : threads) thread.join();
  for (std::size_t t = 0; t < 4; ++t) {
    EXPECT_EQ(scanned[t], expected);
    EXPECT_EQ(static_cast<std::size_t>(reads_equal[t]), (expected.size() - t + 3) / 4);
  }
}

TEST(McapFile, ScanVisitsOnlyTheChosenTopicsAndStopsWhenAsked) {
  test::TempDir tmp;
  const auto file = McapFile::open(writeBytes(tmp / "a.mcap", writeTestMcap(threeChunks(), {"zstd"})));
  const int tf = topicIndex(*file, "/tf");
  const auto visited = scanAll(*file, nullptr, {tf});
  ASSERT_EQ(visited.size(), 12u);
  for (const auto& v : visited) EXPECT_EQ(v.topic, tf);
  int seen = 0;
  const ScanEnd end = file->scan({tf}, [&](const Message&) { return ++seen < 5; });
  EXPECT_EQ(seen, 5);
  EXPECT_TRUE(end.complete);
  EXPECT_TRUE(file->scan({}, [](const Message&) { return true; }).complete);
}

TEST(McapFile, OverlappingChunksMergeInLogTimeOrderWithTiesInFileOrder) {
  test::TempDir tmp;
  // Chunk A: 10 30 50 (and a second 30 later in the chunk); chunk B: 20 30 40 60; chunk C: 5.
  const std::vector<std::vector<TestMessage>> chunks = {
      {{1, 10, payload(1)}, {1, 30, payload(2)}, {2, 50, payload(3)}, {2, 30, payload(4)}},
      {{2, 20, payload(5)}, {1, 30, payload(6)}, {1, 40, payload(7)}, {1, 60, payload(8)}},
      {{1, 5, payload(9)}}};
  for (const bool summary : {true, false}) {
    WriterOptions options;
    options.summary = summary;
    const auto file = McapFile::open(writeBytes(tmp / "overlap.mcap", writeTestMcap(chunks, options)));
    ScanEnd end;
    const auto visited = scanAll(*file, &end);
    EXPECT_TRUE(end.complete) << end.damage;
    const auto expected = expectedOrder(chunks);
    ASSERT_EQ(visited.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(static_cast<std::uint64_t>(visited[i].log_time_ns), expected[i].first) << i;
      EXPECT_EQ(visited[i].bytes, expected[i].second) << "summary " << summary << " message " << i;
    }
  }
}

TEST(McapFile, MessagesOutsideChunksAreReadLinearly) {
  test::TempDir tmp;
  const auto chunks = threeChunks();
  WriterOptions options;
  options.chunked = false;
  const auto file = McapFile::open(writeBytes(tmp / "loose.mcap", writeTestMcap(chunks, options)));
  EXPECT_EQ(file->describe(), "MCAP (profile ros2, no chunks, summary without chunk indexes: read linearly)");
  ScanEnd end;
  const auto visited = scanAll(*file, &end);
  EXPECT_TRUE(end.complete) << end.damage;
  const auto expected = expectedOrder(chunks);
  ASSERT_EQ(visited.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(visited[i].bytes, expected[i].second) << i;
  for (const auto& v : visited) {
    EXPECT_EQ(v.ref.offset, 0u);
    EXPECT_EQ(*file->read(v.ref).bytes, v.bytes);
  }
}

TEST(McapFile, CutShortVisitsTheMessagesBeforeTheCutAndSaysWhere) {
  test::TempDir tmp;
  const auto chunks = threeChunks();
  const Bytes whole = writeTestMcap(chunks, {"zstd"});
  const auto expected = expectedOrder(chunks);
  std::uint64_t summary_start = 0;  // from the footer: where the data end record ends
  for (int i = 7; i >= 0; --i) summary_start = (summary_start << 8) | whole[whole.size() - 8 - 20 + i];
  // Every cut from inside the header to just before the end: never a crash; a prefix of the
  // messages, then damage (or InputError when not even the header is left).
  int opened = 0;
  for (std::size_t cut = 0; cut < whole.size(); cut += 7) {
    const fs::path file = writeBytes(tmp / "cut.mcap", Bytes(whole.begin(), whole.begin() + cut));
    std::unique_ptr<McapFile> mcap;
    try {
      mcap = McapFile::open(file);
    } catch (const InputError& e) {
      EXPECT_LT(cut, 46u) << e.what();  // magic and header
      continue;
    }
    ++opened;
    ScanEnd end;
    const auto visited = scanAll(*mcap, &end);
    ASSERT_LE(visited.size(), expected.size());
    if (end.complete) {
      // Cut in the summary, after the data end record: the summary is lost, no message is.
      EXPECT_EQ(visited.size(), expected.size()) << "cut at " << cut;
      EXPECT_GE(cut, summary_start);
    } else {
      EXPECT_LT(cut, summary_start);
      EXPECT_NE(end.damage.find(file.string() + ": truncated at byte "), std::string::npos) << end.damage;
      EXPECT_EQ(end.damage.find('\n'), std::string::npos);
    }
    for (std::size_t i = 0; i < visited.size(); ++i) EXPECT_EQ(visited[i].bytes, expected[i].second);
  }
  EXPECT_GT(opened, 10);

  // Cut inside the third chunk: the first two chunks' messages, then where the file ends.
  test::TempDir whole_dir;
  const auto refs = scanAll(*McapFile::open(writeBytes(whole_dir / "whole.mcap", whole)));
  const std::size_t cut = refs.back().ref.position + 50;
  const fs::path file =
      writeBytes(tmp / "cut.mcap", Bytes(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(cut)));
  const auto mcap = McapFile::open(file);
  ScanEnd end;
  const auto visited = scanAll(*mcap, &end);
  EXPECT_EQ(visited.size(), 18u);  // two chunks of 4 depth, 4 tf and 1 telemetry messages
  EXPECT_FALSE(end.complete);
  EXPECT_NE(end.damage.find("truncated at byte " + std::to_string(cut) + " in a chunk"), std::string::npos)
      << end.damage;
  EXPECT_NE(end.damage.find("; messages after 0.232 s are lost"), std::string::npos) << end.damage;
  EXPECT_NE(mcap->describe().find("no footer"), std::string::npos) << mcap->describe();
}

TEST(McapFile, AFlippedByteInAChunkFailsItsCrc) {
  test::TempDir tmp;
  const auto chunks = threeChunks();
  for (const bool summary : {true, false}) {
    WriterOptions options;
    options.summary = summary;
    Bytes bytes = writeTestMcap(chunks, options);
    const auto visited = scanAll(*McapFile::open(writeBytes(tmp / "good.mcap", bytes)));
    // A byte of the 11th message (in the second chunk) inside the chunk's records.
    const MessageRef ref = visited[10].ref;
    bytes[ref.position + 9 + 8 + 8 + 8 + 4 + 4 + 8 + ref.offset + 9 + 22 + 3] ^= 0x10;
    const fs::path file = writeBytes(tmp / "flipped.mcap", bytes);
    const auto mcap = McapFile::open(file);
    ScanEnd end;
    const auto partial = scanAll(*mcap, &end);
    EXPECT_EQ(partial.size(), 9u) << "summary " << summary;  // the first chunk's
    EXPECT_FALSE(end.complete);
    EXPECT_EQ(end.damage, file.string() + ": chunk at byte " + std::to_string(ref.position) +
                              " fails its CRC check (its bytes are damaged); messages " +
                              (summary ? "from 0.132 s on are lost" : "after 0.100 s are lost"));
    EXPECT_THROW(mcap->read(ref), InputError);
  }
}

TEST(McapFile, ARecordRunningPastItsChunkLosesTheWholeChunk) {
  test::TempDir tmp;
  const auto chunks = threeChunks();
  for (const bool summary : {true, false}) {
    WriterOptions options;
    options.summary = summary;
    options.crcs = false;  // so the structure, not a CRC, is what fails
    Bytes bytes = writeTestMcap(chunks, options);
    const auto visited = scanAll(*McapFile::open(writeBytes(tmp / "good.mcap", bytes)));
    // The top byte of the length of the second chunk's last message record.
    const MessageRef ref = visited[17].ref;
    ASSERT_EQ(ref.position, visited[9].ref.position);
    const std::size_t records = ref.position + 9 + 8 + 8 + 8 + 4 + 4 + 8;
    ASSERT_EQ(bytes[records + ref.offset], 0x05);
    bytes[records + ref.offset + 1 + 7] = 0x01;
    const fs::path file = writeBytes(tmp / "damaged.mcap", bytes);
    const auto mcap = McapFile::open(file);
    ScanEnd end;
    EXPECT_EQ(scanAll(*mcap, &end).size(), 9u);
    EXPECT_EQ(end.damage, file.string() + ": chunk at byte " + std::to_string(ref.position) +
                              " holds a message record that runs past its end; messages " +
                              (summary ? "from 0.132 s on are lost" : "after 0.100 s are lost"));
    // Reading linearly stops at the damage: only the first chunk's messages are counted.
    EXPECT_EQ(mcap->topics()[0].count, summary ? 12u : 4u);
  }
}

TEST(McapFile, WithoutCrcsADamagedByteIsNotNoticed) {
  test::TempDir tmp;
  WriterOptions options;
  options.crcs = false;
  Bytes bytes = writeTestMcap(threeChunks(), options);
  const auto good = scanAll(*McapFile::open(writeBytes(tmp / "good.mcap", bytes)));
  bytes[good[0].ref.position + 9 + 8 + 8 + 8 + 4 + 4 + 8 + good[0].ref.offset + 9 + 22] ^= 0x01;
  ScanEnd end;
  const auto visited = scanAll(*McapFile::open(writeBytes(tmp / "flipped.mcap", bytes)), &end);
  EXPECT_TRUE(end.complete);
  ASSERT_EQ(visited.size(), good.size());
  EXPECT_NE(visited[0].bytes, good[0].bytes);
}

TEST(McapFile, DamageOutsideChunksFailsTheDataSectionCrcWhenReadLinearly) {
  test::TempDir tmp;
  WriterOptions options;
  options.summary = false;
  Bytes bytes = writeTestMcap(threeChunks(), options);
  const auto good = scanAll(*McapFile::open(writeBytes(tmp / "good.mcap", bytes)));
  // A message index record follows the first chunk: damage its last time stamp's top byte.
  std::size_t chunk_end = good[0].ref.position + 9;
  std::uint64_t chunk_length = 0;
  for (int i = 7; i >= 0; --i) chunk_length = (chunk_length << 8) | bytes[good[0].ref.position + 1 + i];
  chunk_end += chunk_length;
  ASSERT_EQ(bytes[chunk_end], 0x07);
  bytes[chunk_end + 9 + 2 + 4 + 7] ^= 0x40;
  const fs::path file = writeBytes(tmp / "damaged.mcap", bytes);
  ScanEnd end;
  const auto visited = scanAll(*McapFile::open(file), &end);
  EXPECT_EQ(visited, good);
  EXPECT_FALSE(end.complete);
  EXPECT_EQ(end.damage, file.string() +
                            ": the data section fails its CRC check (a byte outside the chunks is damaged); messages "
                            "after 0.364 s are lost");
}

TEST(McapFile, ADamagedSummaryFallsBackToReadingLinearly) {
  test::TempDir tmp;
  Bytes bytes = writeTestMcap(threeChunks(), {"lz4"});
  const auto good = scanAll(*McapFile::open(writeBytes(tmp / "good.mcap", bytes)));
  bytes[bytes.size() - 8 - 29 - 20] ^= 0x01;  // in the last chunk index
  const auto mcap = McapFile::open(writeBytes(tmp / "damaged.mcap", bytes));
  EXPECT_EQ(mcap->describe(), "MCAP (profile ros2, lz4 chunks, summary fails its CRC check: read linearly)");
  ScanEnd end;
  EXPECT_EQ(scanAll(*mcap, &end), good);
  EXPECT_TRUE(end.complete) << end.damage;
  EXPECT_EQ(mcap->topics()[0].count, 12u);
}

TEST(McapFile, UnknownCompressionIsNamed) {
  test::TempDir tmp;
  const auto chunks = threeChunks();
  for (const bool summary : {true, false}) {
    WriterOptions options;
    options.compression = "brotli";
    options.summary = summary;
    const fs::path file = writeBytes(tmp / "brotli.mcap", writeTestMcap(chunks, options));
    const auto mcap = McapFile::open(file);
    ScanEnd end;
    EXPECT_TRUE(scanAll(*mcap, &end).empty());
    EXPECT_FALSE(end.complete);
    EXPECT_NE(
        end.damage.find(file.string() + ": chunk at byte 46 is compressed with 'brotli', which vdmap cannot read"),
        std::string::npos)
        << end.damage;
  }
}

TEST(McapFile, NotMcapIsAnInputError) {
  test::TempDir tmp;
  const auto expectInputError = [&](const Bytes& bytes, const std::string& what) {
    const fs::path file = writeBytes(tmp / "x.mcap", bytes);
    try {
      McapFile::open(file);
      ADD_FAILURE() << "no error for " << what;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).find(file.string() + ": "), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expectInputError({}, "not an MCAP file");
  expectInputError({'#', 'R', 'O', 'S', 'B', 'A', 'G', ' ', 'V', '2', '.', '0', '\n'},
                   "not an MCAP file (it starts with '#ROSBAG ', not MCAP's magic)");
  const Bytes whole = writeTestMcap(threeChunks());
  expectInputError(Bytes(whole.begin(), whole.begin() + 8), "without a header record");
  Bytes bad_header = whole;
  bad_header[8 + 9] = 0xFF;  // the profile's length
  bad_header[8 + 9 + 3] = 0x7F;
  expectInputError(bad_header, "unreadable MCAP header");
  EXPECT_THROW(McapFile::open(tmp / "missing.mcap"), InputError);
  EXPECT_THROW(McapFile::open(tmp.path()), InputError);
}

TEST(McapFile, AnEmptyRecordingHasNoMessages) {
  test::TempDir tmp;
  const auto mcap = McapFile::open(writeBytes(tmp / "empty.mcap", writeTestMcap({})));
  EXPECT_EQ(mcap->describe(), "MCAP (profile ros2, no chunks, with summary)");
  ASSERT_EQ(mcap->topics().size(), 3u);  // the summary lists the channels, without messages
  EXPECT_EQ(mcap->topics()[0].count, 0u);
  ScanEnd end;
  EXPECT_TRUE(scanAll(*mcap, &end).empty());
  EXPECT_TRUE(end.complete);
}

TEST(McapFile, ABadRefIsAnInputError) {
  test::TempDir tmp;
  const auto mcap = McapFile::open(writeBytes(tmp / "a.mcap", writeTestMcap(threeChunks(), {"zstd"})));
  const auto visited = scanAll(*mcap);
  EXPECT_THROW(mcap->read(MessageRef{0, 0}), InputError);
  EXPECT_THROW(mcap->read(MessageRef{1u << 30, 0}), InputError);
  EXPECT_THROW(mcap->read(MessageRef{visited[0].ref.position, visited[0].ref.offset + 1}), InputError);
  EXPECT_THROW(mcap->read(MessageRef{visited[0].ref.position, ~0ull}), InputError);
  EXPECT_EQ(*mcap->read(visited[3].ref).bytes, visited[3].bytes);
}

TEST(McapFile, HostileSizesAreDamageNotAllocations) {
  test::TempDir tmp;
  WriterOptions options;
  options.compression = "zstd";
  options.summary = false;
  Bytes bytes = writeTestMcap(threeChunks(), options);
  const auto visited = scanAll(*McapFile::open(writeBytes(tmp / "good.mcap", bytes)));
  // The second chunk claims 400 GB uncompressed.
  const std::size_t uncompressed = visited[9].ref.position + 9 + 16;
  ASSERT_EQ(bytes[visited[9].ref.position], 0x06);
  bytes[uncompressed + 5] = 0x60;
  const fs::path file = writeBytes(tmp / "huge.mcap", bytes);
  ScanEnd end;
  EXPECT_EQ(scanAll(*McapFile::open(file), &end).size(), 9u);
  EXPECT_NE(end.damage.find("more than vdmap reads in one chunk"), std::string::npos) << end.damage;
}

// ---------------------------------------------------------------------------------------------
// The real recording

TEST(McapFile, ReadsTheRealSenseLayoutRecording) {
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  const fs::path path = bags / "7scenes-redkitchen-realsense-layout.mcap";
  if (!fs::exists(path)) GTEST_SKIP() << path << " not found (real-data test skipped)";
  const auto mcap = McapFile::open(path);
  EXPECT_EQ(mcap->describe(), "MCAP (profile ros2, zstd chunks, with summary)");
  const int color = topicIndex(*mcap, "/camera/color/image_raw/compressed");
  const int depth = topicIndex(*mcap, "/camera/aligned_depth_to_color/image_raw");
  const int info = topicIndex(*mcap, "/camera/color/camera_info");
  const int tf = topicIndex(*mcap, "/tf");
  const int tf_static = topicIndex(*mcap, "/tf_static");
  ASSERT_EQ(mcap->topics().size(), 5u);
  ASSERT_TRUE(color >= 0 && depth >= 0 && info >= 0 && tf >= 0 && tf_static >= 0);
  const auto& topics = mcap->topics();
  EXPECT_EQ(topics[depth].type, "sensor_msgs/msg/Image");
  EXPECT_EQ(topics[depth].kind, MessageType::kImage);
  EXPECT_EQ(topics[color].type, "sensor_msgs/msg/CompressedImage");
  EXPECT_EQ(topics[color].kind, MessageType::kCompressedImage);
  EXPECT_EQ(topics[info].kind, MessageType::kCameraInfo);
  EXPECT_EQ(topics[tf].kind, MessageType::kTfMessage);
  EXPECT_EQ(topics[tf_static].kind, MessageType::kTfMessage);
  EXPECT_EQ(topics[depth].count, 30u);
  EXPECT_EQ(topics[color].count, 30u);
  EXPECT_EQ(topics[tf].count, 30u);
  EXPECT_EQ(topics[info].count, 30u);
  EXPECT_EQ(topics[tf_static].count, 1u);

  std::map<int, int> seen;
  std::int64_t last_ns = 0;
  std::vector<Message> kept;
  const ScanEnd end = mcap->scan(allTopics(*mcap), [&](const Message& m) {
    EXPECT_GE(m.log_time_ns, last_ns);
    last_ns = m.log_time_ns;
    EXPECT_EQ(m.encoding, Encoding::kCdr);
    const int n = seen[m.topic]++;
    if (m.topic == depth) {
      const Image image = detail::decodeImageCdr(*m.bytes);
      EXPECT_EQ(image.encoding, "16UC1");
      EXPECT_EQ(image.width, 640u);
      EXPECT_EQ(image.height, 480u);
      EXPECT_EQ(image.step, 1280u);
      EXPECT_EQ(image.data.size(), 640u * 480u * 2u);
      EXPECT_NEAR(image.header.stamp, static_cast<double>(m.log_time_ns) * 1e-9, 1e-3);
      EXPECT_FALSE(image.header.frame_id.empty());
      if (n == 0 || n == 29) kept.push_back(m);
    } else if (m.topic == color) {
      const CompressedImage image = detail::decodeCompressedImageCdr(*m.bytes);
      EXPECT_EQ(image.format, "rgb8; jpeg compressed bgr8");
      EXPECT_TRUE(image.data.size() > 2 && image.data[0] == 0xFF && image.data[1] == 0xD8);  // a JPEG
      if (n == 7) kept.push_back(m);
    } else if (m.topic == info) {
      const CameraInfo camera = detail::decodeCameraInfoCdr(*m.bytes);
      EXPECT_EQ(camera.width, 640u);
      EXPECT_EQ(camera.height, 480u);
      EXPECT_NEAR(camera.k[0], 585.0, 1e-9);
      EXPECT_NEAR(camera.k[2], 320.0, 1e-9);
    } else if (m.topic == tf) {
      const auto transforms = detail::decodeTransformsCdr(*m.bytes, MessageType::kTfMessage);
      EXPECT_EQ(transforms.size(), 1u);
      for (const auto& t : transforms) {
        EXPECT_EQ(t.header.frame_id, "world");
        EXPECT_EQ(t.child_frame_id, "camera_link");
        EXPECT_NEAR(t.rotation.norm(), 1.0, 1e-6);
      }
      if (n == 3) kept.push_back(m);
    } else if (m.topic == tf_static) {
      const auto transforms = detail::decodeTransformsCdr(*m.bytes, MessageType::kTfMessage);
      EXPECT_EQ(transforms.size(), 1u);
      if (transforms.empty()) return false;
      EXPECT_EQ(transforms[0].header.frame_id, "camera_link");
      EXPECT_EQ(transforms[0].child_frame_id, "camera_color_optical_frame");
      EXPECT_NEAR(transforms[0].rotation.x(), -0.5, 1e-12);
      EXPECT_NEAR(transforms[0].rotation.y(), 0.5, 1e-12);
      EXPECT_NEAR(transforms[0].rotation.z(), -0.5, 1e-12);
      EXPECT_NEAR(transforms[0].rotation.w(), 0.5, 1e-12);
      kept.push_back(m);
    }
    return true;
  });
  EXPECT_TRUE(end.complete) << end.damage;
  for (const auto& [topic, n] : seen)
    EXPECT_EQ(static_cast<std::uint64_t>(n), topics[topic].count) << topics[topic].name;
  for (const Message& m : kept) {
    const Message again = mcap->read(m.ref);
    EXPECT_EQ(again.topic, m.topic);
    EXPECT_EQ(again.log_time_ns, m.log_time_ns);
    EXPECT_EQ(*again.bytes, *m.bytes);
  }
}

// ---------------------------------------------------------------------------------------------
// CDR

/// Writes CDR as rmw does: encapsulation header, then fields aligned to their size from its end.
class CdrWriter {
 public:
  explicit CdrWriter(bool big_endian = false) : big_endian_(big_endian) {
    bytes_ = {0x00, static_cast<std::uint8_t>(big_endian ? 0x00 : 0x01), 0x00, 0x00};
  }
  CdrWriter& u8(std::uint8_t v) { return put(v, 1); }
  CdrWriter& u32(std::uint32_t v) { return put(v, 4); }
  CdrWriter& i32(std::int32_t v) { return put(static_cast<std::uint32_t>(v), 4); }
  CdrWriter& f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    return put(bits, 4);
  }
  CdrWriter& f64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    return put(bits, 8);
  }
  CdrWriter& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
    return *this;
  }
  CdrWriter& header(std::int32_t sec, std::uint32_t nanosec, const std::string& frame) {
    return i32(sec).u32(nanosec).str(frame);
  }
  CdrWriter& blob(const Bytes& data) {
    u32(static_cast<std::uint32_t>(data.size()));
    bytes_.insert(bytes_.end(), data.begin(), data.end());
    return *this;
  }
  const Bytes& bytes() const { return bytes_; }

 private:
  CdrWriter& put(std::uint64_t v, std::size_t size) {
    while ((bytes_.size() - 4) % size != 0) bytes_.push_back(0);
    for (std::size_t i = 0; i < size; ++i)
      bytes_.push_back(static_cast<std::uint8_t>(v >> (8 * (big_endian_ ? size - 1 - i : i))));
    return *this;
  }
  bool big_endian_;
  Bytes bytes_;
};

/// Every proper prefix of `bytes` throws std::runtime_error (and reads nothing past it: run
/// under ASan to see).
template <typename Decode>
void expectEveryPrefixThrows(const Bytes& bytes, Decode decode) {
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    const Bytes prefix(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_THROW(decode(prefix), std::runtime_error) << "prefix of " << n << " of " << bytes.size() << " bytes";
  }
}

Bytes cdrImage(bool big_endian) {
  return CdrWriter(big_endian)
      .header(1600000000, 500000000, "camera_depth_optical_frame")
      .u32(2)
      .u32(3)
      .str("16UC1")
      .u8(0)
      .u32(6)
      .blob({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12})
      .bytes();
}

TEST(CdrMessages, ImageRoundTripsInBothByteOrders) {
  for (const bool big_endian : {false, true}) {
    const Bytes bytes = cdrImage(big_endian);
    const Image image = detail::decodeImageCdr(bytes);
    EXPECT_DOUBLE_EQ(image.header.stamp, 1600000000.5);
    EXPECT_EQ(image.header.frame_id, "camera_depth_optical_frame");
    EXPECT_EQ(image.height, 2u);
    EXPECT_EQ(image.width, 3u);
    EXPECT_EQ(image.encoding, "16UC1");
    EXPECT_FALSE(image.is_bigendian);
    EXPECT_EQ(image.step, 6u);
    EXPECT_EQ(Bytes(image.data.begin(), image.data.end()), Bytes({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}));
    expectEveryPrefixThrows(cdrImage(big_endian), [](const Bytes& b) { detail::decodeImageCdr(b); });
  }
}

TEST(CdrMessages, ImageDataShorterThanHeightTimesStepThrows) {
  const Bytes bytes =
      CdrWriter().header(1, 0, "f").u32(480).u32(640).str("16UC1").u8(0).u32(1280).blob({1, 2, 3}).bytes();
  try {
    detail::decodeImageCdr(bytes);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "image data holds 3 bytes, height * step needs 614400");
  }
}

TEST(CdrMessages, CompressedImageRoundTrips) {
  const Bytes bytes =
      CdrWriter().header(-2, 7, "color").str("rgb8; jpeg compressed bgr8").blob({0xFF, 0xD8, 0xFF}).bytes();
  const CompressedImage image = detail::decodeCompressedImageCdr(bytes);
  EXPECT_DOUBLE_EQ(image.header.stamp, -2.0 + 7e-9);
  EXPECT_EQ(image.header.frame_id, "color");
  EXPECT_EQ(image.format, "rgb8; jpeg compressed bgr8");
  EXPECT_EQ(Bytes(image.data.begin(), image.data.end()), Bytes({0xFF, 0xD8, 0xFF}));
  expectEveryPrefixThrows(bytes, [](const Bytes& b) { detail::decodeCompressedImageCdr(b); });
}

TEST(CdrMessages, CameraInfoRoundTrips) {
  CdrWriter w;
  w.header(10, 20, "cam").u32(480).u32(640).str("plumb_bob").u32(5);
  for (int i = 0; i < 5; ++i) w.f64(0.1 * i);
  for (int i = 0; i < 9; ++i) w.f64(100 + i);
  for (int i = 0; i < 9; ++i) w.f64(200 + i);
  for (int i = 0; i < 12; ++i) w.f64(300 + i);
  w.u32(1).u32(1).u32(0).u32(0).u32(0).u32(0).u8(0);
  const CameraInfo info = detail::decodeCameraInfoCdr(w.bytes());
  EXPECT_EQ(info.header.frame_id, "cam");
  EXPECT_EQ(info.height, 480u);
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  ASSERT_EQ(info.d.size(), 5u);
  EXPECT_DOUBLE_EQ(info.d[4], 0.4);
  EXPECT_DOUBLE_EQ(info.k[8], 108);
  EXPECT_DOUBLE_EQ(info.r[0], 200);
  EXPECT_DOUBLE_EQ(info.p[11], 311);
  expectEveryPrefixThrows(w.bytes(), [](const Bytes& b) { detail::decodeCameraInfoCdr(b); });
}

CdrWriter& transformFields(CdrWriter& w, double base) {
  for (int i = 0; i < 7; ++i) w.f64(base + i);
  return w;
}

TEST(CdrMessages, TransformsRoundTrip) {
  for (const bool big_endian : {false, true}) {
    CdrWriter tf(big_endian);
    tf.u32(2);
    transformFields(tf.header(5, 0, "world").str("camera_link"), 1);
    transformFields(tf.header(6, 0, "camera_link").str("camera_color_optical_frame"), 11);
    const auto transforms = detail::decodeTransformsCdr(tf.bytes(), MessageType::kTfMessage);
    ASSERT_EQ(transforms.size(), 2u);
    EXPECT_EQ(transforms[0].header.frame_id, "world");
    EXPECT_EQ(transforms[0].child_frame_id, "camera_link");
    EXPECT_EQ(transforms[0].translation, Eigen::Vector3d(1, 2, 3));
    EXPECT_EQ(transforms[0].rotation.coeffs(), Eigen::Vector4d(4, 5, 6, 7));  // x y z w
    EXPECT_DOUBLE_EQ(transforms[1].header.stamp, 6.0);
    EXPECT_EQ(transforms[1].child_frame_id, "camera_color_optical_frame");
    EXPECT_EQ(transforms[1].translation, Eigen::Vector3d(11, 12, 13));
    expectEveryPrefixThrows(tf.bytes(),
                            [](const Bytes& b) { detail::decodeTransformsCdr(b, MessageType::kTfMessage); });
  }
  CdrWriter stamped;
  transformFields(stamped.header(1, 2, "a").str("b"), 0.5);
  const auto one = detail::decodeTransformsCdr(stamped.bytes(), MessageType::kTransformStamped);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].child_frame_id, "b");
  EXPECT_EQ(one[0].rotation.w(), 6.5);
  expectEveryPrefixThrows(stamped.bytes(),
                          [](const Bytes& b) { detail::decodeTransformsCdr(b, MessageType::kTransformStamped); });
  CdrWriter bare;
  transformFields(bare, 0);
  const auto plain = detail::decodeTransformsCdr(bare.bytes(), MessageType::kTransform);
  ASSERT_EQ(plain.size(), 1u);
  EXPECT_TRUE(plain[0].header.frame_id.empty());
  EXPECT_EQ(plain[0].translation, Eigen::Vector3d(0, 1, 2));
  EXPECT_EQ(plain[0].rotation.w(), 6);
  expectEveryPrefixThrows(bare.bytes(),
                          [](const Bytes& b) { detail::decodeTransformsCdr(b, MessageType::kTransform); });
  EXPECT_THROW(detail::decodeTransformsCdr(bare.bytes(), MessageType::kImage), std::runtime_error);
}

TEST(CdrMessages, PoseStampedAndOdometryRoundTrip) {
  CdrWriter pose;
  transformFields(pose.header(3, 0, "map"), 1);
  const PoseStamped p = detail::decodePoseCdr(pose.bytes(), MessageType::kPoseStamped);
  EXPECT_EQ(p.header.frame_id, "map");
  EXPECT_EQ(p.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.orientation.coeffs(), Eigen::Vector4d(4, 5, 6, 7));
  expectEveryPrefixThrows(pose.bytes(), [](const Bytes& b) { detail::decodePoseCdr(b, MessageType::kPoseStamped); });

  CdrWriter odometry;
  transformFields(odometry.header(4, 0, "odom").str("base_link"), 10);
  for (int i = 0; i < 36 + 6 + 36; ++i) odometry.f64(i);
  const PoseStamped o = detail::decodePoseCdr(odometry.bytes(), MessageType::kOdometry);
  EXPECT_EQ(o.header.frame_id, "odom");
  EXPECT_EQ(o.child_frame_id, "base_link");
  EXPECT_EQ(o.position, Eigen::Vector3d(10, 11, 12));
  EXPECT_EQ(o.orientation.w(), 16);
  expectEveryPrefixThrows(odometry.bytes(), [](const Bytes& b) { detail::decodePoseCdr(b, MessageType::kOdometry); });
  EXPECT_THROW(detail::decodePoseCdr(pose.bytes(), MessageType::kFloat32), std::runtime_error);
}

TEST(CdrMessages, Float32RoundTrips) {
  const Bytes bytes = CdrWriter().f32(0.001f).bytes();
  EXPECT_EQ(detail::decodeFloat32Cdr(bytes), 0.001f);
  EXPECT_EQ(detail::decodeFloat32Cdr(CdrWriter(true).f32(-2.5f).bytes()), -2.5f);
  expectEveryPrefixThrows(bytes, [](const Bytes& b) { detail::decodeFloat32Cdr(b); });
}

TEST(CdrMessages, RefusesOtherEncapsulationsAndHugeCounts) {
  Bytes xcdr2 = CdrWriter().f32(1.0f).bytes();
  xcdr2[1] = 0x07;
  try {
    detail::decodeFloat32Cdr(xcdr2);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "CDR encapsulation 0x0007 is not plain CDR (0x0000 big or 0x0001 little endian)");
  }
  // A TFMessage declaring four billion transforms in 8 bytes: an error, not an allocation.
  const Bytes huge = CdrWriter().u32(0xFFFFFFFFu).u32(0).bytes();
  EXPECT_THROW(detail::decodeTransformsCdr(huge, MessageType::kTfMessage), std::runtime_error);
  const Bytes huge_data = CdrWriter().header(0, 0, "").str("").u32(0xFFFFFFF0u).bytes();
  try {
    detail::decodeCompressedImageCdr(huge_data);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("message ends inside field 'data'"), std::string::npos) << e.what();
  }
}

}  // namespace mcap_test
}  // namespace vdmap::ros
