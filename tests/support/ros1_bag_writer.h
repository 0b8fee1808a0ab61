#pragma once
// ROS 1 bags written in tests: the bag format 2.0 as rosbag writes it, messages in ROS 1
// serialisation, and a small recording laid out as the TUM RGB-D benchmark's bags.
#include <bzlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdmap::test {

/// A message to write: its connection, log time and serialised bytes.
struct BagMessage {
  std::uint32_t conn = 0;
  std::int64_t time_ns = 0;
  std::vector<std::uint8_t> bytes;
};
struct BagConnection {
  std::uint32_t id = 0;
  std::string topic, type;
};

/// Bag format 2.0 as rosbag writes it (http://wiki.ros.org/Bags/Format/2.0), small.
class BagWriter {
 public:
  /// A bag of `chunks` (each with `compression`: "none" or "bz2"), indexed unless `indexed` is false
  /// (then as a recorder leaves it when it stops without closing the bag).
  static std::string write(const std::vector<BagConnection>& connections,
                           const std::vector<std::vector<BagMessage>>& chunks, const std::string& compression,
                           bool indexed = true) {
    std::string out = "#ROSBAG V2.0\n";
    const std::size_t header_pos = out.size();
    out += bagHeader(0, connections.size(), chunks.size());
    struct ChunkInfo {
      std::uint64_t pos;
      std::int64_t start, end;
      std::map<std::uint32_t, std::vector<std::pair<std::int64_t, std::uint32_t>>> index;  // conn -> (time, offset)
    };
    std::vector<ChunkInfo> infos;
    for (const auto& messages : chunks) {
      ChunkInfo info{out.size(), INT64_MAX, INT64_MIN, {}};
      std::string inner;
      for (const BagMessage& m : messages) {
        if (!info.index.contains(m.conn)) inner += connectionRecord(connections, m.conn);
        info.index[m.conn].emplace_back(m.time_ns, static_cast<std::uint32_t>(inner.size()));
        inner += record({field("op", u8(2)), field("conn", u32(m.conn)), field("time", time(m.time_ns))},
                        std::string(m.bytes.begin(), m.bytes.end()));
        info.start = std::min(info.start, m.time_ns);
        info.end = std::max(info.end, m.time_ns);
      }
      out += record({field("op", u8(5)), field("compression", compression), field("size", u32(inner.size()))},
                    compress(inner, compression));
      for (const auto& [conn, entries] : info.index) {
        std::string data;
        for (const auto& [t, offset] : entries) data += time(t) + u32(offset);
        out += record(
            {field("op", u8(4)), field("ver", u32(1)), field("conn", u32(conn)), field("count", u32(entries.size()))},
            data);
      }
      infos.push_back(std::move(info));
    }
    if (!indexed) return out;
    const std::uint64_t index_pos = out.size();
    for (const BagConnection& c : connections) out += connectionRecord(connections, c.id);
    for (const ChunkInfo& info : infos) {
      std::string data;
      for (const auto& [conn, entries] : info.index) data += u32(conn) + u32(entries.size());
      out += record({field("op", u8(6)), field("ver", u32(1)), field("chunk_pos", u64(info.pos)),
                     field("start_time", time(info.start)), field("end_time", time(info.end)),
                     field("count", u32(info.index.size()))},
                    data);
    }
    out.replace(header_pos, bagHeader(0, 0, 0).size(), bagHeader(index_pos, connections.size(), chunks.size()));
    return out;
  }

 private:
  template <typename T>
  static std::string bytesOf(T value) {
    return std::string(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  static std::string u8(std::uint8_t v) { return bytesOf(v); }
  static std::string u32(std::size_t v) { return bytesOf(static_cast<std::uint32_t>(v)); }
  static std::string u64(std::uint64_t v) { return bytesOf(v); }
  static std::string time(std::int64_t ns) {
    return u32(static_cast<std::uint64_t>(ns) / 1'000'000'000) + u32(static_cast<std::uint64_t>(ns) % 1'000'000'000);
  }
  static std::string field(const std::string& name, const std::string& value) {
    return u32(name.size() + 1 + value.size()) + name + "=" + value;
  }
  static std::string record(const std::vector<std::string>& fields, const std::string& data) {
    std::string header;
    for (const std::string& f : fields) header += f;
    return u32(header.size()) + header + u32(data.size()) + data;
  }
  /// The bag header record, padded to 4096 bytes as rosbag pads it (so it can be rewritten in place).
  static std::string bagHeader(std::uint64_t index_pos, std::size_t conns, std::size_t chunks) {
    const std::string header = field("op", u8(3)) + field("index_pos", u64(index_pos)) +
                               field("conn_count", u32(conns)) + field("chunk_count", u32(chunks));
    return u32(header.size()) + header + u32(4096 - 8 - header.size()) + std::string(4096 - 8 - header.size(), ' ');
  }
  static std::string connectionRecord(const std::vector<BagConnection>& connections, std::uint32_t id) {
    const auto c = std::find_if(connections.begin(), connections.end(), [&](const auto& x) { return x.id == id; });
    return record({field("op", u8(7)), field("conn", u32(id)), field("topic", c->topic)},
                  field("topic", c->topic) + field("type", c->type) + field("md5sum", "*"));
  }
  static std::string compress(const std::string& bytes, const std::string& compression) {
    if (compression != "bz2") return bytes;
    std::string out(bytes.size() + bytes.size() / 100 + 600, '\0');
    auto size = static_cast<unsigned>(out.size());
    if (BZ2_bzBuffToBuffCompress(out.data(), &size, const_cast<char*>(bytes.data()),
                                 static_cast<unsigned>(bytes.size()), 9, 0, 0) != BZ_OK)
      throw std::runtime_error("bz2 compression failed");
    out.resize(size);
    return out;
  }
};

/// A message in ROS 1 serialisation, field by field.
struct Ros1Bytes {
  std::vector<std::uint8_t> bytes;
  template <typename T>
  Ros1Bytes& put(T value) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
    return *this;
  }
  Ros1Bytes& text(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
    return *this;
  }
  Ros1Bytes& header(std::uint32_t sec, std::uint32_t nsec, const std::string& frame) {
    return put(std::uint32_t{7}).put(sec).put(nsec).text(frame);
  }
  Ros1Bytes& pose(double x, double y, double z, double qx, double qy, double qz, double qw) {
    return put(x).put(y).put(z).put(qx).put(qy).put(qz).put(qw);
  }
  Ros1Bytes& blob(const std::vector<std::uint8_t>& data) {
    put(static_cast<std::uint32_t>(data.size()));
    bytes.insert(bytes.end(), data.begin(), data.end());
    return *this;
  }
};

/// sensor_msgs/Image of `width` x `height` in `encoding` with rows of `step` bytes from `data`.
inline std::vector<std::uint8_t> imageMessage(double stamp, const std::string& frame, std::uint32_t width,
                                              std::uint32_t height, const std::string& encoding, std::uint32_t step,
                                              const std::vector<std::uint8_t>& data) {
  const auto sec = static_cast<std::uint32_t>(stamp);
  const auto nsec = static_cast<std::uint32_t>(std::llround((stamp - sec) * 1e9));
  return Ros1Bytes()
      .header(sec, nsec, frame)
      .put(height)
      .put(width)
      .text(encoding)
      .put(std::uint8_t{0})
      .put(step)
      .blob(data)
      .bytes;
}

/// sensor_msgs/CameraInfo of a pinhole camera without distortion.
inline std::vector<std::uint8_t> cameraInfoMessage(double stamp, const std::string& frame, std::uint32_t width,
                                                   std::uint32_t height, double f, double cx, double cy) {
  const auto sec = static_cast<std::uint32_t>(stamp);
  const auto nsec = static_cast<std::uint32_t>(std::llround((stamp - sec) * 1e9));
  Ros1Bytes m;
  m.header(sec, nsec, frame).put(height).put(width).text("plumb_bob").put(std::uint32_t{0});
  for (const double k : {f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0}) m.put(k);
  for (const double r : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) m.put(r);
  for (const double p : {f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0}) m.put(p);
  m.put(std::uint32_t{0}).put(std::uint32_t{0});  // binning
  m.put(std::uint32_t{0})
      .put(std::uint32_t{0})
      .put(std::uint32_t{0})
      .put(std::uint32_t{0})
      .put(std::uint8_t{0});  // roi
  return m.bytes;
}

/// tf2_msgs/TFMessage with one transform: `child` in `parent` at (x, y, z), unrotated.
inline std::vector<std::uint8_t> tfMessage(double stamp, const std::string& parent, const std::string& child, double x,
                                           double y, double z) {
  const auto sec = static_cast<std::uint32_t>(stamp);
  const auto nsec = static_cast<std::uint32_t>(std::llround((stamp - sec) * 1e9));
  return Ros1Bytes().put(std::uint32_t{1}).header(sec, nsec, parent).text(child).pose(x, y, z, 0, 0, 0, 1).bytes;
}

/// A recording as the TUM RGB-D benchmark's bags lay it out, small: `frames` depth images
/// (16UC1 millimetres, 1.5 m everywhere) and rgb8 colour images of width x height, 0.1 s apart from
/// 100 s, each with its camera_info on /camera/depth/camera_info and /camera/rgb/camera_info, and
/// /tf world -> camera moving 1 cm along x a frame. Change `messages` before writing it with
/// write().
struct TinyRecording {
  std::vector<BagConnection> connections = {{0, "/camera/depth/image", "sensor_msgs/Image"},
                                            {1, "/camera/rgb/image_color", "sensor_msgs/Image"},
                                            {2, "/camera/depth/camera_info", "sensor_msgs/CameraInfo"},
                                            {3, "/camera/rgb/camera_info", "sensor_msgs/CameraInfo"},
                                            {4, "/tf", "tf2_msgs/TFMessage"}};
  std::vector<BagMessage> messages;

  explicit TinyRecording(int frames = 3, std::uint32_t width = 32, std::uint32_t height = 24) {
    const std::vector<std::uint8_t> depth = [&] {
      std::vector<std::uint8_t> d;
      for (std::uint32_t i = 0; i < width * height; ++i) d.insert(d.end(), {0xDC, 0x05});  // 1500 mm
      return d;
    }();
    const std::vector<std::uint8_t> rgb(width * height * 3, 128);
    const double f = width * 0.8;
    for (int i = 0; i < frames; ++i) {
      const double t = 100.0 + 0.1 * i;
      const auto ns = static_cast<std::int64_t>(std::llround(t * 1e9));
      messages.push_back({4, ns, tfMessage(t, "world", "camera", 0.01 * i, 0, 0)});
      messages.push_back({2, ns, cameraInfoMessage(t, "camera", width, height, f, width / 2.0, height / 2.0)});
      messages.push_back({3, ns, cameraInfoMessage(t, "camera", width, height, f, width / 2.0, height / 2.0)});
      messages.push_back({0, ns, imageMessage(t, "camera", width, height, "16UC1", width * 2, depth)});
      messages.push_back({1, ns, imageMessage(t, "camera", width, height, "rgb8", width * 3, rgb)});
    }
  }

  /// The messages on `topic` (indices into messages).
  std::vector<std::size_t> on(const std::string& topic) const {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < messages.size(); ++i)
      if (connections[messages[i].conn].topic == topic) out.push_back(i);
    return out;
  }

  /// The bag's bytes: one uncompressed chunk, indexed.
  std::string write() const { return BagWriter::write(connections, {messages}, "none"); }
};

}  // namespace vdmap::test
