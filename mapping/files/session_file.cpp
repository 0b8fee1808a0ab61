#include "mapping/files/session_file.h"
#include "mapping/io/text_list.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>

#include <zlib.h>

#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/pipeline/parameters.h"

namespace vdmap {
namespace {

// A new field in these structs must be added to the file (and the version raised): these
// sizes are a tripwire for that, not a layout promise.
static_assert(sizeof(MapperParams) == 112, "MapperParams changed: store the new field in the .vdmap file");
static_assert(sizeof(GlobalMapParams) == 88, "GlobalMapParams changed: store the new field in the .vdmap file");
static_assert(sizeof(StoredCell) == 56, "StoredCell changed: store the new field in the .vdmap file");
static_assert(sizeof(MapperState) == 400, "MapperState changed: store the new field in the .vdmap file");
static_assert(sizeof(LoopClosure) == 32,
              "LoopClosure changed: store the new field in the .vdmap file (not a wall time)");

constexpr char kMagic[8] = {'V', 'D', 'M', 'A', 'P', 'S', 'E', 'S'};
constexpr std::uint32_t kEndianMark = 0x01020304;  // written little-endian: 04 03 02 01
constexpr std::size_t kHeaderBytes = 24;           // magic, version, endianness, sections, crc
constexpr std::size_t kSectionHeaderBytes = 16;    // tag, payload length (u64), crc
constexpr std::array<char, 4> kParams = {'P', 'A', 'R', 'M'};
constexpr std::array<char, 4> kState = {'M', 'S', 'T', 'A'};  // version >= 2
constexpr std::size_t kMaxSequencePathBytes = 4096;
constexpr std::array<char, 4> kKeyframe = {'K', 'F', 'R', 'M'};
constexpr std::array<char, 4> kEdges = {'E', 'D', 'G', 'E'};

constexpr std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = makeCrcTable();

// Little-endian encoding of the file's fields, whatever the host's byte order.
class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u16(std::uint16_t v) { little(v); }
  void u32(std::uint32_t v) { little(v); }
  void i32(std::int32_t v) { little(static_cast<std::uint32_t>(v)); }
  void u64(std::uint64_t v) { little(v); }
  void f32(float v) { little(std::bit_cast<std::uint32_t>(v)); }
  void f64(double v) { little(std::bit_cast<std::uint64_t>(v)); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void bytes(std::string_view b) { out_.append(b); }
  std::string& str() { return out_; }

 private:
  template <typename T>
  void little(T v) {
    for (std::size_t i = 0; i < sizeof(T); ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  std::string out_;
};

// Reads fields of one region of the file; every failure is an InputError naming the file and
// `where` (the header or a section).
class SessionReader {
 public:
  SessionReader(std::string_view data, const std::string& file, std::string where)
      : data_(data), file_(file), where_(std::move(where)) {}

  [[noreturn]] void fail(const std::string& what) const { throw InputError(file_, where_ + ": " + what); }
  std::size_t left() const { return data_.size() - pos_; }
  void setWhere(std::string where) { where_ = std::move(where); }
  /// A reader of other bytes (unpacked from this region) that names the same file and region.
  SessionReader over(std::string_view data) const { return SessionReader(data, file_, where_); }
  /// "FILE: WHERE", to name this region in another reader's errors.
  std::string context() const { return file_ + ": " + where_; }
  void need(std::uint64_t n, const char* what) const {
    if (n > left())
      fail(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " + std::to_string(left()) +
           " left");
  }
  std::string_view bytes(std::uint64_t n, const char* what) {
    need(n, what);
    const std::string_view b = data_.substr(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return b;
  }
  std::uint8_t u8(const char* what) { return static_cast<std::uint8_t>(bytes(1, what)[0]); }
  std::uint16_t u16(const char* what) { return little<std::uint16_t>(what); }
  std::uint32_t u32(const char* what) { return little<std::uint32_t>(what); }
  std::int32_t i32(const char* what) { return static_cast<std::int32_t>(little<std::uint32_t>(what)); }
  std::uint64_t u64(const char* what) { return little<std::uint64_t>(what); }
  float f32(const char* what) {
    const float v = std::bit_cast<float>(little<std::uint32_t>(what));
    if (!std::isfinite(v)) fail(std::string(what) + " is not a finite number");
    return v;
  }
  double f64(const char* what) {
    const double v = std::bit_cast<double>(little<std::uint64_t>(what));
    if (!std::isfinite(v)) fail(std::string(what) + " is not a finite number");
    return v;
  }
  bool boolean(const char* what) {
    const std::uint8_t v = u8(what);
    if (v > 1) fail(std::string(what) + " must be 0 or 1, not " + std::to_string(v));
    return v == 1;
  }
  /// A count of records of `record_bytes` each that must fit in what is left.
  std::uint32_t count(std::uint64_t record_bytes, const char* what) {
    const std::uint32_t n = u32(what);
    need(n * record_bytes, what);
    return n;
  }
  void check(bool ok, const std::string& what) const {
    if (!ok) fail(what);
  }
  /// Runs a validate() that throws std::invalid_argument, as an InputError.
  template <typename Validate>
  void checkValid(const char* what, Validate validate) const {
    try {
      validate();
    } catch (const std::invalid_argument& e) {
      fail(std::string(what) + ": " + e.what());
    }
  }
  void expectEnd() const {
    if (left() != 0) fail(std::to_string(left()) + " unexpected bytes at the end");
  }

 private:
  template <typename T>
  T little(const char* what) {
    const std::string_view b = bytes(sizeof(T), what);
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<std::uint8_t>(b[i])) << (8 * i);
    return v;
  }

  std::string_view data_;
  std::size_t pos_ = 0;
  const std::string& file_;
  std::string where_;
};

void writeSection(const ByteSink& sink, const std::array<char, 4>& tag, const std::string& payload) {
  Writer head;
  head.bytes({tag.data(), tag.size()});
  head.u64(payload.size());
  const std::uint32_t crc = crc32(payload, crc32(head.str()));
  head.u32(crc);
  sink(head.str());
  sink(payload);
}

// --- parameters -------------------------------------------------------------------------------
// The parameter fields come from the parameter table (storedParameters(), in the file's order);
// the camera before them, the pose source after the mapper's, the counts at the end are this
// file's own.

void writeStored(Writer* w, const ParameterValues& values, bool live) {
  for (const StoredParameter& s : storedParameters(live)) {
    const double v = s.parameter->get(values);
    switch (s.type) {
      case StoredParameter::Type::kI32: w->i32(static_cast<std::int32_t>(v)); break;
      case StoredParameter::Type::kU32: w->u32(static_cast<std::uint32_t>(v)); break;
      case StoredParameter::Type::kF64: w->f64(v); break;
      case StoredParameter::Type::kBool: w->boolean(v != 0); break;
    }
  }
}

void writeMapperParams(Writer* w, const MapperParams& m) {
  writeStored(w, {m, {}}, /*live=*/false);
  w->u32(static_cast<std::uint32_t>(m.poses));
}

void writeParams(Writer* w, const SessionInfo& info, std::size_t keyframes) {
  const PinholeCamera& c = info.camera;
  w->i32(c.width);
  w->i32(c.height);
  for (double v : {c.fx, c.fy, c.cx, c.cy, c.depth_scale}) w->f64(v);
  writeMapperParams(w, info.mapper);
  writeStored(w, {{}, info.global}, /*live=*/true);
  w->i32(info.state.frames_mapped);
  w->i32(info.state.revisits);
  w->u32(static_cast<std::uint32_t>(keyframes));
}

double readField(SessionReader* r, const StoredParameter& s) {
  switch (s.type) {
    case StoredParameter::Type::kI32: return r->i32(s.name);
    case StoredParameter::Type::kU32: {
      const std::uint32_t v = r->u32(s.name);
      r->check(v < s.parameter->choices.size(), "unknown " + std::string(s.name) + " " + std::to_string(v));
      return v;
    }
    case StoredParameter::Type::kF64: return r->f64(s.name);
    case StoredParameter::Type::kBool: return r->boolean(s.name);
  }
  return 0;
}

// Reads the fields of storedParameters(live) into `values`; a field newer than the file gets the
// value such files were made with. `after_each` checks a field as soon as it is read.
template <typename Check>
void readStored(SessionReader* r, std::uint32_t version, bool live, ParameterValues* values, Check after_each) {
  for (const StoredParameter& s : storedParameters(live)) {
    if (version < s.since_version) {
      if (s.older) s.parameter->set(*values, *s.older);
      continue;
    }
    s.parameter->set(*values, readField(r, s));
    after_each(*s.parameter);
  }
}

std::uint32_t readParams(SessionReader* r, std::uint32_t version, SessionInfo* info) {
  PinholeCamera& c = info->camera;
  c.width = r->i32("camera width");
  c.height = r->i32("camera height");
  c.fx = r->f64("fx");
  c.fy = r->f64("fy");
  c.cx = r->f64("cx");
  c.cy = r->f64("cy");
  c.depth_scale = r->f64("depth_scale");
  r->checkValid("camera", [&c] { c.validate(); });  // also bounds the image size
  ParameterValues values{info->mapper, info->global};
  const Parameter* cell_size = findParameter("cell_size");
  readStored(r, version, /*live=*/false, &values, [&](const Parameter& p) {
    // The one field bounded by a value outside the table (the camera's image): checked as soon as
    // it is read, so a file with a bad one says so whatever follows it.
    if (&p == cell_size)
      r->check(values.mapper.local_map.cell_size_px >= 1 &&
                   values.mapper.local_map.cell_size_px <= std::min(c.width, c.height),
               "cell_size_px must be within 1..min(width, height)");
  });
  MapperParams& m = values.mapper;
  if (version >= 4) {  // sessions before version 4 were all mapped with ground-truth poses
    const std::uint32_t poses = r->u32("pose source");
    r->check(poses <= static_cast<std::uint32_t>(PoseSource::kTrack), "unknown pose source " + std::to_string(poses));
    m.poses = static_cast<PoseSource>(poses);
  }
  r->checkValid("mapper parameters", [&m] { m.validate(); });
  readStored(r, version, /*live=*/true, &values, [](const Parameter&) {});
  const GlobalMapParams& g = values.global;
  r->checkValid("global map", [&g] { g.validate(); });
  info->mapper = values.mapper;
  info->global = values.global;
  info->state.frames_mapped = r->i32("frames_mapped");
  info->state.revisits = r->i32("revisits");
  r->check(info->state.frames_mapped >= 0 && info->state.revisits >= 0, "frame and revisit counts must be >= 0");
  const std::uint32_t keyframes = r->u32("keyframe count");
  r->expectEnd();
  return keyframes;
}

// --- mapper state (version >= 2) ------------------------------------------------------------

constexpr std::uint64_t kTransformBytes = 12 * 8;  // the top three rows, row by row

void writeTransform(Writer* w, const Transform& T) {
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) w->f64(T.matrix()(row, col));
}

Transform readTransform(SessionReader* r, const char* what) {
  Transform T = Transform::Identity();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) T.matrix()(row, col) = r->f64(what);
  r->check(isValidTransform(T), std::string(what) + " is not a rigid transform");
  return T;
}

void writeState(Writer* w, const SessionInfo& info) {
  w->i32(info.state.current_keyframe);
  w->i32(info.state.last_frame_index);
  w->f64(info.state.last_timestamp);
  w->u32(static_cast<std::uint32_t>(info.sequence.size()));
  w->bytes(info.sequence);
  const MapperState& s = info.state;
  w->i32(s.frames_lost);
  w->u32(static_cast<std::uint32_t>(s.frame_poses.size()));
  for (const FramePose& f : s.frame_poses) {
    w->i32(f.frame_index);
    w->f64(f.timestamp);
    w->i32(f.keyframe);
    writeTransform(w, f.T_K_C);
  }
  w->i32(s.tracker.keyframe);
  writeTransform(w, s.tracker.T_K_C);
  writeTransform(w, s.tracker.velocity);
  w->i32(s.tracker.frames_lost);
  w->u32(static_cast<std::uint32_t>(s.pose_graph_edges.size()));
  for (const PoseGraphEdge& e : s.pose_graph_edges) {
    w->i32(e.from);
    w->i32(e.to);
    writeTransform(w, e.T_from_to);
    for (int row = 0; row < 6; ++row)
      for (int col = row; col < 6; ++col) w->f64(e.information(row, col));
    w->boolean(e.robust);
  }
  w->u32(static_cast<std::uint32_t>(s.loops.size()));
  for (const LoopClosure& l : s.loops) {
    for (int v : {l.frame_index, l.from, l.to, l.inliers}) w->i32(v);
    w->f64(l.correction_m);  // not pose_graph_ms: a wall-clock time would make equal runs differ
  }
  w->i32(s.frames_weak);
  w->i32(s.frames_relocalised);
}

void readState(SessionReader* r, std::uint32_t version, SessionInfo* info, std::uint32_t keyframes) {
  MapperState& s = info->state;
  s.current_keyframe = r->i32("current keyframe");
  s.last_frame_index = r->i32("last frame index");
  s.last_timestamp = r->f64("last timestamp");
  const std::uint32_t n = r->count(1, "sequence folder");
  r->check(n <= kMaxSequencePathBytes, "sequence folder of " + std::to_string(n) + " bytes is too long");
  info->sequence = r->bytes(n, "sequence folder");
  r->check(info->sequence.find('\0') == std::string::npos, "sequence folder holds a NUL byte");
  if (version >= 4) {  // the trajectory, the tracker's and the pose graph's state
    s.frames_lost = r->i32("frames lost");
    const std::uint32_t poses = r->count(4 + 8 + 4 + kTransformBytes, "frame poses");
    s.frame_poses.resize(poses);
    for (FramePose& f : s.frame_poses) {
      f.frame_index = r->i32("frame index");
      f.timestamp = r->f64("frame timestamp");
      f.keyframe = r->i32("frame keyframe");
      f.T_K_C = readTransform(r, "frame pose");
    }
    s.tracker.keyframe = r->i32("tracker keyframe");
    s.tracker.T_K_C = readTransform(r, "tracker pose");
    s.tracker.velocity = readTransform(r, "tracker velocity");
    s.tracker.frames_lost = r->i32("tracker frames lost");
    const std::uint32_t edges = r->count(4 + 4 + kTransformBytes + 21 * 8 + 1, "pose-graph edges");
    s.pose_graph_edges.resize(edges);
    for (PoseGraphEdge& e : s.pose_graph_edges) {
      e.from = r->i32("edge from");
      e.to = r->i32("edge to");
      e.T_from_to = readTransform(r, "edge measurement");
      for (int row = 0; row < 6; ++row)
        for (int col = row; col < 6; ++col)
          e.information(row, col) = e.information(col, row) = r->f64("edge information");
      e.robust = r->boolean("edge robust");
    }
    // Versions 4 and 5 stored each optimisation's wall time: read and dropped, as version 6
    // stores none (a session is the same for the same input, whatever the machine's speed).
    const bool timed = version <= 5;
    const std::uint32_t loops = r->count(4 * 4 + (timed ? 2 : 1) * 8, "loop closures");
    s.loops.resize(loops);
    for (LoopClosure& l : s.loops) {
      for (int* v : {&l.frame_index, &l.from, &l.to, &l.inliers}) *v = r->i32("loop closure");
      l.correction_m = r->f64("loop correction");
      if (timed) r->f64("loop time");
    }
  }
  if (version >= 5) {  // the frames placed on a weak estimate, and those relocalised
    s.frames_weak = r->i32("frames weak");
    s.frames_relocalised = r->i32("frames relocalised");
  }
  r->checkValid("mapper state", [&] { s.validate(keyframes); });
  r->expectEnd();
}

// --- keyframes --------------------------------------------------------------------------------
// Version 6 keeps each image as the PNG or JPEG file the keyframe holds, and packs the keypoints,
// descriptors and cells with zlib, their records split into byte planes; versions 1-5 stored
// the pixels and the records as they are.

constexpr std::size_t kKeypointBytes = 32;  // one record: f32 x, y, size, angle, response, i32 octave, class, f32 depth
constexpr std::size_t kCellBytes = 56;      // f32 mean[3], scatter[6], colour[3], u32 n, i32 grid index
// zlib's level for the packed records: 9 packs barely tighter than 6 and takes much longer.
constexpr int kPackLevel = 6;
// Deflate never packs more than 1032 bytes into one, so a packed length bounds what a
// damaged count may make the reader allocate.
constexpr std::uint64_t kMaxInflation = 1032;

/// The records of a table, `record_bytes` each, by byte planes: byte b of record i goes to
/// b * n + i. Fields of neighbouring records share their high bytes (exponents, signs, small
/// counts), which zlib then finds next to each other.
std::string toPlanes(std::string_view records, std::size_t record_bytes) {
  const std::size_t n = records.size() / record_bytes;
  std::string planes(records.size(), '\0');
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t b = 0; b < record_bytes; ++b) planes[b * n + i] = records[i * record_bytes + b];
  return planes;
}

std::string fromPlanes(std::string_view planes, std::size_t record_bytes) {
  const std::size_t n = planes.size() / record_bytes;
  std::string records(planes.size(), '\0');
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t b = 0; b < record_bytes; ++b) records[i * record_bytes + b] = planes[b * n + i];
  return records;
}

std::string pack(std::string_view raw) {
  uLongf packed_bytes = compressBound(raw.size());
  std::string packed(packed_bytes, '\0');
  if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_bytes, reinterpret_cast<const Bytef*>(raw.data()),
                raw.size(), kPackLevel) != Z_OK)
    throw std::runtime_error("zlib could not pack a keyframe's features and cells");
  packed.resize(packed_bytes);
  return packed;
}

/// The `raw_bytes` bytes the zlib stream `packed` holds, which must be all of it.
std::string unpack(const SessionReader& r, std::string_view packed, std::uint64_t raw_bytes, const char* what) {
  r.check(raw_bytes <= kMaxInflation * packed.size() + 64, std::string(what) + ": " + std::to_string(packed.size()) +
                                                               " packed bytes cannot hold " +
                                                               std::to_string(raw_bytes));
  std::string raw(static_cast<std::size_t>(raw_bytes), '\0');
  uLongf out = raw.size();
  uLong in = packed.size();
  const int rc =
      uncompress2(reinterpret_cast<Bytef*>(raw.data()), &out, reinterpret_cast<const Bytef*>(packed.data()), &in);
  r.check(rc == Z_OK && out == raw.size() && in == packed.size(), std::string(what) + ": not a zlib stream of " +
                                                                      std::to_string(raw_bytes) + " bytes (" +
                                                                      (rc == Z_OK ? "other length" : zError(rc)) + ")");
  return raw;
}

void writeImage(Writer* w, const CompressedImage& image) {
  w->i32(image.rows());
  w->i32(image.cols());
  w->i32(image.type());
  if (image.empty()) return;
  w->u8(image.swappedRedBlue() ? 1 : 0);
  w->u32(static_cast<std::uint32_t>(image.encoded().size()));
  w->bytes(image.encoded());
}

/// Checks an image's header (h, w, t): either empty (0 x 0, of `type` or CV_8UC1) or of `type`
/// and rows x cols (cols -1: any column count in 1..1024). True when it is not empty.
bool checkImageHeader(const SessionReader& r, int h, int w, int t, int type, int rows, int cols, const char* what) {
  if (h == 0 && w == 0) {
    r.check(t == type || t == CV_8UC1, std::string(what) + ": unexpected type of an empty image");
    return false;
  }
  r.check(t == type, std::string(what) + ": type " + std::to_string(t) + ", expected " + std::to_string(type));
  r.check(h == rows && (cols < 0 ? w >= 1 && w <= 1024 : w == cols),
          std::string(what) + ": size " + std::to_string(w) + "x" + std::to_string(h) + " does not fit");
  return true;
}

/// Version 6: an image's file, decoded here once so that a session that loads never fails to show one.
CompressedImage readImage(SessionReader* r, int type, const PinholeCamera& camera, const char* what, bool decode) {
  const int h = r->i32(what), w = r->i32(what), t = r->i32(what);
  if (!checkImageHeader(*r, h, w, t, type, camera.height, camera.width, what))
    return CompressedImage::fromEncoded(0, 0, t, {}, false);
  const std::uint8_t swapped = r->u8(what);
  r->check(swapped <= (type == CV_8UC3 ? 1 : 0),
           std::string(what) + ": red and blue swapped must be " + (type == CV_8UC3 ? "0 or 1" : "0"));
  const std::uint32_t n = r->count(1, what);
  CompressedImage image = CompressedImage::fromEncoded(h, w, t, std::string(r->bytes(n, what)), swapped == 1);
  if (decode) image.decode(r->context() + ": " + what);
  return image;
}

/// Versions 1-5: an image of `type` that is either empty or rows x cols (cols -1: any column count).
cv::Mat readMat(SessionReader* r, int type, int rows, int cols, const char* what) {
  const int h = r->i32(what), w = r->i32(what), t = r->i32(what);
  if (!checkImageHeader(*r, h, w, t, type, rows, cols, what)) return cv::Mat(0, 0, t);
  cv::Mat m(h, w, type);
  if (m.empty()) return m;  // no rows (descriptors of no keypoints): m.data is null
  const std::uint64_t bytes = static_cast<std::uint64_t>(m.total()) * m.elemSize();
  const std::string_view b = r->bytes(bytes, what);
  if (m.depth() == CV_8U) {
    std::memcpy(m.data, b.data(), b.size());
  } else {
    auto* p = reinterpret_cast<std::uint16_t*>(m.data);
    for (std::size_t i = 0; i < b.size() / 2; ++i)
      p[i] = static_cast<std::uint16_t>(static_cast<std::uint8_t>(b[2 * i]) | static_cast<std::uint8_t>(b[2 * i + 1])
                                                                                  << 8);
  }
  return m;
}

void writeKeypoints(Writer* w, const FrameFeatures& f) {
  for (std::size_t i = 0; i < f.keypoints.size(); ++i) {
    const cv::KeyPoint& p = f.keypoints[i];
    for (float v : {p.pt.x, p.pt.y, p.size, p.angle, p.response}) w->f32(v);
    w->i32(p.octave);
    w->i32(p.class_id);
    w->f32(f.depth_m[i]);
  }
}

void readKeypoints(SessionReader* r, std::uint32_t n, FrameFeatures* f) {
  f->keypoints.resize(n);
  f->depth_m.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    cv::KeyPoint& p = f->keypoints[i];
    p.pt.x = r->f32("keypoint x");
    p.pt.y = r->f32("keypoint y");
    p.size = r->f32("keypoint size");
    p.angle = r->f32("keypoint angle");
    p.response = r->f32("keypoint response");
    p.octave = r->i32("keypoint octave");
    p.class_id = r->i32("keypoint class");
    f->depth_m[i] = r->f32("keypoint depth");
    r->check(f->depth_m[i] >= 0, "keypoint depth must be >= 0");
  }
}

void writeCells(Writer* w, const KeyframeContainer& container) {
  for (const StoredCell& c : container.cells()) {
    for (float v : c.mean) w->f32(v);
    for (float v : c.scatter) w->f32(v);
    for (float v : c.color) w->f32(v);
    w->u32(c.n);
    w->i32(c.grid_index);
  }
}

void readCells(SessionReader* r, std::uint32_t cells, KeyframeContainer* container) {
  const int grid = container->cols() * container->rows();
  for (std::uint32_t i = 0; i < cells; ++i) {
    StoredCell c;
    for (float& v : c.mean) v = r->f32("cell mean");
    for (float& v : c.scatter) v = r->f32("cell scatter");
    for (float& v : c.color) v = r->f32("cell colour");
    c.n = r->u32("cell count");
    c.grid_index = r->i32("cell index");
    r->check(c.n >= 1, "a stored cell must hold at least one point");
    r->check(c.grid_index >= 0 && c.grid_index < grid,
             "cell index " + std::to_string(c.grid_index) + " outside the container's " + std::to_string(grid));
    r->check(container->find(c.grid_index) == nullptr, "cell " + std::to_string(c.grid_index) + " stored twice");
    container->findOrCreate(c.grid_index) = c;
  }
}

// --- the integrated frames' free space (version >= 7) ------------------------------------------
// Their poses, then every frame's blocks (u16 each) in one zlib stream, by byte planes.

void writeFramesFree(Writer* w, const std::vector<FrameFreeSpace>& frames) {
  w->u32(static_cast<std::uint32_t>(frames.size()));
  Writer blocks;
  for (const FrameFreeSpace& f : frames) {
    writeTransform(w, f.T_K_C);
    for (std::uint16_t b : f.near_mm) blocks.u16(b);
  }
  if (frames.empty()) return;
  const std::string packed = pack(toPlanes(blocks.str(), 2));
  w->u32(static_cast<std::uint32_t>(packed.size()));
  w->bytes(packed);
}

void readFramesFree(SessionReader* r, const PinholeCamera& camera, int frames_integrated,
                    std::vector<FrameFreeSpace>* frames) {
  const std::uint32_t n = r->count(kTransformBytes, "frames' free space");
  r->check(n <= static_cast<std::uint32_t>(frames_integrated),
           std::to_string(n) + " frames' free space in a keyframe of " + std::to_string(frames_integrated) + " frames");
  frames->resize(n);
  for (FrameFreeSpace& f : *frames) f.T_K_C = readTransform(r, "free-space frame pose");
  if (n == 0) return;
  const int cols = (camera.width + kFreeBlockPx - 1) / kFreeBlockPx,
            rows = (camera.height + kFreeBlockPx - 1) / kFreeBlockPx;
  const std::uint64_t per_frame = static_cast<std::uint64_t>(cols) * rows;
  const std::uint32_t packed_bytes = r->count(1, "packed free-space blocks");
  const std::string raw = fromPlanes(unpack(*r, r->bytes(packed_bytes, "packed free-space blocks"),
                                            std::uint64_t{n} * per_frame * 2, "packed free-space blocks"),
                                     2);
  SessionReader blocks = r->over(raw);
  for (FrameFreeSpace& f : *frames) {
    f.cols = cols, f.rows = rows;
    f.near_mm.resize(per_frame);
    for (std::uint16_t& b : f.near_mm) b = blocks.u16("free-space block");
  }
}

void writeKeyframe(Writer* w, const Keyframe& k) {
  w->i32(k.id);
  w->i32(k.frame_index);
  w->f64(k.timestamp);
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) w->f64(k.T_W_K.matrix()(row, col));
  w->i32(k.frames_integrated);
  writeImage(w, k.rgb_image);
  writeImage(w, k.depth_image);
  const FrameFeatures& f = k.features;
  const cv::Mat descriptors = f.descriptors.isContinuous() ? f.descriptors : f.descriptors.clone();
  w->u32(static_cast<std::uint32_t>(f.keypoints.size()));
  w->i32(descriptors.rows);
  w->i32(descriptors.cols);
  w->i32(descriptors.type());
  w->u32(static_cast<std::uint32_t>(k.container.size()));
  Writer keypoints, cells;
  writeKeypoints(&keypoints, f);
  writeCells(&cells, k.container);
  std::string raw = toPlanes(keypoints.str(), kKeypointBytes);
  if (!descriptors.empty())
    raw.append(reinterpret_cast<const char*>(descriptors.data), descriptors.total() * descriptors.elemSize());
  raw += toPlanes(cells.str(), kCellBytes);
  const std::string packed = pack(raw);
  w->u32(static_cast<std::uint32_t>(packed.size()));
  w->bytes(packed);
  writeFramesFree(w, k.frames_free);
}

Keyframe readKeyframe(SessionReader* r, int id, const SessionInfo& info, std::uint32_t version,
                      const SessionDecodeOptions& options) {
  const bool decode_images = options.decode_images;
  const PinholeCamera& camera = info.camera;
  Keyframe k{id, 0,  0.0, Transform::Identity(),
             {}, {}, {},  KeyframeContainer(camera, info.mapper.local_map.cell_size_px),
             0,  {}};
  r->check(r->i32("keyframe id") == id, "keyframe ids must be 0, 1, 2, ... in order");
  k.frame_index = r->i32("frame index");
  r->check(k.frame_index >= 0, "frame index must be >= 0");
  k.timestamp = r->f64("timestamp");
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) k.T_W_K.matrix()(row, col) = r->f64("pose");
  r->check(isValidTransform(k.T_W_K), "pose is not a rigid transform");
  k.frames_integrated = r->i32("frames integrated");
  r->check(k.frames_integrated >= 0, "frames integrated must be >= 0");
  FrameFeatures& f = k.features;
  if (version >= 6) {
    k.rgb_image = readImage(r, CV_8UC3, camera, "rgb image", decode_images);
    k.depth_image = readImage(r, CV_16UC1, camera, "depth image", decode_images);
    const std::uint32_t n = r->u32("keypoint count");
    r->check(n <= static_cast<std::uint32_t>(std::numeric_limits<int>::max()),
             "keypoint count " + std::to_string(n) + " is too large");
    const int h = r->i32("descriptors"), w = r->i32("descriptors"), t = r->i32("descriptors");
    const bool described = checkImageHeader(*r, h, w, t, CV_8UC1, static_cast<int>(n), -1, "descriptors");
    const std::uint32_t cells = r->u32("cell count");
    const int grid = k.container.cols() * k.container.rows();
    r->check(cells <= static_cast<std::uint32_t>(grid),
             std::to_string(cells) + " cells in a container of " + std::to_string(grid));
    const std::uint64_t keypoint_bytes = std::uint64_t{n} * kKeypointBytes,
                        descriptor_bytes = described ? std::uint64_t(h) * static_cast<std::uint64_t>(w) : 0;
    const std::uint32_t packed_bytes = r->count(1, "packed features and cells");
    const std::string raw =
        unpack(*r, r->bytes(packed_bytes, "packed features and cells"),
               keypoint_bytes + descriptor_bytes + std::uint64_t{cells} * kCellBytes, "packed features and cells");
    const std::string_view rest(raw);
    const std::string keypoints = fromPlanes(rest.substr(0, keypoint_bytes), kKeypointBytes);
    SessionReader keypoint_reader = r->over(keypoints);
    readKeypoints(&keypoint_reader, n, &f);
    f.descriptors = cv::Mat(described ? h : 0, described ? w : 0, t);
    if (!f.descriptors.empty()) std::memcpy(f.descriptors.data, rest.data() + keypoint_bytes, descriptor_bytes);
    const std::string cell_records = fromPlanes(rest.substr(keypoint_bytes + descriptor_bytes), kCellBytes);
    SessionReader cell_reader = r->over(cell_records);
    readCells(&cell_reader, cells, &k.container);
  } else {
    k.rgb_image = CompressedImage(readMat(r, CV_8UC3, camera.height, camera.width, "rgb image"));
    k.depth_image = CompressedImage(readMat(r, CV_16UC1, camera.height, camera.width, "depth image"));
    readKeypoints(r, r->count(kKeypointBytes, "keypoints"), &f);
    f.descriptors = readMat(r, CV_8UC1, static_cast<int>(f.keypoints.size()), -1, "descriptors");
    readCells(r, r->count(kCellBytes, "cells"), &k.container);
  }
  r->check(f.keypoints.empty() || !f.descriptors.empty(), "keypoints without descriptors");
  if (version >= 7) readFramesFree(r, camera, k.frames_integrated, &k.frames_free);
  r->expectEnd();
  if (!options.keep_features) f = FrameFeatures{};
  if (!options.keep_images) {
    k.rgb_image = CompressedImage::fromEncoded(0, 0, CV_8UC3, {}, false);
    k.depth_image = CompressedImage::fromEncoded(0, 0, CV_16UC1, {}, false);
  }
  return k;
}

// --- covisibility edges -----------------------------------------------------------------------

void writeEdges(Writer* w, const CovisibilityGraph& edges) {
  const std::vector<CovisibilityEdge> list = edges.edges();
  w->u32(static_cast<std::uint32_t>(list.size()));
  for (const CovisibilityEdge& e : list) {
    w->i32(e.a);
    w->i32(e.b);
    w->f64(e.weight);
  }
}

void readEdges(SessionReader* r, KeyframeGraph* graph) {
  const int keyframes = static_cast<int>(graph->size());
  const std::uint32_t n = r->count(16, "edges");
  std::pair<int, int> previous{-1, -1};
  for (std::uint32_t i = 0; i < n; ++i) {
    const int a = r->i32("edge"), b = r->i32("edge");
    const double weight = r->f64("edge weight");
    r->check(a >= 0 && a < b && b < keyframes, "edge " + std::to_string(a) + "-" + std::to_string(b) +
                                                   " does not join two of the " + std::to_string(keyframes) +
                                                   " keyframes");
    r->check(std::pair{a, b} > previous, "edges must be sorted and unique");
    r->check(weight >= 0, "edge weight must be >= 0");
    previous = {a, b};
    graph->edges().strengthen(a, b, weight);
  }
  r->expectEnd();
}

}  // namespace

std::uint32_t crc32(std::string_view bytes, std::uint32_t crc) {
  crc = ~crc;
  for (char ch : bytes) crc = kCrcTable[(crc ^ static_cast<std::uint8_t>(ch)) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

SessionInfo sessionInfo(const Mapper& mapper, const GlobalMapParams& global, const std::filesystem::path& sequence) {
  std::error_code ec;
  const std::filesystem::path absolute = sequence.empty() ? sequence : std::filesystem::absolute(sequence, ec);
  return {mapper.camera(), mapper.params(), global, mapper.state(),
          (ec ? sequence : absolute).lexically_normal().string()};
}

bool sameMapperParams(const MapperParams& a, const MapperParams& b) {
  Writer wa, wb;
  writeMapperParams(&wa, a);
  writeMapperParams(&wb, b);
  return wa.str() == wb.str();
}

void encodeSession(const KeyframeGraph& graph, const SessionInfo& info, const ByteSink& sink) {
  Writer header;
  header.bytes({kMagic, sizeof(kMagic)});
  header.u32(kSessionFormatVersion);
  header.u32(kEndianMark);
  header.u32(static_cast<std::uint32_t>(graph.size() + 3));
  header.u32(crc32(header.str()));
  sink(header.str());

  Writer params;
  writeParams(&params, info, graph.size());
  writeSection(sink, kParams, params.str());
  info.state.validate(graph.size());  // a programming error otherwise: the reader would refuse the file
  if (info.sequence.size() > kMaxSequencePathBytes) throw std::invalid_argument("sequence folder path too long");
  Writer state;
  writeState(&state, info);
  writeSection(sink, kState, state.str());
  // One section at a time: the file is never held whole.
  for (const Keyframe& k : graph.keyframes()) {
    const PinholeCamera& c = k.container.camera();
    if (k.container.cellSizePx() != info.mapper.local_map.cell_size_px || c.width != info.camera.width ||
        c.height != info.camera.height || c.fx != info.camera.fx || c.fy != info.camera.fy || c.cx != info.camera.cx ||
        c.cy != info.camera.cy)
      throw std::invalid_argument("keyframe " + std::to_string(k.id) +
                                  ": its container does not use the session's camera and cell size");
    Writer w;
    writeKeyframe(&w, k);
    writeSection(sink, kKeyframe, w.str());
  }
  Writer edges;
  writeEdges(&edges, graph.edges());
  writeSection(sink, kEdges, edges.str());
}

std::string encodeSession(const KeyframeGraph& graph, const SessionInfo& info) {
  std::string file;
  encodeSession(graph, info, [&file](std::string_view piece) { file.append(piece); });
  return file;
}

void saveSession(const std::filesystem::path& file, const KeyframeGraph& graph, const SessionInfo& info) {
  writeFileAtomically(file, [&](const ByteSink& sink) { encodeSession(graph, info, sink); });
}

Session decodeSession(std::string_view bytes, const std::string& name, const SessionDecodeOptions& options) {
  SessionReader header(bytes.substr(0, std::min(bytes.size(), kHeaderBytes)), name, "header");
  const std::string_view magic = bytes.substr(0, std::min(bytes.size(), sizeof(kMagic)));
  if (magic != std::string_view(kMagic, magic.size()) || bytes.empty())
    throw InputError(name, "not a vdmap session file (wrong magic; expected it to start with 'VDMAPSES')");
  header.need(kHeaderBytes, "the file header");
  header.bytes(sizeof(kMagic), "magic");
  const std::uint32_t version = header.u32("format version");
  const std::uint32_t endian = header.u32("endianness mark");
  const std::uint32_t sections = header.u32("section count");
  const std::uint32_t header_crc = header.u32("header checksum");
  if (options.verify_checksums && header_crc != crc32(bytes.substr(0, kHeaderBytes - 4)))
    header.fail("checksum mismatch (the file is corrupted)");
  if (endian != kEndianMark)
    header.fail("byte order mark " + std::to_string(endian) + ": not a little-endian vdmap file");
  if (version > kSessionFormatVersion)
    header.fail("format version " + std::to_string(version) + " is newer than this vdmap reads (" +
                std::to_string(kSessionFormatVersion) + "); update vdmap");
  if (version == 0) header.fail("format version 0 does not exist");

  // Sections: the checksum of each is verified before its payload is parsed. Version 1 has no
  // state section: PARM, KFRM..., EDGE.
  const std::uint32_t fixed_sections = version >= 2 ? 3 : 2;  // all but the keyframes
  if (sections < fixed_sections)
    header.fail("a session has at least " + std::to_string(fixed_sections) + " sections, the header says " +
                std::to_string(sections));
  const std::uint32_t first_keyframe = version >= 2 ? 2 : 1;
  SessionReader body(bytes.substr(kHeaderBytes), name, "file");
  Session session;
  session.info.format_version = version;
  std::uint32_t keyframes = 0;
  for (std::uint32_t s = 0; s < sections; ++s) {
    const std::array<char, 4>& expected = s == 0               ? kParams
                                          : s + 1 == sections  ? kEdges
                                          : s < first_keyframe ? kState
                                                               : kKeyframe;
    const std::string where = "section " + std::to_string(s) + " " + printable({expected.data(), 4});
    body.setWhere(where);
    const std::string_view head = body.bytes(kSectionHeaderBytes, "the section header");
    SessionReader section_header(head, name, where);
    const std::string_view tag = section_header.bytes(4, "tag");
    const std::uint64_t length = section_header.u64("length");
    const std::uint32_t crc = section_header.u32("checksum");
    if (tag != std::string_view(expected.data(), 4))
      body.fail("found tag " + printable(tag) + " (the file is corrupted or the section count is wrong)");
    const std::string_view payload = body.bytes(length, "the section");
    if (options.verify_checksums && crc != crc32(payload, crc32(head.substr(0, 12))))
      body.fail("checksum mismatch (the file is corrupted)");
    SessionReader r(payload, name, where);
    if (s == 0) {
      keyframes = readParams(&r, version, &session.info);
      if (sections != keyframes + std::uint64_t{fixed_sections})
        r.fail(std::to_string(keyframes) + " keyframes need " +
               std::to_string(keyframes + std::uint64_t{fixed_sections}) + " sections, the header says " +
               std::to_string(sections));
    } else if (s + 1 == sections) {
      readEdges(&r, &session.graph);
    } else if (s < first_keyframe) {
      readState(&r, version, &session.info, keyframes);
    } else {
      session.graph.add(readKeyframe(&r, static_cast<int>(s - first_keyframe), session.info, version, options));
    }
  }
  body.setWhere("file");
  body.expectEnd();
  return session;
}

bool isSessionFile(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return false;
  std::ifstream in(file, std::ios::binary);
  char magic[sizeof(kMagic)] = {};
  return in.read(magic, sizeof magic) && std::equal(magic, magic + sizeof magic, kMagic);
}

bool isSessionPath(const std::filesystem::path& file) {
  std::error_code ec;
  return isSessionFile(file) || (file.extension() == ".vdmap" && std::filesystem::is_regular_file(file, ec));
}

Session loadSession(const std::filesystem::path& file, const SessionDecodeOptions& options) {
  checkNotAFolder(file);
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(file.string(), "cannot open the session file");
  // Read at its size in one piece: growing a string char by char held up to three times the file.
  const std::streamoff size = in.tellg();
  std::string bytes(static_cast<std::size_t>(std::max<std::streamoff>(0, size)), '\0');
  in.seekg(0);
  if (size < 0 || !in.read(bytes.data(), size)) throw InputError(file.string(), "cannot read the session file");
  if (file.extension() == ".vdmap" && bytes.compare(0, sizeof(kMagic), std::string_view(kMagic, sizeof(kMagic))) != 0)
    throw InputError(file.string(), bytes.empty()
                                        ? "a damaged session file: it is empty (wrong magic)"
                                        : "a damaged session file: it does not start with 'VDMAPSES' (wrong magic)");
  return decodeSession(bytes, file.string(), options);
}

cv::Mat keyframeImage(const Keyframe& k, const std::string& session) {
  return k.rgb_image.decode(session + ": keyframe " + std::to_string(k.id) + ": rgb image");
}

}  // namespace vdmap
