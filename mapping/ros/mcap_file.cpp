#include "mapping/ros/mcap_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <queue>
#include <set>
#include <stdexcept>
#include <string_view>
#include <tuple>
#include <unordered_map>

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "mapping/core/error.h"

namespace vdmap::ros {

namespace detail {

/// Decompressed chunk records, or a run of records outside chunks read as they are. `data`
/// points into `storage`.
struct McapBuffer {
  std::shared_ptr<const std::uint8_t[]> storage;
  const std::uint8_t* data = nullptr;
  std::uint64_t size = 0;
};

/// A piece of the data section a scan reads as one: a chunk record, or a run of records outside
/// chunks (loose messages; runs are cut at about 4 MiB so a scan never holds more).
struct McapBlock {
  std::uint64_t offset = 0;  ///< file offset of the chunk record / of the run's first record
  std::uint64_t length = 0;  ///< bytes: the whole chunk record / the whole run
  bool is_chunk = true;
  std::uint64_t start_ns = 0, end_ns = 0;  ///< log times of its earliest and latest message
  std::vector<std::uint16_t> channels;     ///< channel ids it holds messages of; empty: unknown
};

/// What opening learned: fixed afterwards, so scans and reads share it without locks.
struct McapIndex {
  std::string profile;
  std::string how_read;  ///< "with summary", "no summary: read linearly", ...
  std::set<std::string> compressions;
  std::vector<Topic> topics;
  std::vector<Encoding> topic_encodings;                 ///< per topic
  std::unordered_map<std::uint16_t, int> channel_topic;  ///< channel id -> index into topics
  std::vector<McapBlock> blocks;                         ///< sorted by (start_ns, offset)
  std::uint64_t first_ns = 0;                            ///< earliest log time: damage times are given from it
  /// Damage the linear reading at open() found: every scan that reaches the end reports it.
  std::string damage;
  bool damage_has_time = false;
  std::uint64_t damage_after_ns = 0;  ///< latest log time read before the damage
};

}  // namespace detail

// A named namespace: the target is compiled in unity batches (CMakeLists.txt), where these
// file-scope names must not meet another reader's (the ROS 1 bag reader's, say).
namespace mcap_reader {
namespace {

using detail::McapBlock;
using detail::McapBuffer;
using detail::McapIndex;

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

// Record opcodes (spec "Records").
enum Opcode : std::uint8_t {
  kOpHeader = 0x01,
  kOpFooter = 0x02,
  kOpSchema = 0x03,
  kOpChannel = 0x04,
  kOpMessage = 0x05,
  kOpChunk = 0x06,
  kOpMessageIndex = 0x07,
  kOpChunkIndex = 0x08,
  kOpAttachment = 0x09,
  kOpAttachmentIndex = 0x0A,
  kOpStatistics = 0x0B,
  kOpMetadata = 0x0C,
  kOpMetadataIndex = 0x0D,
  kOpSummaryOffset = 0x0E,
  kOpDataEnd = 0x0F,
};

constexpr std::uint64_t kPrefixBytes = 9;                      // opcode + uint64 content length
constexpr std::uint64_t kFooterBytes = kPrefixBytes + 20 + 8;  // footer record + trailing magic
constexpr std::uint64_t kMessageHeaderBytes = 22;              // channel id, sequence, log and publish time
// The header holds two short strings; more than this is not a header.
constexpr std::uint64_t kMaxHeaderBytes = 1 << 20;
// Summaries take a few hundred bytes per chunk; past this the file is read linearly instead.
constexpr std::uint64_t kMaxSummaryBytes = std::uint64_t{256} << 20;
// Runs of records outside chunks are cut into blocks of about this size.
constexpr std::uint64_t kLooseRunBytes = std::uint64_t{4} << 20;
// Records the linear reading skips are still read (for the data section's CRC), in pieces.
constexpr std::uint64_t kSkipPieceBytes = std::uint64_t{1} << 20;
// Ratios no real compressor exceeds: lz4 writes at most ~255 bytes per input byte, zstd at most
// 128 KiB per 4-byte RLE block. A declared size above them is damage, and not allocated.
constexpr std::uint64_t kMaxLz4Ratio = 256;
constexpr std::uint64_t kMaxZstdRatio = 32768;
constexpr std::uint64_t kRatioSlackBytes = 1 << 16;

/// The bytes do not hold what they should: the text says where and what, without the file name.
class Malformed : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::uint64_t little(const std::uint8_t* at, int bytes) {
  std::uint64_t value = 0;
  for (int i = bytes - 1; i >= 0; --i) value = (value << 8) | at[i];
  return value;
}
std::uint64_t littleU64(const std::uint8_t* at) { return little(at, 8); }
std::uint32_t littleU32(const std::uint8_t* at) { return static_cast<std::uint32_t>(little(at, 4)); }

/// Bounds-checked little-endian reading of one record's fields.
class Fields {
 public:
  Fields(const std::uint8_t* data, std::uint64_t size, const char* record)
      : data_(data), size_(size), record_(record) {}

  std::uint64_t remaining() const { return size_ - pos_; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(little(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(little(4)); }
  std::uint64_t u64() { return little(8); }
  std::string string() {
    const std::uint32_t length = u32();
    return std::string(reinterpret_cast<const char*>(take(length)), length);
  }
  /// The next `n` bytes, as a pointer into the record.
  const std::uint8_t* take(std::uint64_t n) {
    if (n > remaining()) throw Malformed(std::string(record_) + " record ends inside its fields");
    const std::uint8_t* at = data_ + pos_;
    pos_ += n;
    return at;
  }
  /// A uint32-length-prefixed field (a map, bytes), as Fields of its own.
  Fields prefixed() {
    const std::uint32_t length = u32();
    return Fields(take(length), length, record_);
  }
  /// Map<uint16, uint64>: the keys in order.
  std::vector<std::pair<std::uint16_t, std::uint64_t>> mapU16U64() {
    Fields map = prefixed();
    std::vector<std::pair<std::uint16_t, std::uint64_t>> entries;
    while (map.remaining() > 0) {
      const std::uint16_t key = map.u16();
      entries.emplace_back(key, map.u64());
    }
    return entries;
  }

 private:
  std::uint64_t little(int bytes) { return mcap_reader::little(take(static_cast<std::uint64_t>(bytes)), bytes); }

  const std::uint8_t* data_;
  std::uint64_t size_;
  std::uint64_t pos_ = 0;
  const char* record_;
};

std::uint32_t crc32Of(std::uint32_t crc, const std::uint8_t* data, std::uint64_t size) {
  return static_cast<std::uint32_t>(::crc32_z(crc, data, static_cast<z_size_t>(size)));
}

std::string recordName(std::uint8_t opcode) {
  switch (opcode) {
    case kOpHeader: return "header";
    case kOpFooter: return "footer";
    case kOpSchema: return "schema";
    case kOpChannel: return "channel";
    case kOpMessage: return "message";
    case kOpChunk: return "chunk";
    case kOpMessageIndex: return "message index";
    case kOpChunkIndex: return "chunk index";
    case kOpAttachment: return "attachment";
    case kOpAttachmentIndex: return "attachment index";
    case kOpStatistics: return "statistics";
    case kOpMetadata: return "metadata";
    case kOpMetadataIndex: return "metadata index";
    case kOpSummaryOffset: return "summary offset";
    case kOpDataEnd: return "data end";
    default: return "opcode " + std::to_string(opcode);
  }
}

std::string at(std::uint64_t offset) { return "byte " + std::to_string(offset); }

/// Reads `size` bytes at `offset` with pread (no shared file position, so several threads may
/// read at once). False when the file ends first or the read fails.
bool readAt(int fd, std::uint64_t offset, void* out, std::uint64_t size) {
  auto* bytes = static_cast<std::uint8_t*>(out);
  while (size > 0) {
    const ssize_t got = ::pread(fd, bytes, static_cast<std::size_t>(std::min<std::uint64_t>(size, 1 << 30)),
                                static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    bytes += got;
    offset += static_cast<std::uint64_t>(got);
    size -= static_cast<std::uint64_t>(got);
  }
  return true;
}

struct SchemaInfo {
  std::string name;  ///< "sensor_msgs/msg/Image"
};

struct ChannelInfo {
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  ///< "cdr"
};

void parseSchema(const std::uint8_t* data, std::uint64_t size, std::map<std::uint16_t, SchemaInfo>* schemas) {
  Fields f(data, size, "schema");
  const std::uint16_t id = f.u16();
  SchemaInfo schema;
  schema.name = f.string();
  f.string();                                       // schema encoding ("ros2msg"): vdmap knows its types by name
  f.prefixed();                                     // the schema text
  if (id != 0) (*schemas)[id] = std::move(schema);  // id 0 is invalid (spec: readers ignore it)
}

void parseChannel(const std::uint8_t* data, std::uint64_t size, std::map<std::uint16_t, ChannelInfo>* channels) {
  Fields f(data, size, "channel");
  const std::uint16_t id = f.u16();
  ChannelInfo channel;
  channel.schema_id = f.u16();
  channel.topic = f.string();
  channel.message_encoding = f.string();
  f.prefixed();  // metadata (QoS profiles)
  (*channels)[id] = std::move(channel);
}

struct MessageHeader {
  std::uint16_t channel_id = 0;
  std::uint64_t log_time_ns = 0;
};

MessageHeader parseMessageHeader(const std::uint8_t* data, std::uint64_t size) {
  Fields f(data, size, "message");
  MessageHeader header;
  header.channel_id = f.u16();
  f.u32();  // sequence
  header.log_time_ns = f.u64();
  f.u64();  // publish time
  return header;
}

/// A chunk record's fields; `records` points into the record's bytes.
struct ChunkFields {
  std::uint64_t start_ns = 0, end_ns = 0;
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;
  std::string compression;
  const std::uint8_t* records = nullptr;
  std::uint64_t records_size = 0;
};

ChunkFields parseChunk(const std::uint8_t* data, std::uint64_t size) {
  Fields f(data, size, "chunk");
  ChunkFields chunk;
  chunk.start_ns = f.u64();
  chunk.end_ns = f.u64();
  chunk.uncompressed_size = f.u64();
  chunk.uncompressed_crc = f.u32();
  chunk.compression = f.string();
  chunk.records_size = f.u64();
  chunk.records = f.take(chunk.records_size);
  return chunk;
}

/// Calls visit(opcode, record offset in data, content, content size) for each record laid end to
/// end in `data` (a chunk's records, a run of loose records). Throws Malformed, naming `where`,
/// when a record runs past the end.
void forEachRecord(const std::uint8_t* data, std::uint64_t size, const std::string& where,
                   const std::function<void(std::uint8_t, std::uint64_t, const std::uint8_t*, std::uint64_t)>& visit) {
  std::uint64_t pos = 0;
  while (pos < size) {
    if (size - pos < kPrefixBytes) throw Malformed(where + " ends inside a record's opcode and length");
    const std::uint8_t opcode = data[pos];
    const std::uint64_t length = littleU64(data + pos + 1);
    if (length > size - pos - kPrefixBytes)
      throw Malformed(where + " holds a " + recordName(opcode) + " record that runs past its end");
    try {
      visit(opcode, pos, data + pos + kPrefixBytes, length);
    } catch (const Malformed& e) {
      throw Malformed(where + ": " + e.what());
    }
    pos += kPrefixBytes + length;
  }
}

std::shared_ptr<std::uint8_t[]> newBytes(std::uint64_t size) {
  return std::shared_ptr<std::uint8_t[]>(
      std::make_unique_for_overwrite<std::uint8_t[]>(static_cast<std::size_t>(size)));
}

void decompressZstd(const ChunkFields& chunk, std::uint8_t* out, const std::string& where) {
  const std::size_t got = ZSTD_decompress(out, static_cast<std::size_t>(chunk.uncompressed_size), chunk.records,
                                          static_cast<std::size_t>(chunk.records_size));
  if (ZSTD_isError(got)) throw Malformed(where + " does not decompress (zstd: " + ZSTD_getErrorName(got) + ")");
  if (got != chunk.uncompressed_size)
    throw Malformed(where + " decompresses to " + std::to_string(got) + " bytes, not the " +
                    std::to_string(chunk.uncompressed_size) + " it declares");
}

void decompressLz4(const ChunkFields& chunk, std::uint8_t* out, const std::string& where) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION)))
    throw Malformed(where + ": no lz4 decompression context");
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> owned(context,
                                                                                   &LZ4F_freeDecompressionContext);
  std::uint64_t in_pos = 0, out_pos = 0;
  while (in_pos < chunk.records_size) {
    std::size_t in_size = static_cast<std::size_t>(chunk.records_size - in_pos);
    std::size_t out_size = static_cast<std::size_t>(chunk.uncompressed_size - out_pos);
    const std::size_t hint =
        LZ4F_decompress(context, out + out_pos, &out_size, chunk.records + in_pos, &in_size, nullptr);
    if (LZ4F_isError(hint)) throw Malformed(where + " does not decompress (lz4: " + LZ4F_getErrorName(hint) + ")");
    in_pos += in_size;
    out_pos += out_size;
    // hint 0: a frame ended (another may follow). Otherwise the frame wants more input, and when
    // it took none and gave none, the output is full: more bytes than the chunk declares.
    if (hint != 0 && in_size == 0 && out_size == 0)
      throw Malformed(where + " decompresses to more than the " + std::to_string(chunk.uncompressed_size) +
                      " bytes it declares");
    if (hint != 0 && in_pos == chunk.records_size) throw Malformed(where + " ends inside an lz4 frame");
  }
  if (out_pos != chunk.uncompressed_size)
    throw Malformed(where + " decompresses to " + std::to_string(out_pos) + " bytes, not the " +
                    std::to_string(chunk.uncompressed_size) + " it declares");
}

/// A chunk record's content (`record`, `size` bytes, of the chunk at file offset `offset`)
/// decompressed and checked against its CRC. `fields_out` receives its fields.
std::shared_ptr<const McapBuffer> decodeChunk(std::uint64_t offset, std::shared_ptr<const std::uint8_t[]> record,
                                              std::uint64_t size, ChunkFields* fields_out = nullptr) {
  const std::string where = "chunk at " + at(offset);
  ChunkFields chunk;
  try {
    chunk = parseChunk(record.get(), size);
  } catch (const Malformed& e) {
    throw Malformed(where + ": " + e.what());
  }
  if (fields_out) *fields_out = chunk;
  if (chunk.uncompressed_size > McapFile::kMaxChunkBytes)
    throw Malformed(where + " declares " + std::to_string(chunk.uncompressed_size) +
                    " uncompressed bytes, more than vdmap reads in one chunk");
  auto buffer = std::make_shared<McapBuffer>();
  buffer->size = chunk.uncompressed_size;
  if (chunk.compression.empty()) {
    if (chunk.records_size != chunk.uncompressed_size)
      throw Malformed(where + " is uncompressed but holds " + std::to_string(chunk.records_size) + " bytes, not the " +
                      std::to_string(chunk.uncompressed_size) + " it declares");
    buffer->data = chunk.records;  // the records stay in the record's bytes
    buffer->storage = std::move(record);
  } else if (chunk.compression == "zstd" || chunk.compression == "lz4") {
    const bool zstd = chunk.compression == "zstd";
    const std::uint64_t most = chunk.records_size * (zstd ? kMaxZstdRatio : kMaxLz4Ratio) + kRatioSlackBytes;
    if (chunk.uncompressed_size > most)
      throw Malformed(where + " declares " + std::to_string(chunk.uncompressed_size) + " bytes from " +
                      std::to_string(chunk.records_size) + " compressed ones, more than " + chunk.compression +
                      " can give");
    std::shared_ptr<std::uint8_t[]> out = newBytes(chunk.uncompressed_size);
    if (zstd) {
      decompressZstd(chunk, out.get(), where);
    } else {
      decompressLz4(chunk, out.get(), where);
    }
    buffer->data = out.get();
    buffer->storage = std::move(out);
  } else {
    throw Malformed(where + " is compressed with " + printable(chunk.compression) + ", which vdmap cannot read");
  }
  if (chunk.uncompressed_crc != 0 && crc32Of(0, buffer->data, buffer->size) != chunk.uncompressed_crc)
    throw Malformed(where + " fails its CRC check (its bytes are damaged)");
  return buffer;
}

/// Reads records of one file by offset; every length is checked against the file's size before
/// anything is allocated.
class RecordReader {
 public:
  RecordReader(int fd, std::uint64_t size_bytes) : fd_(fd), size_bytes_(size_bytes) {}
  std::uint64_t size() const { return size_bytes_; }

  /// The opcode and content length of the record at `offset`.
  std::pair<std::uint8_t, std::uint64_t> prefixAt(std::uint64_t offset) const {
    std::uint8_t prefix[kPrefixBytes];
    if (offset > size_bytes_ || size_bytes_ - offset < kPrefixBytes)
      throw Malformed("truncated at " + at(size_bytes_) + " in a record's opcode and length");
    bytesInto(offset, prefix, kPrefixBytes);
    const std::uint64_t length = littleU64(prefix + 1);
    if (length > size_bytes_ - offset - kPrefixBytes)
      throw Malformed("truncated at " + at(size_bytes_) + " in a " + recordName(prefix[0]) + " (the record at " +
                      at(offset) + " declares " + std::to_string(length) + " bytes)");
    return {prefix[0], length};
  }

  /// `size` bytes at `offset`; callers checked that they lie in the file (prefixAt).
  std::shared_ptr<std::uint8_t[]> bytesAt(std::uint64_t offset, std::uint64_t size) const {
    std::shared_ptr<std::uint8_t[]> bytes = newBytes(size);
    bytesInto(offset, bytes.get(), size);
    return bytes;
  }

  void bytesInto(std::uint64_t offset, std::uint8_t* out, std::uint64_t size) const {
    if (!readAt(fd_, offset, out, size))
      throw Malformed("cannot read " + std::to_string(size) + " bytes at " + at(offset) +
                      " (a read failed or the file shrank)");
  }

  /// The content of the record at `offset` whose opcode and length prefixAt() gave; a record
  /// longer than kMaxChunkBytes is damage.
  std::shared_ptr<std::uint8_t[]> contentAt(std::uint64_t offset, std::uint8_t opcode, std::uint64_t length) const {
    if (length > McapFile::kMaxChunkBytes)
      throw Malformed("the " + recordName(opcode) + " record at " + at(offset) + " declares " + std::to_string(length) +
                      " bytes, more than vdmap reads in one record");
    return bytesAt(offset + kPrefixBytes, length);
  }

  /// The chunk record at `offset`, decompressed and checked.
  std::shared_ptr<const McapBuffer> chunkAt(std::uint64_t offset) const {
    const auto [opcode, length] = prefixAt(offset);
    if (opcode != kOpChunk) throw Malformed(at(offset) + " holds a " + recordName(opcode) + " record, not a chunk");
    return decodeChunk(offset, contentAt(offset, opcode, length), length);
  }

 private:
  int fd_;
  std::uint64_t size_bytes_;
};

/// Schemas, channels and counts, from the summary or from reading linearly.
struct Catalogue {
  std::map<std::uint16_t, SchemaInfo> schemas;
  std::map<std::uint16_t, ChannelInfo> channels;
  std::map<std::uint16_t, std::uint64_t> counts;  ///< messages per channel id
  std::set<std::string> compressions;
  std::vector<McapBlock> blocks;
  std::uint64_t first_ns = 0;  ///< statistics' message_start_time; 0: unknown
};

/// Reads the summary into `catalogue`. Returns "" when it is usable: present, passing its CRC,
/// and indexing every chunk (so a scan can go by the chunk indexes alone); otherwise why not.
std::string readSummary(const RecordReader& file, std::uint64_t data_start, Catalogue* catalogue) {
  const std::uint64_t size = file.size();
  if (size < data_start + kFooterBytes) return "no footer, cut short or still being written";
  std::uint8_t tail[kFooterBytes];
  const std::uint64_t footer = size - kFooterBytes;
  file.bytesInto(footer, tail, kFooterBytes);
  if (std::memcmp(tail + kFooterBytes - sizeof(kMagic), kMagic, sizeof(kMagic)) != 0)
    return "no footer, cut short or still being written";
  if (tail[0] != kOpFooter || littleU64(tail + 1) != 20) return "damaged footer";
  const std::uint64_t summary_start = littleU64(tail + 9);
  const std::uint64_t summary_offset_start = littleU64(tail + 17);
  const std::uint32_t summary_crc = littleU32(tail + 25);
  if (summary_start == 0) return "no summary";
  if (summary_start < data_start || summary_start > footer) return "damaged footer";
  if (summary_offset_start != 0 && (summary_offset_start < summary_start || summary_offset_start > footer))
    return "damaged footer";
  const std::uint64_t summary_end = summary_offset_start != 0 ? summary_offset_start : footer;
  // The CRC covers the summary and summary offset sections and the footer up to the CRC itself.
  const std::uint64_t crc_end = footer + kPrefixBytes + 16;
  if (crc_end - summary_start > kMaxSummaryBytes) return "summary too large";
  std::vector<std::uint8_t> summary(static_cast<std::size_t>(crc_end - summary_start));
  file.bytesInto(summary_start, summary.data(), summary.size());
  if (summary_crc != 0 && crc32Of(0, summary.data(), summary.size()) != summary_crc)
    return "summary fails its CRC check";

  bool have_statistics = false;
  std::uint64_t message_count = 0, chunk_count = 0;
  try {
    forEachRecord(summary.data(), summary_end - summary_start, "the summary",
                  [&](std::uint8_t opcode, std::uint64_t, const std::uint8_t* data, std::uint64_t length) {
                    if (opcode == kOpSchema) parseSchema(data, length, &catalogue->schemas);
                    if (opcode == kOpChannel) parseChannel(data, length, &catalogue->channels);
                    if (opcode == kOpChunkIndex) {
                      Fields f(data, length, "chunk index");
                      McapBlock block;
                      block.start_ns = f.u64();
                      block.end_ns = f.u64();
                      block.offset = f.u64();
                      block.length = f.u64();
                      for (const auto& [channel, offset] : f.mapU16U64()) block.channels.push_back(channel);
                      f.u64();  // message index length
                      catalogue->compressions.insert(f.string());
                      if (block.offset < data_start || block.offset > summary_start ||
                          block.length > summary_start - block.offset || block.length < kPrefixBytes)
                        throw Malformed("a chunk index points outside the data section");
                      catalogue->blocks.push_back(std::move(block));
                    }
                    if (opcode == kOpStatistics) {
                      Fields f(data, length, "statistics");
                      message_count = f.u64();
                      f.u16();  // schemas
                      f.u32();  // channels
                      f.u32();  // attachments
                      f.u32();  // metadata
                      chunk_count = f.u32();
                      catalogue->first_ns = f.u64();
                      f.u64();  // message end time
                      for (const auto& [channel, count] : f.mapU16U64()) catalogue->counts[channel] = count;
                      have_statistics = true;
                    }
                  });
  } catch (const Malformed& e) {
    return std::string("damaged summary (") + e.what() + ")";
  }
  if (catalogue->blocks.empty() && !(have_statistics && message_count == 0)) return "summary without chunk indexes";
  if (have_statistics && chunk_count != catalogue->blocks.size())
    return "summary indexes " + std::to_string(catalogue->blocks.size()) + " of " + std::to_string(chunk_count) +
           " chunks";
  for (const McapBlock& block : catalogue->blocks)
    for (std::uint16_t channel : block.channels)
      if (!catalogue->channels.contains(channel)) return "summary without channel " + std::to_string(channel);
  return "";
}

/// What reading linearly found wrong, where the index ends.
struct LinearDamage {
  std::string what;
  bool has_time = false;
  std::uint64_t after_ns = 0;
};

/// Reads the data section from `data_start` record by record (decompressing each chunk) into
/// `catalogue`, checking chunk CRCs and the data section's CRC; stops at the first damage.
/// `head`: the file's bytes before data_start (magic and header), the start of the data CRC.
LinearDamage readLinearly(const RecordReader& file, std::uint64_t data_start, const std::vector<std::uint8_t>& head,
                          Catalogue* catalogue) {
  const std::uint64_t size = file.size();
  std::uint32_t crc = crc32Of(0, head.data(), head.size());
  LinearDamage damage;
  McapBlock run;  // the loose messages read since the last chunk or other record
  run.is_chunk = false;
  auto endRun = [&] {
    if (run.length > 0) catalogue->blocks.push_back(run);
    run = McapBlock();
    run.is_chunk = false;
  };
  auto noteMessage = [&](McapBlock* block, const MessageHeader& message) {
    if (block->channels.empty()) block->start_ns = block->end_ns = message.log_time_ns;  // its first message
    if (std::find(block->channels.begin(), block->channels.end(), message.channel_id) == block->channels.end())
      block->channels.push_back(message.channel_id);
    block->start_ns = std::min(block->start_ns, message.log_time_ns);
    block->end_ns = std::max(block->end_ns, message.log_time_ns);
    ++catalogue->counts[message.channel_id];
    damage.after_ns = damage.has_time ? std::max(damage.after_ns, message.log_time_ns) : message.log_time_ns;
    damage.has_time = true;
  };
  std::uint64_t pos = data_start;
  try {
    for (;;) {
      if (pos == size) throw Malformed("truncated at " + at(size) + " (the file ends without its footer)");
      const auto [opcode, length] = file.prefixAt(pos);
      std::uint8_t prefix[kPrefixBytes] = {opcode};
      for (std::size_t i = 0; i < 8; ++i) prefix[1 + i] = static_cast<std::uint8_t>(length >> (8 * i));
      if (opcode == kOpDataEnd) {
        endRun();
        std::uint8_t content[4] = {};
        if (length < 4) throw Malformed("the data end record at " + at(pos) + " is too short");
        file.bytesInto(pos + kPrefixBytes, content, 4);
        const std::uint32_t expected = littleU32(content);
        if (expected != 0 && expected != crc)
          throw Malformed("the data section fails its CRC check (a byte outside the chunks is damaged)");
        return LinearDamage();
      }
      if (opcode == kOpFooter) {  // a writer that left out the data end record
        endRun();
        return LinearDamage();
      }
      if (opcode == 0) throw Malformed(at(pos) + " holds no record (opcode 0)");
      crc = crc32Of(crc, prefix, kPrefixBytes);
      if (opcode == kOpChunk || opcode == kOpMessage || opcode == kOpSchema || opcode == kOpChannel) {
        const std::uint64_t content_size = length;
        std::shared_ptr<std::uint8_t[]> content = file.contentAt(pos, opcode, length);
        crc = crc32Of(crc, content.get(), content_size);
        if (opcode == kOpChunk) {
          endRun();
          ChunkFields fields;
          const auto buffer = decodeChunk(pos, std::move(content), content_size, &fields);
          catalogue->compressions.insert(fields.compression);
          // Messages count once the whole chunk parses: a damaged chunk is lost as a whole.
          std::vector<MessageHeader> messages;
          forEachRecord(buffer->data, buffer->size, "chunk at " + at(pos),
                        [&](std::uint8_t inner, std::uint64_t, const std::uint8_t* data, std::uint64_t inner_length) {
                          if (inner == kOpSchema) parseSchema(data, inner_length, &catalogue->schemas);
                          if (inner == kOpChannel) parseChannel(data, inner_length, &catalogue->channels);
                          if (inner == kOpMessage) messages.push_back(parseMessageHeader(data, inner_length));
                        });
          McapBlock block;
          for (const MessageHeader& message : messages) noteMessage(&block, message);
          block.offset = pos;
          block.length = kPrefixBytes + content_size;
          if (!block.channels.empty()) catalogue->blocks.push_back(std::move(block));
        } else {
          MessageHeader message;
          try {
            if (opcode == kOpSchema) parseSchema(content.get(), content_size, &catalogue->schemas);
            if (opcode == kOpChannel) parseChannel(content.get(), content_size, &catalogue->channels);
            if (opcode == kOpMessage) message = parseMessageHeader(content.get(), content_size);
          } catch (const Malformed& e) {
            throw Malformed("record at " + at(pos) + ": " + e.what());
          }
          if (opcode == kOpMessage) {
            if (run.length > 0 && run.length + kPrefixBytes + content_size > kLooseRunBytes) endRun();
            if (run.length == 0) run.offset = pos;
            noteMessage(&run, message);
          }
          // Schema and channel records inside a run keep it contiguous.
          if (run.length > 0 || opcode == kOpMessage) run.length = pos + kPrefixBytes + content_size - run.offset;
        }
      } else {
        // Indexes, attachments, metadata, private records: not read, but part of the data CRC.
        endRun();
        std::vector<std::uint8_t> piece(static_cast<std::size_t>(std::min(length, kSkipPieceBytes)));
        for (std::uint64_t done = 0; done < length;) {
          const std::uint64_t n = std::min<std::uint64_t>(piece.size(), length - done);
          file.bytesInto(pos + kPrefixBytes + done, piece.data(), n);
          crc = crc32Of(crc, piece.data(), n);
          done += n;
        }
      }
      pos += kPrefixBytes + length;
    }
  } catch (const Malformed& e) {
    endRun();
    damage.what = e.what();
    return damage;
  }
}

/// The kind of a channel's messages: only encodings vdmap decodes get a kind other than kOther.
MessageType kindOf(const std::string& type, const std::string& message_encoding) {
  // ROS 2 names hold "/msg/", ROS 1 names do not.
  const bool ros2_name = type.find("/msg/") != std::string::npos;
  if (message_encoding == "cdr" && ros2_name) return messageType(type);
  if (message_encoding == "ros1" && !ros2_name) return messageType(type);
  return MessageType::kOther;
}

/// Topics from the catalogue's channels: channels with the same topic, type and encoding (one per
/// publisher, say) share one Topic.
void makeTopics(const Catalogue& catalogue, McapIndex* index) {
  std::map<std::tuple<std::string, std::string, std::string>, int> seen;
  for (const auto& [id, channel] : catalogue.channels) {
    const auto schema = catalogue.schemas.find(channel.schema_id);
    const std::string type = schema != catalogue.schemas.end() ? schema->second.name : "";
    const auto key = std::make_tuple(channel.topic, type, channel.message_encoding);
    auto [it, added] = seen.emplace(key, static_cast<int>(index->topics.size()));
    if (added) {
      Topic topic;
      topic.name = channel.topic;
      topic.type = type;
      topic.kind = kindOf(type, channel.message_encoding);
      index->topics.push_back(topic);
      index->topic_encodings.push_back(channel.message_encoding == "ros1" ? Encoding::kRos1 : Encoding::kCdr);
    }
    index->channel_topic[id] = it->second;
    if (const auto count = catalogue.counts.find(id); count != catalogue.counts.end())
      index->topics[static_cast<std::size_t>(it->second)].count += count->second;
  }
}

/// A message of a loaded block waiting for its turn in log-time order.
struct PendingMessage {
  std::uint64_t log_time_ns = 0;
  MessageRef ref;
  int topic = -1;
  std::shared_ptr<const McapBuffer> buffer;
  std::uint64_t data_offset = 0, data_size = 0;  ///< the message's bytes in buffer
  /// Later in the scan: later log time, ties in file order.
  bool operator>(const PendingMessage& other) const {
    if (log_time_ns != other.log_time_ns) return log_time_ns > other.log_time_ns;
    if (ref.position != other.ref.position) return ref.position > other.ref.position;
    return ref.offset > other.ref.offset;
  }
};

std::string secondsText(std::uint64_t ns, std::uint64_t origin_ns) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", ns >= origin_ns ? static_cast<double>(ns - origin_ns) * 1e-9 : 0.0);
  return text;
}

}  // namespace
}  // namespace mcap_reader

McapFile::McapFile(std::filesystem::path path, int fd, std::uint64_t size_bytes)
    : path_(std::move(path)), fd_(fd), size_bytes_(size_bytes) {}

McapFile::~McapFile() {
  if (fd_ >= 0) ::close(fd_);
}

const std::vector<Topic>& McapFile::topics() const { return index_->topics; }

std::unique_ptr<McapFile> McapFile::open(const std::filesystem::path& file) {
  using namespace mcap_reader;
  const std::string name = file.string();
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(name, std::string("cannot open: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    throw InputError(name, "not a regular file");
  }
  // From here the McapFile owns fd and closes it, whatever is thrown.
  std::unique_ptr<McapFile> mcap(new McapFile(file, fd, static_cast<std::uint64_t>(info.st_size)));
  const RecordReader reader(fd, mcap->size_bytes_);
  const std::uint64_t size = mcap->size_bytes_;
  auto index = std::make_unique<McapIndex>();

  // Magic and header record: without them this is not an MCAP file at all.
  std::uint8_t start[sizeof(kMagic) + kPrefixBytes] = {};
  const std::uint64_t start_bytes = std::min<std::uint64_t>(size, sizeof(start));
  if (!readAt(fd, 0, start, start_bytes)) throw InputError(name, "cannot read the file");
  if (start_bytes < sizeof(kMagic) || std::memcmp(start, kMagic, sizeof(kMagic)) != 0)
    throw InputError(name, "not an MCAP file (it starts with " +
                               printable(std::string_view(reinterpret_cast<const char*>(start),
                                                          std::min<std::uint64_t>(start_bytes, sizeof(kMagic)))) +
                               ", not MCAP's magic)");
  if (start_bytes < sizeof(start) || start[sizeof(kMagic)] != kOpHeader)
    throw InputError(name, "MCAP file without a header record after its magic (cut short or damaged)");
  const std::uint64_t header_length = littleU64(start + sizeof(kMagic) + 1);
  if (header_length > kMaxHeaderBytes || header_length > size - sizeof(start))
    throw InputError(name,
                     "MCAP header record declares " + std::to_string(header_length) + " bytes (cut short or damaged)");
  const std::uint64_t data_start = sizeof(start) + header_length;
  std::vector<std::uint8_t> head(static_cast<std::size_t>(data_start));
  if (!readAt(fd, 0, head.data(), data_start)) throw InputError(name, "cannot read the MCAP header");
  try {
    Fields f(head.data() + sizeof(start), header_length, "header");
    index->profile = f.string();
    f.string();  // library
  } catch (const Malformed& e) {
    throw InputError(name, std::string("unreadable MCAP header: ") + e.what());
  }

  Catalogue catalogue;
  std::string no_summary;
  try {
    no_summary = readSummary(reader, data_start, &catalogue);
  } catch (const Malformed& e) {  // a read failed
    no_summary = std::string("unreadable summary (") + e.what() + ")";
  }
  if (no_summary.empty()) {
    index->how_read = "with summary";
  } else {
    catalogue = Catalogue();
    const LinearDamage damage = readLinearly(reader, data_start, head, &catalogue);
    index->how_read = no_summary + ": read linearly";
    index->damage = damage.what;
    index->damage_has_time = damage.has_time;
    index->damage_after_ns = damage.after_ns;
  }
  makeTopics(catalogue, index.get());
  index->compressions = catalogue.compressions;
  index->blocks = std::move(catalogue.blocks);
  std::stable_sort(index->blocks.begin(), index->blocks.end(), [](const McapBlock& a, const McapBlock& b) {
    return a.start_ns != b.start_ns ? a.start_ns < b.start_ns : a.offset < b.offset;
  });
  index->first_ns = catalogue.first_ns;
  if (index->first_ns == 0) {
    // Chunk indexes of chunks without messages give 0 for both times: not a log time.
    bool found = false;
    for (const McapBlock& block : index->blocks) {
      if (block.start_ns == 0 && block.end_ns == 0) continue;
      index->first_ns = found ? std::min(index->first_ns, block.start_ns) : block.start_ns;
      found = true;
    }
  }
  mcap->index_ = std::move(index);
  return mcap;
}

std::string McapFile::describe() const {
  std::string chunks;
  for (const std::string& compression : index_->compressions)
    chunks += (chunks.empty() ? "" : " and ") + (compression.empty() ? std::string("uncompressed") : compression);
  chunks = chunks.empty() ? "no chunks" : chunks + " chunks";
  const std::string profile = index_->profile.empty() ? "no profile" : "profile " + index_->profile;
  std::string text = "MCAP (" + profile + ", " + chunks + ", " + index_->how_read;
  if (!index_->damage.empty()) text += "; damaged";
  return text + ")";
}

ScanEnd McapFile::scan(const std::vector<int>& topics, const std::function<bool(const Message&)>& visit) const {
  using namespace mcap_reader;
  const McapIndex& index = *index_;
  const std::string name = path_.string();
  std::vector<char> wanted(index.topics.size(), 0);
  for (int topic : topics)
    if (topic >= 0 && static_cast<std::size_t>(topic) < wanted.size()) wanted[static_cast<std::size_t>(topic)] = 1;
  std::unordered_map<std::uint16_t, int> channel_topic;  // only the wanted channels
  for (const auto& [channel, topic] : index.channel_topic)
    if (wanted[static_cast<std::size_t>(topic)]) channel_topic[channel] = topic;

  const RecordReader reader(fd_, size_bytes_);
  std::priority_queue<PendingMessage, std::vector<PendingMessage>, std::greater<>> pending;
  auto load = [&](const McapBlock& block) {
    std::shared_ptr<const McapBuffer> buffer;
    std::string where;
    if (block.is_chunk) {
      buffer = reader.chunkAt(block.offset);
      where = "chunk at " + at(block.offset);
    } else {
      if (block.offset > size_bytes_ || block.length > size_bytes_ - block.offset)
        throw Malformed("truncated at " + at(size_bytes_) + " in records at " + at(block.offset));
      auto run = std::make_shared<McapBuffer>();
      std::shared_ptr<std::uint8_t[]> bytes = reader.bytesAt(block.offset, block.length);
      run->data = bytes.get();
      run->size = block.length;
      run->storage = std::move(bytes);
      buffer = std::move(run);
      where = "records at " + at(block.offset);
    }
    forEachRecord(
        buffer->data, buffer->size, where,
        [&](std::uint8_t opcode, std::uint64_t offset, const std::uint8_t* data, std::uint64_t length) {
          if (opcode != kOpMessage) return;
          const MessageHeader header = parseMessageHeader(data, length);
          const auto topic = channel_topic.find(header.channel_id);
          if (topic == channel_topic.end()) return;
          PendingMessage message;
          message.log_time_ns = header.log_time_ns;
          message.ref = block.is_chunk ? MessageRef{block.offset, offset} : MessageRef{block.offset + offset, 0};
          message.topic = topic->second;
          message.buffer = buffer;
          message.data_offset = offset + kPrefixBytes + kMessageHeaderBytes;
          message.data_size = length - kMessageHeaderBytes;
          pending.push(std::move(message));
        });
  };
  auto wantedBlock = [&](const McapBlock& block) {
    if (block.channels.empty()) return true;  // not indexed: read it to see
    return std::any_of(block.channels.begin(), block.channels.end(),
                       [&](std::uint16_t channel) { return channel_topic.contains(channel); });
  };

  // Blocks are sorted by their earliest message: one is loaded once the next message in time
  // order could be in it, so overlapping chunks merge and ties keep file order.
  std::size_t next = channel_topic.empty() ? index.blocks.size() : 0;
  for (;;) {
    while (next < index.blocks.size() &&
           (pending.empty() || index.blocks[next].start_ns <= pending.top().log_time_ns)) {
      const McapBlock& block = index.blocks[next++];
      if (!wantedBlock(block)) continue;
      try {
        load(block);
      } catch (const Malformed& e) {
        return ScanEnd{false, name + ": " + e.what() + "; messages from " +
                                  secondsText(block.start_ns, index.first_ns) + " s on are lost"};
      }
    }
    if (pending.empty()) break;
    const PendingMessage& top = pending.top();
    Message message;
    message.topic = top.topic;
    message.log_time_ns = static_cast<std::int64_t>(top.log_time_ns);
    message.ref = top.ref;
    message.encoding = index.topic_encodings[static_cast<std::size_t>(top.topic)];
    const std::uint8_t* bytes = top.buffer->data + top.data_offset;
    message.bytes = std::make_shared<const std::vector<std::uint8_t>>(bytes, bytes + top.data_size);
    pending.pop();  // drops the buffer's share: a chunk goes once its last message is visited
    if (!visit(message)) return ScanEnd();
  }
  if (!index.damage.empty()) {
    const std::string lost =
        index.damage_has_time ? "messages after " + secondsText(index.damage_after_ns, index.first_ns) + " s are lost"
                              : "no message before it could be read";
    return ScanEnd{false, name + ": " + index.damage + "; " + lost};
  }
  return ScanEnd();
}

Message McapFile::read(const MessageRef& ref) const {
  using namespace mcap_reader;
  const RecordReader reader(fd_, size_bytes_);
  const std::lock_guard lock(read_mutex_);
  try {
    const auto [opcode, length] = reader.prefixAt(ref.position);
    std::shared_ptr<const void> keep;  // owns the bytes `content` points into
    const std::uint8_t* content = nullptr;
    std::uint64_t content_size = 0;
    if (opcode == kOpMessage) {
      if (ref.offset != 0) throw Malformed("a message outside chunks has no offset " + std::to_string(ref.offset));
      std::shared_ptr<std::uint8_t[]> bytes = reader.contentAt(ref.position, opcode, length);
      content = bytes.get();
      content_size = length;
      keep = std::move(bytes);
    } else if (opcode == kOpChunk) {
      if (!cached_chunk_ || cached_position_ != ref.position) {
        cached_chunk_.reset();  // one chunk in memory, not two
        cached_chunk_ = reader.chunkAt(ref.position);
        cached_position_ = ref.position;
      }
      const McapBuffer& chunk = *cached_chunk_;
      const std::uint64_t offset = ref.offset;
      if (offset > chunk.size || chunk.size - offset < kPrefixBytes || chunk.data[offset] != kOpMessage)
        throw Malformed("the chunk holds no message record at offset " + std::to_string(offset));
      content = chunk.data + offset + kPrefixBytes;
      content_size = littleU64(chunk.data + offset + 1);
      if (content_size > chunk.size - offset - kPrefixBytes)
        throw Malformed("the message record at offset " + std::to_string(offset) + " runs past the chunk's end");
      keep = cached_chunk_;
    } else {
      throw Malformed(at(ref.position) + " holds a " + recordName(opcode) + " record, not a message or chunk");
    }
    const MessageHeader header = parseMessageHeader(content, content_size);
    const auto topic = index_->channel_topic.find(header.channel_id);
    if (topic == index_->channel_topic.end())
      throw Malformed("the message is on channel " + std::to_string(header.channel_id) +
                      ", which the file never defines");
    Message message;
    message.topic = topic->second;
    message.log_time_ns = static_cast<std::int64_t>(header.log_time_ns);
    message.ref = ref;
    message.encoding = index_->topic_encodings[static_cast<std::size_t>(topic->second)];
    message.bytes =
        std::make_shared<const std::vector<std::uint8_t>>(content + kMessageHeaderBytes, content + content_size);
    return message;
  } catch (const Malformed& e) {
    throw InputError(path_.string(), "cannot read the message at " + at(ref.position) + " (offset " +
                                         std::to_string(ref.offset) + "): " + e.what());
  }
}

}  // namespace vdmap::ros
