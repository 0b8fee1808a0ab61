#include "mapping/ros/ros1_bag.h"

#include <bzlib.h>
#include <lz4frame.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string_view>
#include <tuple>

#include "mapping/core/error.h"

namespace vdmap::ros {
// In a namespace of its own: the MCAP reader's file may share a unity batch with this one.
namespace ros1bag {
namespace {

namespace fs = std::filesystem;

// Bag files are little-endian and fields are copied as they lie.
static_assert(std::endian::native == std::endian::little);

constexpr std::string_view kBagMagic = "#ROSBAG V2.0\n";

// Record ops of format 2.0.
constexpr std::uint8_t kOpMessageDefinition = 0x01;  // format 1.2's; rosbag skips it in chunks too
constexpr std::uint8_t kOpMessageData = 0x02;
constexpr std::uint8_t kOpBagHeader = 0x03;
constexpr std::uint8_t kOpIndexData = 0x04;
constexpr std::uint8_t kOpChunk = 0x05;
constexpr std::uint8_t kOpChunkInfo = 0x06;
constexpr std::uint8_t kOpConnection = 0x07;

// Record headers hold a few short fields (a connection's is its id and topic): a longer one is
// damage, and the bound keeps a garbage length from asking for the rest of a large file.
constexpr std::uint32_t kMaxHeaderBytes = 1u << 16;
// rosbag writes chunks of about 768 KiB; a chunk claiming more than this is damage, and refusing
// it keeps a hostile size field from asking for gigabytes.
constexpr std::uint32_t kMaxChunkBytes = 1u << 30;

enum class Compression { kNone, kLz4, kBz2 };

const char* compressionName(Compression c) {
  switch (c) {
    case Compression::kNone: return "uncompressed";
    case Compression::kLz4: return "lz4";
    case Compression::kBz2: return "bz2";
  }
  return "?";
}

/// One "name=value" field of a record header; views into the header's bytes.
struct Field {
  std::string_view name, value;
};

/// Splits a record header into its fields (each a 4-byte length, then "name=value").
bool parseFields(std::string_view header, std::vector<Field>& fields, std::string& why) {
  fields.clear();
  while (!header.empty()) {
    std::uint32_t length = 0;
    if (header.size() < 4) return why = "a header field's length is cut", false;
    std::memcpy(&length, header.data(), 4);
    header.remove_prefix(4);
    if (length > header.size()) return why = "a header field runs past its header", false;
    const std::string_view field = header.substr(0, length);
    header.remove_prefix(length);
    const auto equals = field.find('=');
    if (equals == std::string_view::npos) return why = "a header field has no '='", false;
    fields.push_back({field.substr(0, equals), field.substr(equals + 1)});
  }
  return true;
}

std::optional<std::string_view> findField(const std::vector<Field>& fields, std::string_view name) {
  for (const Field& f : fields)
    if (f.name == name) return f.value;
  return std::nullopt;
}

/// A fixed-size little-endian field (u8, u32, u64): absent or of another size is nullopt.
template <typename T>
std::optional<T> intField(const std::vector<Field>& fields, std::string_view name) {
  const auto value = findField(fields, name);
  if (!value || value->size() != sizeof(T)) return std::nullopt;
  T out;
  std::memcpy(&out, value->data(), sizeof(T));
  return out;
}

/// A packed ROS time field (u32 sec, u32 nsec) in nanoseconds.
std::optional<std::int64_t> timeField(const std::vector<Field>& fields, std::string_view name) {
  const auto packed = intField<std::uint64_t>(fields, name);
  if (!packed) return std::nullopt;
  return static_cast<std::int64_t>(*packed & 0xFFFFFFFFu) * 1'000'000'000 + static_cast<std::int64_t>(*packed >> 32);
}

std::string seconds(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", static_cast<double>(ns) * 1e-9);
  return text;
}

/// The bag file, read at positions; every read is checked against its size.
class BagFile {
 public:
  explicit BagFile(const fs::path& path) : in_(path, std::ios::binary) {
    std::error_code error;
    size_ = fs::file_size(path, error);
    ok_ = in_.good() && !error;
  }
  bool ok() const { return ok_; }
  std::uint64_t size() const { return size_; }
  bool read(std::uint64_t pos, void* out, std::uint64_t n) {
    if (pos > size_ || n > size_ - pos) return false;
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(pos));
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    return in_.gcount() == static_cast<std::streamsize>(n);
  }

 private:
  std::ifstream in_;
  std::uint64_t size_ = 0;
  bool ok_ = false;
};

/// A record of the file (not inside a chunk): its header read and split, its data left in the file.
struct Record {
  Record() = default;
  Record(const Record&) = delete;  // fields view into header
  Record& operator=(const Record&) = delete;

  std::uint64_t pos = 0;
  std::string header;
  std::vector<Field> fields;
  std::uint8_t op = 0;  ///< 0 until the header was read whole
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::uint64_t end() const { return data_pos + data_len; }
};

enum class ReadStatus { kOk, kCut, kBad };

/// Reads the record at `pos`. kCut: the file ends inside it (when only its data is cut, `record`
/// has its header and op, so a cut chunk can still give its first messages); kBad: it does not
/// parse (`why` says how).
ReadStatus readRecord(BagFile& file, std::uint64_t pos, Record& record, std::string& why) {
  record.pos = pos;
  record.op = 0;
  std::uint32_t header_len = 0;
  if (!file.read(pos, &header_len, 4)) return why = "the file ends inside a record's length", ReadStatus::kCut;
  // A cut file shows a sane length with its bytes missing; an absurd one is damage.
  if (header_len > kMaxHeaderBytes)
    return why = "a record header of " + std::to_string(header_len) + " bytes", ReadStatus::kBad;
  record.header.resize(header_len);
  if (!file.read(pos + 4, record.header.data(), header_len))
    return why = "the file ends inside a record header", ReadStatus::kCut;
  if (!parseFields(record.header, record.fields, why)) return ReadStatus::kBad;
  const auto op = intField<std::uint8_t>(record.fields, "op");
  if (!op) return why = "a record header without an op field", ReadStatus::kBad;
  if (!file.read(pos + 4 + header_len, &record.data_len, 4))
    return why = "the file ends inside a record's data length", ReadStatus::kCut;
  record.op = *op;
  record.data_pos = pos + 8 + header_len;
  if (record.data_len > file.size() - record.data_pos)
    return why = "a record's data runs past the end of the file", ReadStatus::kCut;
  return ReadStatus::kOk;
}

/// A record inside a decompressed chunk; fields view into the chunk's bytes.
struct ChunkRecord {
  std::vector<Field> fields;
  std::uint8_t op = 0;
  std::size_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::size_t end() const { return data_pos + data_len; }
};

/// Reads the record at `offset` of a chunk's bytes; false when it does not fit or parse. With
/// `with_data` false its data may lie beyond the bytes given.
bool chunkRecord(std::span<const std::uint8_t> chunk, std::size_t offset, ChunkRecord& record, std::string& why,
                 bool with_data = true) {
  std::uint32_t header_len = 0;
  if (offset > chunk.size() || chunk.size() - offset < 4) return why = "a record's length is cut", false;
  std::memcpy(&header_len, chunk.data() + offset, 4);
  if (header_len > chunk.size() - offset - 4) return why = "a record header runs past its chunk", false;
  const std::string_view header(reinterpret_cast<const char*>(chunk.data() + offset + 4), header_len);
  if (!parseFields(header, record.fields, why)) return false;
  const auto op = intField<std::uint8_t>(record.fields, "op");
  if (!op) return why = "a record header without an op field", false;
  const std::size_t len_pos = offset + 4 + header_len;
  if (chunk.size() - len_pos < 4) return why = "a record's data length is cut", false;
  std::memcpy(&record.data_len, chunk.data() + len_pos, 4);
  record.op = *op;
  record.data_pos = len_pos + 4;
  if (with_data && record.data_len > chunk.size() - record.data_pos)
    return why = "a record's data runs past its chunk", false;
  return true;
}

/// A message data record found in a chunk.
struct ChunkMessage {
  std::uint32_t conn = 0;
  std::int64_t time_ns = 0;
  std::span<const std::uint8_t> data;
};

/// A message data record's connection and time; false when the record is not one.
bool messageFields(const ChunkRecord& record, ChunkMessage& message, std::string& why) {
  if (record.op != kOpMessageData)
    return why = "the record is not a message (op " + std::to_string(record.op) + ")", false;
  const auto conn = intField<std::uint32_t>(record.fields, "conn");
  const auto time = timeField(record.fields, "time");
  if (!conn || !time) return why = "a message record without conn and time fields", false;
  message.conn = *conn, message.time_ns = *time;
  return true;
}

/// The message data record at `offset` of a chunk, past the connection records before it: rosbag
/// indexes a connection's first message at the connection record written just before it.
bool messageAt(std::span<const std::uint8_t> chunk, std::size_t offset, ChunkMessage& message, std::string& why) {
  ChunkRecord record;
  for (;;) {  // ends: each record moves `offset` on by at least 8 bytes, and the chunk is finite
    if (!chunkRecord(chunk, offset, record, why)) return false;
    if (record.op != kOpConnection && record.op != kOpMessageDefinition) break;
    offset = record.end();
  }
  if (!messageFields(record, message, why)) return false;
  message.data = chunk.subspan(record.data_pos, record.data_len);
  return true;
}

// How much of an image message a scan with heads gives: its header, size and encoding (a frame
// id or encoding longer than this makes the listing read the message whole).
constexpr std::size_t kHeadBytes = 1024;

/// A chunk's data `in` decompressed as far as they are asked for, into `out` (at most `size`
/// bytes; both buffers are the caller's, so that a scan re-uses them chunk after chunk). With
/// `partial` (a chunk the file cuts short) the data may end early and give what they hold;
/// otherwise finish() checks that they give exactly `size`. The output grows as the data
/// decompress, so a false size costs only what the data really give. Uncompressed data are
/// given as they lie in `in`.
class ChunkInflater {
 public:
  ChunkInflater(Compression compression, std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out,
                std::uint32_t size, bool partial)
      : compression_(compression), in_(in), out_(out), size_(size), partial_(partial) {
    out_.clear();
    if (compression_ == Compression::kNone) {
      ended_ = true;
    } else if (compression_ == Compression::kLz4) {
      if (LZ4F_isError(LZ4F_createDecompressionContext(&lz4_, LZ4F_VERSION))) lz4_ = nullptr;
    } else {
      bz2_ready_ = BZ2_bzDecompressInit(&bz2_, 0, 0) == BZ_OK;
    }
  }
  ~ChunkInflater() {
    if (lz4_) LZ4F_freeDecompressionContext(lz4_);
    if (bz2_ready_) BZ2_bzDecompressEnd(&bz2_);
  }
  ChunkInflater(const ChunkInflater&) = delete;
  ChunkInflater& operator=(const ChunkInflater&) = delete;

  /// Decompresses until at least `n` bytes are out or the data end (then fewer are); false with
  /// `why` when the data do not decode.
  bool ensure(std::size_t n, std::string& why) {
    if (!error_.empty()) return why = error_, false;
    while (produced_ < n && !ended_ && !stalled_ && grow()) {
      std::size_t dst = 0, src = 0;
      if (compression_ == Compression::kLz4) {
        if (!lz4_) return why = error_ = "out of memory", false;
        dst = out_.size() - produced_, src = in_.size() - consumed_;
        const std::size_t r =
            LZ4F_decompress(lz4_, out_.data() + produced_, &dst, in_.data() + consumed_, &src, nullptr);
        if (LZ4F_isError(r))
          return why = error_ = std::string("lz4 data do not decode (") + LZ4F_getErrorName(r) + ")", false;
        ended_ = r == 0;
      } else {
        if (!bz2_ready_) return why = error_ = "out of memory", false;
        // Both counts fit: a chunk's data and size are 32-bit fields.
        bz2_.next_in = const_cast<char*>(reinterpret_cast<const char*>(in_.data() + consumed_));
        bz2_.avail_in = static_cast<unsigned>(in_.size() - consumed_);
        bz2_.next_out = reinterpret_cast<char*>(out_.data() + produced_);
        bz2_.avail_out = static_cast<unsigned>(out_.size() - produced_);
        const int r = BZ2_bzDecompress(&bz2_);
        dst = out_.size() - produced_ - bz2_.avail_out, src = in_.size() - consumed_ - bz2_.avail_in;
        if (r != BZ_OK && r != BZ_STREAM_END)
          return why = error_ = "bz2 data do not decode (error " + std::to_string(r) + ")", false;
        ended_ = r == BZ_STREAM_END;
      }
      produced_ += dst;
      consumed_ += src;
      stalled_ = dst == 0 && src == 0;  // the data end early: no call will give more
    }
    return true;
  }

  /// Decompresses the rest and checks the total against the chunk's size.
  bool finish(std::string& why) {
    if (compression_ == Compression::kNone) {
      if (in_.size() > size_ || (!partial_ && in_.size() != size_))
        return why =
                   "an uncompressed chunk of " + std::to_string(in_.size()) + " bytes states " + std::to_string(size_),
               false;
      return true;
    }
    if (!ensure(size_ + std::size_t{1}, why)) return false;
    if (ended_ && produced_ != size_)
      return why = "a chunk decompresses to " + std::to_string(produced_) + " bytes, its header says " +
                   std::to_string(size_),
             false;
    if (!ended_ && !partial_) {
      if (produced_ == size_)
        return why = "a chunk decompresses to more than the " + std::to_string(size_) + " bytes its header says", false;
      return why = std::string(compressionName(compression_)) + " data end early", false;
    }
    return true;
  }

  /// The bytes decompressed so far.
  std::span<const std::uint8_t> bytes() const {
    return compression_ == Compression::kNone ? in_ : std::span<const std::uint8_t>(out_.data(), produced_);
  }

 private:
  // Room for more output: false when the output holds `size` bytes already.
  bool grow() {
    if (produced_ < out_.size()) return true;
    if (out_.size() >= size_) return false;
    out_.resize(std::min<std::size_t>(size_, std::max<std::size_t>(out_.size() * 2, std::size_t{1} << 16)));
    return true;
  }

  Compression compression_;
  std::span<const std::uint8_t> in_;
  std::vector<std::uint8_t>& out_;
  std::uint32_t size_;
  bool partial_;
  std::size_t produced_ = 0, consumed_ = 0;
  bool ended_ = false, stalled_ = false;
  std::string error_;
  LZ4F_dctx* lz4_ = nullptr;
  bz_stream bz2_{};
  bool bz2_ready_ = false;
};

/// messageAt() in a chunk decompressed on demand: the message's first `want` bytes of data
/// (`cut` when that is fewer than it has).
bool messageIn(ChunkInflater& chunk, std::size_t offset, std::size_t want, ChunkMessage& message, bool& cut,
               std::string& why) {
  ChunkRecord record;
  for (;;) {  // ends as messageAt's loop does
    std::uint32_t header_len = 0;
    if (!chunk.ensure(offset + 4, why)) return false;
    if (chunk.bytes().size() >= offset + 4) std::memcpy(&header_len, chunk.bytes().data() + offset, 4);
    if (!chunk.ensure(offset + 8 + std::size_t{header_len}, why) ||
        !chunkRecord(chunk.bytes(), offset, record, why, false))
      return false;
    if (record.op != kOpConnection && record.op != kOpMessageDefinition) break;
    if (!chunk.ensure(record.end(), why)) return false;
    offset = record.end();
  }
  if (!messageFields(record, message, why)) return false;
  const std::size_t take = std::min<std::size_t>(record.data_len, want);
  if (!chunk.ensure(record.data_pos + take, why)) return false;
  if (chunk.bytes().size() - record.data_pos < take) return why = "a record's data runs past its chunk", false;
  message.data = chunk.bytes().subspan(record.data_pos, take);
  cut = take < record.data_len;
  return true;
}

/// A chunk record's place in the file.
struct Chunk {
  std::uint64_t pos = 0;       ///< of the record
  std::uint64_t data_pos = 0;  ///< of its (compressed) data
  std::uint32_t data_len = 0;  ///< all of it, or what the file holds of a cut chunk
  std::uint32_t size = 0;      ///< decompressed, as its header says
  Compression compression = Compression::kNone;
  bool cut = false;  ///< the file ends inside it
};

/// One message as the index gives it.
struct Entry {
  std::int64_t time_ns = 0;
  std::uint32_t chunk = 0;   ///< index into chunks
  std::uint32_t offset = 0;  ///< of its record (or the connection record before it) in the chunk
  std::uint32_t conn = 0;
  int topic = -1;
};

/// A chunk's fields, checked: its compression and decompressed size.
bool chunkFields(const std::vector<Field>& fields, Chunk& chunk, std::string& why) {
  const auto compression = findField(fields, "compression");
  const auto size = intField<std::uint32_t>(fields, "size");
  if (!compression || !size) return why = "a chunk without compression and size fields", false;
  if (*compression == "none") chunk.compression = Compression::kNone;
  else if (*compression == "lz4") chunk.compression = Compression::kLz4;
  else if (*compression == "bz2") chunk.compression = Compression::kBz2;
  else return why = "a chunk compressed with " + printable(*compression), false;
  if (*size > kMaxChunkBytes) return why = "a chunk stating " + std::to_string(*size) + " bytes", false;
  chunk.size = *size;
  return true;
}

}  // namespace

/// The bag as its index gives it, and the reading of it; Ros1Bag's implementation.
struct Reader {
  fs::path path;
  std::vector<Topic> topics;
  std::vector<Chunk> chunks;                ///< in file order
  std::vector<Entry> entries;               ///< in log-time order, ties in file order
  std::map<std::uint32_t, int> conn_topic;  ///< connection id -> index into topics
  std::string damage;                       ///< the note a scan ends with when open found damage; empty when whole
  bool rebuilt = false;                     ///< the index was rebuilt by reading the chunks

  // read()'s last chunk, kept for refs read in file order.
  mutable std::mutex mutex;
  mutable std::uint32_t cached_chunk = UINT32_MAX;
  mutable std::vector<std::uint8_t> cached_bytes;

  /// Connections as their records give them, before topics are made of them.
  std::map<std::uint32_t, std::pair<std::string, std::string>> connections;  // id -> (topic, type)

  void open(BagFile& file);
  /// Reads the index at `index_pos`; false with `why` when it does not parse, and `cut` when the file
  /// ends inside it.
  bool readIndex(BagFile& file, std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count,
                 std::string& why, bool& cut);
  void rebuildIndex(BagFile& file, std::uint64_t first_record, std::uint64_t index_pos,
                    const std::string& index_problem, bool index_missing, bool file_cut);
  bool addConnection(const std::vector<Field>& fields, std::string_view data, std::string& why);
  void walkChunk(std::span<const std::uint8_t> bytes, std::uint32_t chunk, bool cut, std::string& why, bool& bad);
  void finish();
  /// A chunk's data as they lie in the file (compressed).
  bool readChunkData(BagFile& file, const Chunk& chunk, std::vector<std::uint8_t>& data, std::string& why) const;
  /// A chunk decompressed whole and checked.
  bool loadChunk(BagFile& file, const Chunk& chunk, std::vector<std::uint8_t>& bytes, std::string& why) const;
  std::string lostAfter(std::int64_t last_ns, bool any) const;

  std::string describe() const;
  ScanEnd scan(const std::vector<int>& topics, const std::vector<int>& heads,
               const std::function<bool(const Message&)>& visit) const;
  Message read(const MessageRef& ref) const;
};

bool Reader::addConnection(const std::vector<Field>& fields, std::string_view data, std::string& why) {
  const auto conn = intField<std::uint32_t>(fields, "conn");
  const auto topic = findField(fields, "topic");
  if (!conn || !topic) return why = "a connection record without conn and topic fields", false;
  std::vector<Field> header;  // the connection header: type, md5sum, message_definition, ...
  if (!parseFields(data, header, why)) return false;
  const auto type = findField(header, "type");
  connections.try_emplace(*conn, std::string(*topic), type ? std::string(*type) : std::string());
  return true;
}

bool Reader::readIndex(BagFile& file, std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count,
                       std::string& why, bool& cut) {
  // Each loop below reads one record a turn and fails at the end of the file, so a false count
  // costs at most one pass over the file.
  std::uint64_t pos = index_pos;
  Record record;
  std::string data;
  auto readWhole = [&](std::uint8_t op, const char* what) {
    const ReadStatus status = readRecord(file, pos, record, why);
    cut = status == ReadStatus::kCut;
    if (status != ReadStatus::kOk || record.op != op) {
      if (record.op != 0 && record.op != op) why = std::string("expected ") + what + " record";
      why += " at byte " + std::to_string(pos);
      return false;
    }
    pos = record.end();
    return true;
  };
  for (std::uint32_t i = 0; i < conn_count; ++i) {
    if (!readWhole(kOpConnection, "a connection")) return false;
    data.resize(record.data_len);
    if (!file.read(record.data_pos, data.data(), data.size())) return why = "unreadable", false;
    if (!addConnection(record.fields, data, why)) return why += " at byte " + std::to_string(record.pos), false;
  }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> chunk_infos;  // chunk position, connections in it
  for (std::uint32_t i = 0; i < chunk_count; ++i) {
    if (!readWhole(kOpChunkInfo, "a chunk info")) return false;
    const auto version = intField<std::uint32_t>(record.fields, "ver");
    const auto chunk_pos = intField<std::uint64_t>(record.fields, "chunk_pos");
    const auto count = intField<std::uint32_t>(record.fields, "count");
    if (version != 1u || !chunk_pos || !count || record.data_len != std::uint64_t{8} * *count)
      return why = "a chunk info record that does not parse at byte " + std::to_string(record.pos), false;
    chunk_infos.emplace_back(*chunk_pos, *count);
  }
  std::sort(chunk_infos.begin(), chunk_infos.end());
  std::vector<char> index_bytes;
  for (const auto& [chunk_pos, conns_in_chunk] : chunk_infos) {
    pos = chunk_pos;
    if (!readWhole(kOpChunk, "a chunk")) return false;
    Chunk chunk{record.pos, record.data_pos, record.data_len};
    if (!chunkFields(record.fields, chunk, why)) return why += " at byte " + std::to_string(record.pos), false;
    if (!chunks.empty() && chunks.back().pos == chunk.pos) return why = "two chunk infos name one chunk", false;
    const auto chunk_index = static_cast<std::uint32_t>(chunks.size());
    chunks.push_back(chunk);
    for (std::uint32_t c = 0; c < conns_in_chunk; ++c) {
      if (!readWhole(kOpIndexData, "an index data")) return false;
      const auto version = intField<std::uint32_t>(record.fields, "ver");
      const auto conn = intField<std::uint32_t>(record.fields, "conn");
      const auto count = intField<std::uint32_t>(record.fields, "count");
      if (version != 1u || !conn || !count || record.data_len != std::uint64_t{12} * *count)
        return why = "an index data record that does not parse at byte " + std::to_string(record.pos), false;
      if (!connections.contains(*conn))
        return why = "the index names connection " + std::to_string(*conn) + ", which it does not list", false;
      index_bytes.resize(record.data_len);
      if (!file.read(record.data_pos, index_bytes.data(), index_bytes.size())) return why = "unreadable", false;
      for (std::uint32_t e = 0; e < *count; ++e) {
        std::uint32_t sec = 0, nsec = 0, offset = 0;
        std::memcpy(&sec, index_bytes.data() + 12 * e, 4);
        std::memcpy(&nsec, index_bytes.data() + 12 * e + 4, 4);
        std::memcpy(&offset, index_bytes.data() + 12 * e + 8, 4);
        if (offset >= chunk.size)
          return why = "the index points past the end of the chunk at byte " + std::to_string(chunk.pos), false;
        entries.push_back({std::int64_t{sec} * 1'000'000'000 + nsec, chunk_index, offset, *conn, -1});
      }
    }
  }
  return true;
}

void Reader::walkChunk(std::span<const std::uint8_t> bytes, std::uint32_t chunk, bool cut, std::string& why,
                       bool& bad) {
  ChunkRecord record;
  std::size_t offset = 0;
  while (offset < bytes.size()) {
    if (!chunkRecord(bytes, offset, record, why)) {
      // In a chunk the file cuts short the last record is expected to be cut.
      bad = !cut;
      return;
    }
    if (record.op == kOpConnection) {
      const std::string_view data(reinterpret_cast<const char*>(bytes.data() + record.data_pos), record.data_len);
      if (!addConnection(record.fields, data, why)) return void(bad = true);
    } else if (record.op == kOpMessageData) {
      const auto conn = intField<std::uint32_t>(record.fields, "conn");
      const auto time = timeField(record.fields, "time");
      if (!conn || !time) return void((why = "a message record without conn and time fields", bad = true));
      entries.push_back({*time, chunk, static_cast<std::uint32_t>(offset), *conn, -1});
    } else if (record.op != kOpMessageDefinition) {
      return void((why = "a record of op " + std::to_string(record.op) + " in a chunk", bad = true));
    }
    offset = record.end();
  }
}

std::string Reader::lostAfter(std::int64_t last_ns, bool any) const {
  if (!any || entries.empty()) return "no message before it was read";
  return "messages after " + seconds(last_ns - entries.front().time_ns) + " s are lost";
}

// Reads the bag from its first record to its end or its damage, gathering connections, chunks and
// messages as the index would list them. `index_pos`: where the bag header says the index starts
// (0: nowhere); damage there (or a cut there) loses no message, as the chunks come before it.
// `file_cut`: the bag header puts the index past the end of the file, so the file lost its end
// even where it ends between two records.
void Reader::rebuildIndex(BagFile& file, std::uint64_t first_record, std::uint64_t index_pos,
                          const std::string& index_problem, bool index_missing, bool file_cut) {
  rebuilt = true;
  chunks.clear();
  entries.clear();
  std::string problem;  // the damage that stopped the walk, if any
  std::string why;
  Record record;
  std::vector<std::uint8_t> data, bytes;
  std::uint64_t pos = first_record;
  while (pos < file.size()) {
    const ReadStatus status = readRecord(file, pos, record, why);
    if (status == ReadStatus::kBad) {
      problem = "bad record at byte " + std::to_string(pos) + " (" + why + ")";
      break;
    }
    if (status == ReadStatus::kCut && record.op != kOpChunk) {
      problem = "truncated at byte " + std::to_string(file.size());
      break;
    }
    if (record.op == kOpChunk) {
      const bool cut = status == ReadStatus::kCut;
      Chunk chunk{record.pos, record.data_pos, record.data_len};
      if (cut) chunk.data_len = static_cast<std::uint32_t>(file.size() - record.data_pos);
      chunk.cut = cut;
      if (!chunkFields(record.fields, chunk, why)) {
        problem = "bad chunk at byte " + std::to_string(pos) + " (" + why + ")";
        break;
      }
      const auto index = static_cast<std::uint32_t>(chunks.size());
      chunks.push_back(chunk);
      bool bad = false;
      if (!loadChunk(file, chunk, bytes, why)) {
        bad = true;
      } else {
        walkChunk(bytes, index, cut, why, bad);
      }
      if (bad) {
        problem = "bad chunk at byte " + std::to_string(pos) + " (" + why + ")";
        break;
      }
      if (cut) {
        problem = "truncated at byte " + std::to_string(file.size()) + " in a chunk";
        break;
      }
    } else if (record.op == kOpConnection) {
      data.resize(record.data_len);
      const bool read = file.read(record.data_pos, data.data(), data.size());
      const std::string_view text(reinterpret_cast<const char*>(data.data()), data.size());
      if (!read || !addConnection(record.fields, text, why)) {
        problem = "bad connection record at byte " + std::to_string(pos) + " (" + why + ")";
        break;
      }
    } else if (record.op != kOpIndexData && record.op != kOpChunkInfo) {
      problem = "unexpected record (op " + std::to_string(record.op) + ") at byte " + std::to_string(pos);
      break;
    }
    pos = record.end();
  }
  finish();
  const std::string file_name = path.string();
  if (problem.empty() && file_cut) problem = "truncated at byte " + std::to_string(file.size());
  if (problem.empty()) {
    damage = file_name + ": " + index_problem + "; its messages were found by reading it to the end";
    return;
  }
  if (index_pos != 0 && pos >= index_pos) {
    damage = file_name + ": " + problem + ", inside the bag's index; every message was read from its chunks";
    return;
  }
  // How much of the recording the damage costs: messages from the last one read on are lost.
  std::int64_t last = 0;
  for (const Entry& e : entries) last = std::max(last, e.time_ns);
  damage = file_name + ": " + problem +
           (index_missing ? " (the bag's index is missing); " : " (" + index_problem + "); ") +
           lostAfter(last, !entries.empty());
}

bool Reader::readChunkData(BagFile& file, const Chunk& chunk, std::vector<std::uint8_t>& data, std::string& why) const {
  data.resize(chunk.data_len);
  return file.read(chunk.data_pos, data.data(), data.size()) || (why = "the chunk's data cannot be read", false);
}

bool Reader::loadChunk(BagFile& file, const Chunk& chunk, std::vector<std::uint8_t>& bytes, std::string& why) const {
  std::vector<std::uint8_t> data;
  if (!readChunkData(file, chunk, data, why)) return false;
  ChunkInflater inflater(chunk.compression, data, bytes, chunk.size, chunk.cut);
  if (!inflater.finish(why)) return false;
  if (chunk.compression == Compression::kNone) bytes = std::move(data);
  else bytes.resize(inflater.bytes().size());
  return true;
}

void Reader::finish() {
  // Topics in the order of their connections' ids (the order the recorder made them); connections
  // on one topic (several publishers) share it.
  std::map<std::string, int> by_name;
  for (const auto& [id, connection] : connections) {
    const auto [it, added] = by_name.try_emplace(connection.first, static_cast<int>(topics.size()));
    if (added) topics.push_back({connection.first, connection.second, MessageType::kOther, 0});
    conn_topic[id] = it->second;
  }
  for (Topic& topic : topics) topic.kind = messageType(topic.type);
  std::erase_if(entries, [&](Entry& e) {
    const auto it = conn_topic.find(e.conn);
    if (it == conn_topic.end()) return true;  // a message whose connection record was lost
    e.topic = it->second;
    ++topics[e.topic].count;
    return false;
  });
  std::sort(entries.begin(), entries.end(), [&](const Entry& a, const Entry& b) {
    return std::tie(a.time_ns, chunks[a.chunk].pos, a.offset) < std::tie(b.time_ns, chunks[b.chunk].pos, b.offset);
  });
}

void Reader::open(BagFile& file) {
  const std::string name = path.string();
  if (!file.ok()) throw InputError(name, "cannot be read");
  std::string magic(std::min<std::uint64_t>(file.size(), kBagMagic.size()), '\0');
  file.read(0, magic.data(), magic.size());
  if (magic != kBagMagic) {
    if (!magic.empty() && kBagMagic.starts_with(magic))
      throw InputError(name, "truncated at byte " + std::to_string(magic.size()) + ", inside its '#ROSBAG V2.0' line");
    if (magic.starts_with("#ROSBAG V"))
      throw InputError(name, "a ROS bag of format " + printable(magic.substr(9, 3)) + ": only format 2.0 is read");
    throw InputError(name, "not a ROS 1 bag: it does not start with '#ROSBAG V2.0'");
  }
  Record header;
  std::string why;
  if (readRecord(file, kBagMagic.size(), header, why) == ReadStatus::kBad || header.op != kOpBagHeader)
    throw InputError(name, "no bag header record after '#ROSBAG V2.0'" + (why.empty() ? "" : " (" + why + ")"));
  const auto index_pos = intField<std::uint64_t>(header.fields, "index_pos");
  const auto conn_count = intField<std::uint32_t>(header.fields, "conn_count");
  const auto chunk_count = intField<std::uint32_t>(header.fields, "chunk_count");
  if (!index_pos || !conn_count || !chunk_count)
    throw InputError(name, "the bag header lacks index_pos, conn_count or chunk_count");
  // rosbag would load the encryptor plugin the bag names; an encrypted bag's chunks are unreadable here.
  if (findField(header.fields, "encryptor")) throw InputError(name, "an encrypted bag (not supported)");
  // A cut header record's padding: the walk below reports the cut.
  const std::uint64_t first_record = std::min(header.end(), file.size());

  if (*index_pos == 0)
    return rebuildIndex(file, first_record, 0, "the bag's index is missing (its recorder did not close it)", true,
                        false);
  if (*index_pos >= file.size())
    return rebuildIndex(file, first_record, *index_pos, "the bag's index is missing", true, true);
  bool index_cut = false;
  if (*index_pos < first_record || !readIndex(file, *index_pos, *conn_count, *chunk_count, why, index_cut)) {
    connections.clear();
    chunks.clear();
    entries.clear();
    if (why.empty()) why = "it starts at byte " + std::to_string(*index_pos) + ", inside the bag header";
    return rebuildIndex(file, first_record, *index_pos, "its index is damaged: " + why, false, index_cut);
  }
  finish();
}

std::string Reader::describe() const {
  std::set<std::string> kinds;
  for (const Chunk& chunk : chunks) kinds.insert(compressionName(chunk.compression));
  std::string text = "ROS 1 bag (format 2.0";
  for (auto it = kinds.begin(); it != kinds.end(); ++it) text += (it == kinds.begin() ? ", " : " and ") + *it;
  if (!kinds.empty()) text += " chunks";
  if (rebuilt) text += ", index rebuilt by reading the chunks";
  return text + ")";
}

ScanEnd Reader::scan(const std::vector<int>& chosen, const std::vector<int>& heads,
                     const std::function<bool(const Message&)>& visit) const {
  const Reader& bag = *this;
  std::vector<char> wanted(bag.topics.size(), 0), head(bag.topics.size(), 0);
  for (const int t : chosen)
    if (t >= 0 && t < static_cast<int>(wanted.size())) wanted[t] = 1;
  for (const int t : heads)
    if (t >= 0 && t < static_cast<int>(head.size())) head[t] = 1;
  BagFile file(bag.path);
  // Without heads each chunk is decompressed whole and checked when it is reached (as read()
  // does); with heads only as far as the messages asked for.
  std::vector<std::uint8_t> data, bytes;  // the chunk's as read and decompressed, re-used
  std::optional<ChunkInflater> chunk_bytes;
  std::uint32_t loaded = UINT32_MAX;
  std::string why;
  std::int64_t last_ns = 0;
  bool any = false;
  auto damaged = [&](const std::string& what) {
    return ScanEnd{false, bag.path.string() + ": " + what + "; " + bag.lostAfter(last_ns, any)};
  };
  if (!file.ok()) return damaged("cannot be read");
  for (const Entry& entry : bag.entries) {
    if (!wanted[entry.topic]) continue;
    const Chunk& chunk = bag.chunks[entry.chunk];
    if (entry.chunk != loaded) {
      loaded = UINT32_MAX;
      chunk_bytes.reset();
      if (!bag.readChunkData(file, chunk, data, why))
        return damaged("bad chunk at byte " + std::to_string(chunk.pos) + " (" + why + ")");
      chunk_bytes.emplace(chunk.compression, data, bytes, chunk.size, chunk.cut);
      if (heads.empty() && !chunk_bytes->finish(why))
        return damaged("bad chunk at byte " + std::to_string(chunk.pos) + " (" + why + ")");
      loaded = entry.chunk;
    }
    ChunkMessage found;
    bool cut = false;
    if (!messageIn(*chunk_bytes, entry.offset, head[entry.topic] ? kHeadBytes : SIZE_MAX, found, cut, why) ||
        found.conn != entry.conn)
      return damaged("the chunk at byte " + std::to_string(chunk.pos) +
                     " does not hold the message its index names at offset " + std::to_string(entry.offset) +
                     (why.empty() ? "" : " (" + why + ")"));
    Message message;
    message.topic = entry.topic;
    message.log_time_ns = entry.time_ns;
    message.ref = {chunk.pos, entry.offset};
    message.encoding = Encoding::kRos1;
    message.bytes = std::make_shared<const std::vector<std::uint8_t>>(found.data.begin(), found.data.end());
    message.head_only = cut;
    last_ns = entry.time_ns;
    any = true;
    if (!visit(message)) return {};
  }
  if (!bag.damage.empty()) return {false, bag.damage};
  return {};
}

Message Reader::read(const MessageRef& ref) const {
  const Reader& bag = *this;
  const std::string name = bag.path.string();
  const auto chunk_it = std::lower_bound(bag.chunks.begin(), bag.chunks.end(), ref.position,
                                         [](const Chunk& c, std::uint64_t pos) { return c.pos < pos; });
  if (chunk_it == bag.chunks.end() || chunk_it->pos != ref.position)
    throw InputError(name, "no chunk starts at byte " + std::to_string(ref.position));
  const auto chunk = static_cast<std::uint32_t>(chunk_it - bag.chunks.begin());
  std::string why;
  std::lock_guard lock(bag.mutex);
  if (bag.cached_chunk != chunk) {
    bag.cached_chunk = UINT32_MAX;
    BagFile file(bag.path);
    if (!file.ok() || !bag.loadChunk(file, *chunk_it, bag.cached_bytes, why))
      throw InputError(name, "the chunk at byte " + std::to_string(ref.position) + " cannot be read (" + why + ")");
    bag.cached_chunk = chunk;
  }
  ChunkMessage found;
  if (ref.offset > UINT32_MAX || !messageAt(bag.cached_bytes, ref.offset, found, why))
    throw InputError(name, "no message at offset " + std::to_string(ref.offset) + " of the chunk at byte " +
                               std::to_string(ref.position) + (why.empty() ? "" : " (" + why + ")"));
  const auto topic = bag.conn_topic.find(found.conn);
  if (topic == bag.conn_topic.end())
    throw InputError(name, "the message at offset " + std::to_string(ref.offset) + " of the chunk at byte " +
                               std::to_string(ref.position) + " is on an unknown connection");
  Message message;
  message.topic = topic->second;
  message.log_time_ns = found.time_ns;
  message.ref = ref;
  message.encoding = Encoding::kRos1;
  message.bytes = std::make_shared<const std::vector<std::uint8_t>>(found.data.begin(), found.data.end());
  return message;
}

}  // namespace ros1bag

struct Ros1Bag::Impl : ros1bag::Reader {};

Ros1Bag::Ros1Bag(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Ros1Bag::~Ros1Bag() = default;

std::unique_ptr<Ros1Bag> Ros1Bag::open(const std::filesystem::path& file) {
  auto impl = std::make_unique<Impl>();
  impl->path = file;
  ros1bag::BagFile bag(file);
  impl->open(bag);
  return std::unique_ptr<Ros1Bag>(new Ros1Bag(std::move(impl)));
}

std::string Ros1Bag::describe() const { return impl_->describe(); }
const std::filesystem::path& Ros1Bag::path() const { return impl_->path; }
const std::vector<Topic>& Ros1Bag::topics() const { return impl_->topics; }

ScanEnd Ros1Bag::scan(const std::vector<int>& topics, const std::function<bool(const Message&)>& visit) const {
  return impl_->scan(topics, {}, visit);
}

ScanEnd Ros1Bag::scanHeads(const std::vector<int>& topics, const std::vector<int>& heads,
                           const std::function<bool(const Message&)>& visit) const {
  return impl_->scan(topics, heads, visit);
}

Message Ros1Bag::read(const MessageRef& ref) const { return impl_->read(ref); }

}  // namespace vdmap::ros
