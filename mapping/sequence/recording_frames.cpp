// A ROS 1 bag's or an MCAP's frames (detail/listing.h): the topics chosen, one pass over them
// for stamps, camera_info and tf, then each frame decoded from its messages when loaded.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <span>

#include "mapping/core/error.h"
#include "mapping/io/image_codec.h"
#include "mapping/io/text_list.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/ros/recording.h"
#include "mapping/sequence/detail/listing.h"
#include "mapping/sequence/detail/tf_tree.h"

namespace fs = std::filesystem;

namespace vdmap::detail {

static_assert(std::endian::native == std::endian::little);  // images are converted to little-endian order
namespace {

using ros::MessageType;

// 32FC1 depth (metres) is stored at the TUM benchmark's 5000 units per metre: 0.2 mm steps up to
// 13.1 m, finer than any RGB-D sensor measures.
constexpr double kFloatDepthScale = 5000.0;
// 16-bit depth without a recorded unit is in millimetres (REP 118).
constexpr double kMillimetreScale = 1000.0;

std::string lower(std::string s) { return asciiLower(std::move(s)); }

bool contains(const std::string& text, const char* part) { return lower(text).find(part) != std::string::npos; }

std::string topicList(const ros::Recording& rec) {
  std::string list;
  for (const ros::Topic& t : rec.topics()) list += (list.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return list.empty() ? "none" : list;
}

int topicNamed(const ros::Recording& rec, const std::string& name, const char* flag,
               std::initializer_list<MessageType> kinds) {
  const auto& topics = rec.topics();
  for (std::size_t i = 0; i < topics.size(); ++i) {
    if (topics[i].name != name) continue;
    if (std::find(kinds.begin(), kinds.end(), topics[i].kind) == kinds.end())
      throw InputError(rec.path().string(), std::string(flag) + " " + name + " is of type " + topics[i].type +
                                                ", which vdmap does not read there");
    return static_cast<int>(i);
  }
  throw InputError(rec.path().string(),
                   std::string(flag) + " " + name + ": no such topic (topics: " + topicList(rec) + ")");
}

// The best topic by `score` (> 0 qualifies; ties: more messages, then the name): -1 when none.
int bestTopic(const ros::Recording& rec, const std::function<int(const ros::Topic&)>& score) {
  int best = -1, best_score = 0;
  const auto& topics = rec.topics();
  for (std::size_t i = 0; i < topics.size(); ++i) {
    const int s = score(topics[i]);
    if (s <= 0) continue;
    if (best < 0 || s > best_score || (s == best_score && topics[i].count > topics[best].count)) {
      best = static_cast<int>(i);
      best_score = s;
    }
  }
  return best;
}

bool isImage(const ros::Topic& t) { return t.kind == MessageType::kImage || t.kind == MessageType::kCompressedImage; }

int depthScore(const ros::Topic& t) {
  if (!isImage(t) || !contains(t.name, "depth")) return 0;
  int s = 10;
  if (contains(t.name, "aligned_depth")) s += 4;  // already registered to the colour camera
  if (t.kind == MessageType::kImage) s += 2;      // raw over compressedDepth of the same
  if (contains(t.name, "disparity")) s = 0;
  return s;
}

int colourScore(const ros::Topic& t) {
  if (!isImage(t) || contains(t.name, "depth") || contains(t.name, "infra") || contains(t.name, "ir/")) return 0;
  int s = 1;
  if (contains(t.name, "rgb") || contains(t.name, "color") || contains(t.name, "colour")) s += 10;
  if (t.kind == MessageType::kImage) s += 2;
  if (contains(t.name, "rect")) s += 1;
  return s;
}

// Length of the common prefix of two topic names, in whole path parts.
int sharedParts(const std::string& a, const std::string& b) {
  int parts = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size() && a[i] == b[i]; ++i)
    if (a[i] == '/') ++parts;
  return parts;
}

// The CameraInfo topic nearest to `image` in the topic tree.
int infoTopicFor(const ros::Recording& rec, const std::string& image) {
  return bestTopic(rec, [&](const ros::Topic& t) {
    return t.kind == MessageType::kCameraInfo ? 1 + sharedParts(t.name, image) : 0;
  });
}

struct DepthCoding {
  /// kCompressedDepth: compressed_depth_image_transport's PNG of 16-bit depth; kInverseDepth: its
  /// PNG of quantised inverse depth, for 32FC1 images.
  enum class Kind { kUnsigned16, kFloat32, kCompressedDepth, kInverseDepth } kind = Kind::kUnsigned16;
  double scale = kMillimetreScale;
};

struct ImageRefs {
  std::vector<ros::MessageRef> depth, rgb;  // by listed frame (rgb: of its matched colour)
};

class RecordingDecoder : public FrameDecoder {
 public:
  RecordingDecoder(std::shared_ptr<const ros::Recording> rec, std::string depth_topic, std::string rgb_topic,
                   DepthCoding coding, cv::Size depth_size, cv::Size rgb_size, ImageRefs refs)
      : rec_(std::move(rec)), depth_topic_(std::move(depth_topic)), rgb_topic_(std::move(rgb_topic)), coding_(coding),
        depth_size_(depth_size), rgb_size_(rgb_size), refs_(std::move(refs)) {}

  void decode(int listed, cv::Mat* depth, cv::Mat* rgb, std::string* rgb_file) const override {
    *depth = decodeDepth(rec_->read(refs_.depth.at(listed)));
    *rgb = decodeColour(rec_->read(refs_.rgb.at(listed)), rgb_file);
  }

 private:
  InputError error(const std::string& topic, const ros::Message& m, const std::string& what) const {
    char at[64];
    std::snprintf(at, sizeof at, " message at %.6f s", static_cast<double>(m.log_time_ns) * 1e-9);
    return InputError(rec_->path().string(), topic + at + ": " + what);
  }

  void checkSize(const std::string& topic, const ros::Message& m, int width, int height, cv::Size expected) const {
    if (width != expected.width || height != expected.height)
      throw error(topic, m,
                  "image is " + std::to_string(width) + "x" + std::to_string(height) + " but its camera is " +
                      std::to_string(expected.width) + "x" + std::to_string(expected.height));
  }

  cv::Mat decodeDepth(const ros::Message& m) const {
    try {
      if (coding_.kind == DepthCoding::Kind::kCompressedDepth || coding_.kind == DepthCoding::Kind::kInverseDepth) {
        const ros::CompressedImage c = ros::decodeCompressedImage(*m.bytes, m.encoding);
        // compressed_depth_image_transport: a 12-byte header (format, then the two floats that
        // quantise inverse depth) before the PNG of 16-bit values.
        constexpr std::size_t kHeader = 12;
        if (c.data.size() <= kHeader) throw std::runtime_error("compressedDepth message holds no PNG");
        cv::Mat d = decodeDepthImage(std::string(c.data.begin() + kHeader, c.data.end()), depth_topic_);
        checkSize(depth_topic_, m, d.cols, d.rows, depth_size_);
        if (coding_.kind == DepthCoding::Kind::kCompressedDepth) return d;
        float quant[2];
        std::memcpy(quant, c.data.data() + 4, sizeof quant);
        // As the transport decodes it: depth = A / (v - B) metres, 0 = no measurement.
        for (int v = 0; v < d.rows; ++v)
          for (std::uint16_t& value : std::span(d.ptr<std::uint16_t>(v), d.cols)) {
            const float metres = value == 0 ? 0.0f : quant[0] / (static_cast<float>(value) - quant[1]);
            const double raw = std::round(metres * coding_.scale);
            value = std::isfinite(metres) && raw > 0 && raw <= 65535 ? static_cast<std::uint16_t>(raw) : 0;
          }
        return d;
      }
      const ros::Image image = ros::decodeImage(*m.bytes, m.encoding);
      checkSize(depth_topic_, m, static_cast<int>(image.width), static_cast<int>(image.height), depth_size_);
      const int w = static_cast<int>(image.width), h = static_cast<int>(image.height);
      const bool f32 = coding_.kind == DepthCoding::Kind::kFloat32;
      const std::size_t pixel = f32 ? 4 : 2;
      // (The decoder checked that the data holds height * step bytes.)
      if (image.step < w * pixel)
        throw std::runtime_error("rows of " + std::to_string(image.step) + " bytes hold no " + std::to_string(w) +
                                 " pixels of " + std::to_string(pixel) + " bytes");
      cv::Mat out(h, w, CV_16UC1);
      std::vector<std::uint8_t> swapped(image.is_bigendian ? w * pixel : 0);
      std::vector<float> metres(f32 ? w : 0);
      for (int v = 0; v < h; ++v) {
        const std::uint8_t* row = image.data.data() + static_cast<std::size_t>(v) * image.step;
        if (image.is_bigendian) {  // to this machine's (little-endian) order
          for (int u = 0; u < w; ++u) std::reverse_copy(row + u * pixel, row + (u + 1) * pixel, &swapped[u * pixel]);
          row = swapped.data();
        }
        std::uint16_t* o = out.ptr<std::uint16_t>(v);
        if (!f32) {
          std::memcpy(o, row, w * pixel);
          continue;
        }
        std::memcpy(metres.data(), row, w * pixel);
        for (int u = 0; u < w; ++u) {
          const double raw = std::round(metres[u] * coding_.scale);
          o[u] = std::isfinite(metres[u]) && raw > 0 && raw <= 65535 ? static_cast<std::uint16_t>(raw) : 0;
        }
      }
      return out;
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw error(depth_topic_, m, e.what());
    }
  }

  cv::Mat decodeColour(const ros::Message& m, std::string* file) const {
    try {
      if (rec_->topics().at(m.topic).kind == MessageType::kCompressedImage) {
        ros::CompressedImage c = ros::decodeCompressedImage(*m.bytes, m.encoding);
        std::string bytes(c.data.begin(), c.data.end());
        cv::Mat rgb = decodeColorImage(bytes, rgb_topic_);
        checkSize(rgb_topic_, m, rgb.cols, rgb.rows, rgb_size_);
        if (file) *file = std::move(bytes);
        return rgb;
      }
      const ros::Image image = ros::decodeImage(*m.bytes, m.encoding);
      checkSize(rgb_topic_, m, static_cast<int>(image.width), static_cast<int>(image.height), rgb_size_);
      const std::string enc = lower(image.encoding);
      int channels = 0, red = 0;
      if (enc == "rgb8") channels = 3, red = 0;
      else if (enc == "bgr8") channels = 3, red = 2;
      else if (enc == "rgba8") channels = 4, red = 0;
      else if (enc == "bgra8") channels = 4, red = 2;
      else if (enc == "mono8") channels = 1;
      else
        throw std::runtime_error("colour encoding '" + image.encoding +
                                 "' is not one vdmap reads (rgb8, bgr8, "
                                 "rgba8, bgra8, mono8)");
      const int w = static_cast<int>(image.width), h = static_cast<int>(image.height);
      if (image.step < static_cast<std::uint32_t>(w * channels))  // (the decoder checked height * step)
        throw std::runtime_error("rows of " + std::to_string(image.step) + " bytes hold no " + std::to_string(w) +
                                 " pixels of " + std::to_string(channels) + " bytes");
      cv::Mat out(h, w, CV_8UC3);
      for (int v = 0; v < h; ++v) {
        const std::uint8_t* row = image.data.data() + static_cast<std::size_t>(v) * image.step;
        cv::Vec3b* o = out.ptr<cv::Vec3b>(v);
        for (int u = 0; u < w; ++u) {
          const std::uint8_t* p = row + u * channels;
          o[u] = channels == 1 ? cv::Vec3b(p[0], p[0], p[0]) : cv::Vec3b(p[red], p[1], p[2 - red]);
        }
      }
      return out;
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw error(rgb_topic_, m, e.what());
    }
  }

  std::shared_ptr<const ros::Recording> rec_;
  std::string depth_topic_, rgb_topic_;
  DepthCoding coding_;
  cv::Size depth_size_, rgb_size_;
  ImageRefs refs_;
};

struct StampedImage {
  double stamp = 0.0;
  std::string frame_id;
  ros::MessageRef ref;
};

// What one pass over the chosen topics found.
struct Scanned {
  std::vector<StampedImage> depth, rgb;
  std::optional<ros::CameraInfo> depth_info, rgb_info;
  std::string depth_encoding;  // of the first depth message (a CompressedImage's format)
  int depth_width = 0, depth_height = 0;
  std::optional<float> depth_units;                 // RealSense's recorded metres per unit
  std::optional<Transform> T_ref_depth, T_ref_rgb;  // RealSense's recorded stream extrinsics
  TfTree tf;
  std::vector<StampedPose> poses;  // --pose-topic
  std::string pose_frame;
  ros::ScanEnd end;
};

}  // namespace

Listing listRecording(const fs::path& file, const SequenceOptions& options) {
  std::shared_ptr<const ros::Recording> rec = ros::openRecording(file);
  const std::string name = file.string();
  const SequenceOptions::Topics& want = options.topics;
  const int depth = want.depth.empty() ? bestTopic(*rec, depthScore)
                                       : topicNamed(*rec, want.depth, "--depth-topic",
                                                    {MessageType::kImage, MessageType::kCompressedImage});
  if (depth < 0)
    throw InputError(name, "has no depth image topic (topics: " + topicList(*rec) + "); name one with --depth-topic");
  const int rgb = want.rgb.empty()
                      ? bestTopic(*rec, colourScore)
                      : topicNamed(*rec, want.rgb, "--rgb-topic", {MessageType::kImage, MessageType::kCompressedImage});
  if (rgb < 0)
    throw InputError(name, "has no colour image topic (topics: " + topicList(*rec) + "); name one with --rgb-topic");
  const std::string depth_name = rec->topics()[depth].name, rgb_name = rec->topics()[rgb].name;
  const int depth_info = want.info.empty() ? infoTopicFor(*rec, depth_name)
                                           : topicNamed(*rec, want.info, "--info-topic", {MessageType::kCameraInfo});
  const int rgb_info = infoTopicFor(*rec, rgb_name);
  const int pose = want.pose.empty() ? -1
                                     : topicNamed(*rec, want.pose, "--pose-topic",
                                                  {MessageType::kPoseStamped, MessageType::kOdometry});
  // RealSense's recorder keeps the depth unit as an option of the depth sensor.
  const std::string sensor = depth_name.substr(0, depth_name.find('/', depth_name.find("sensor_") + 1) + 1);
  const int units = bestTopic(*rec, [&](const ros::Topic& t) {
    return t.kind == MessageType::kFloat32 && contains(t.name, "depth units") ? 1 + sharedParts(t.name, sensor) : 0;
  });
  // RealSense's recorder keeps each stream's extrinsics (to the reference stream) as a bare
  // geometry_msgs/Transform beside its images: .../Depth_0/tf/0, .../Color_0/tf/0.
  auto extrinsicsOf = [&](const std::string& image) {
    const std::string stream = image.substr(0, image.rfind("/image/") + 1);
    return bestTopic(*rec, [&](const ros::Topic& t) {
      return t.kind == MessageType::kTransform && !stream.empty() && t.name.rfind(stream, 0) == 0 ? 1 : 0;
    });
  };
  const int depth_extrinsics = extrinsicsOf(depth_name), rgb_extrinsics = extrinsicsOf(rgb_name);
  std::vector<int> chosen = {depth, rgb};
  for (int t : {depth_info, rgb_info, pose, units, depth_extrinsics, rgb_extrinsics})
    if (t >= 0) chosen.push_back(t);
  std::vector<int> tf_topics;
  for (std::size_t i = 0; i < rec->topics().size(); ++i)
    if (rec->topics()[i].kind == MessageType::kTfMessage) {
      chosen.push_back(static_cast<int>(i));
      tf_topics.push_back(static_cast<int>(i));
    }

  Scanned s;
  // Images are listed from their heads (stamp, frame, size, encoding): their pixels are read
  // when the frames load. A head too short for its fields (a very long frame id) is read whole.
  auto head = [&]<typename T>(const ros::Message& m, T (*decode)(const std::vector<std::uint8_t>&, ros::Encoding)) {
    try {
      return decode(*m.bytes, m.encoding);
    } catch (const std::runtime_error&) {
      if (!m.head_only) throw;
    }
    return decode(*rec->read(m.ref).bytes, m.encoding);
  };
  s.end = rec->scanHeads(chosen, {depth, rgb}, [&](const ros::Message& m) {
    const ros::Topic& topic = rec->topics()[m.topic];
    try {
      if (m.topic == depth || m.topic == rgb) {
        ros::Header header;
        if (topic.kind == MessageType::kImage) {
          const ros::Image image = head(m, &ros::decodeImageHead);
          header = image.header;
          if (m.topic == depth && s.depth.empty()) {
            s.depth_encoding = image.encoding;
            s.depth_width = static_cast<int>(image.width), s.depth_height = static_cast<int>(image.height);
          }
        } else {
          const ros::CompressedImage image = head(m, &ros::decodeCompressedImageHead);
          header = image.header;
          if (m.topic == depth && s.depth.empty()) s.depth_encoding = image.format;
        }
        std::vector<StampedImage>& list = m.topic == depth ? s.depth : s.rgb;
        if (!list.empty() && header.stamp < list.back().stamp)
          throw std::runtime_error("header stamps go backwards (" + std::to_string(header.stamp) + " s after " +
                                   std::to_string(list.back().stamp) + " s)");
        list.push_back({header.stamp, header.frame_id, m.ref});
      } else if (m.topic == depth_info || m.topic == rgb_info) {
        auto& info = m.topic == depth_info ? s.depth_info : s.rgb_info;
        if (!info) info = ros::decodeCameraInfo(*m.bytes, m.encoding);
        if (depth_info == rgb_info && !s.rgb_info) s.rgb_info = s.depth_info;
      } else if (m.topic == pose) {
        const ros::PoseStamped p = ros::decodePose(*m.bytes, m.encoding, topic.kind);
        if (s.poses.empty() || p.header.stamp > s.poses.back().t)
          s.poses.push_back({p.header.stamp, rigidTransform(p.orientation, p.position)});
        s.pose_frame = p.header.frame_id;
      } else if (m.topic == units) {
        s.depth_units = ros::decodeFloat32(*m.bytes, m.encoding);
      } else if (m.topic == depth_extrinsics || m.topic == rgb_extrinsics) {
        const ros::TransformStamped t = ros::decodeTransforms(*m.bytes, m.encoding, topic.kind).at(0);
        (m.topic == depth_extrinsics ? s.T_ref_depth : s.T_ref_rgb) = rigidTransform(t.rotation, t.translation);
      } else {
        const bool is_static = contains(topic.name, "tf_static");
        for (const ros::TransformStamped& t : ros::decodeTransforms(*m.bytes, m.encoding, topic.kind))
          s.tf.add(t, is_static);
      }
    } catch (const std::exception& e) {
      char at[64];
      std::snprintf(at, sizeof at, " message at %.6f s", static_cast<double>(m.log_time_ns) * 1e-9);
      throw InputError(name, topic.name + at + ": " + e.what());
    }
    return true;
  });
  if (s.depth.empty())
    throw InputError(name, "depth topic " + depth_name + " holds no message" +
                               (s.end.complete ? "" : " before the damage: " + s.end.damage));

  Listing listing;
  listing.list_file = file;
  listing.notes.push_back("recording: " + rec->describe());
  listing.notes.push_back("depth: " + depth_name + " (" + s.depth_encoding + ", " + std::to_string(s.depth.size()) +
                          " frames" + (want.depth.empty() ? ", chosen by type and name" : ", --depth-topic") + ")");
  listing.notes.push_back("colour: " + rgb_name + " (" + std::to_string(s.rgb.size()) + " frames" +
                          (want.rgb.empty() ? ", chosen by type and name" : ", --rgb-topic") + ")");
  if (!s.end.complete) listing.notes.push_back("damaged: " + s.end.damage);

  // The depth coding and the camera.
  DepthCoding coding;
  const std::string enc = lower(s.depth_encoding);
  // A compressedDepth format reads "16UC1; compressedDepth" (ROS 1), "32FC1; compressedDepth png"
  // (ROS 2) or "...; compressedDepth rvl" (ROS 2's other codec, not read here).
  const bool compressed = contains(enc, "compresseddepth") && !contains(enc, "rvl");
  if (enc == "32fc1") coding = {DepthCoding::Kind::kFloat32, kFloatDepthScale};
  else if (compressed && enc.starts_with("32fc1")) coding = {DepthCoding::Kind::kInverseDepth, kFloatDepthScale};
  else if (compressed) coding = {DepthCoding::Kind::kCompressedDepth, kMillimetreScale};
  else if (enc == "16uc1" || enc == "mono16") coding = {DepthCoding::Kind::kUnsigned16, kMillimetreScale};
  else
    throw InputError(name, "depth topic " + depth_name + " has encoding '" + s.depth_encoding +
                               "'; vdmap reads 16UC1, mono16 (millimetres or the recorded Depth Units), 32FC1 "
                               "(metres) and compressedDepth PNG (of 16UC1 or 32FC1)");
  if (coding.kind == DepthCoding::Kind::kUnsigned16 && s.depth_units) {
    if (!(*s.depth_units > 0) || !std::isfinite(*s.depth_units))
      throw InputError(name, "the recorded Depth Units (" + std::to_string(*s.depth_units) + ") are not positive");
    coding.scale = 1.0 / *s.depth_units;
  }
  if (!options.camera_preset.empty()) {
    try {
      listing.camera = {cameraPreset(options.camera_preset), "preset " + options.camera_preset + " (--camera)",
                        cameraPresetColour(options.camera_preset)};
    } catch (const std::invalid_argument& e) {
      throw InputError("--camera", e.what());
    }
  } else if (s.depth_info) {
    const ros::CameraInfo& c = *s.depth_info;
    listing.camera.camera = {
        static_cast<int>(c.width), static_cast<int>(c.height), c.k[0], c.k[4], c.k[2], c.k[5], coding.scale};
    listing.camera.source = "camera_info of " + rec->topics()[depth_info].name;
  } else {
    listing.camera = {cameraPreset("tum-default"),
                      "preset tum-default (the recording has no camera_info; --camera "
                      "PRESET sets it)",
                      std::nullopt, true};
  }
  listing.camera.camera.depth_scale = coding.scale;
  if (s.depth_width > 0 &&
      (s.depth_width != listing.camera.camera.width || s.depth_height != listing.camera.camera.height))
    throw InputError(name, "depth topic " + depth_name + " has " + std::to_string(s.depth_width) + "x" +
                               std::to_string(s.depth_height) + " images but the camera (" + listing.camera.source +
                               ") is " + std::to_string(listing.camera.camera.width) + "x" +
                               std::to_string(listing.camera.camera.height));
  const std::string camera_frame =
      TfTree::name(want.camera_frame.empty() ? s.depth.front().frame_id : want.camera_frame);
  cv::Size rgb_size(listing.camera.camera.width, listing.camera.camera.height);
  if (options.camera_preset.empty() && s.rgb_info && rgb_info != depth_info) {
    // Colour from another camera: registered into the depth camera.
    const ros::CameraInfo& c = *s.rgb_info;
    ColourCamera colour{c.k[0], c.k[4], c.k[2], c.k[5]};
    colour.width = static_cast<int>(c.width), colour.height = static_cast<int>(c.height);
    const std::string colour_frame = TfTree::name(s.rgb.empty() ? "" : s.rgb.front().frame_id);
    if (s.T_ref_depth && s.T_ref_rgb) {
      colour.T_colour_depth = s.T_ref_rgb->inverse() * *s.T_ref_depth;
    } else if (!colour_frame.empty() && colour_frame != camera_frame && s.tf.has(colour_frame) &&
               s.tf.has(camera_frame) && s.tf.root(colour_frame) == s.tf.root(camera_frame)) {
      const std::string root = s.tf.root(camera_frame);
      const double t = s.depth.front().stamp;
      const auto a = s.tf.lookup(root, colour_frame, t, options.max_pose_dt_s);
      const auto b = s.tf.lookup(root, camera_frame, t, options.max_pose_dt_s);
      if (a && b) colour.T_colour_depth = a->inverse() * *b;
    }
    const PinholeCamera& d = listing.camera.camera;
    const bool same = colour.fx == d.fx && colour.fy == d.fy && colour.cx == d.cx && colour.cy == d.cy &&
                      colour.width == d.width && colour.height == d.height &&
                      colour.T_colour_depth.matrix().isIdentity(0.0);
    if (!same) {
      listing.camera.colour = colour;
      rgb_size = {colour.width, colour.height};
    }
  }

  // Poses: --pose-topic, else tf from the tree's root (or --pose-frames) to the depth frame.
  std::function<std::optional<Transform>(double)> pose_at;
  if (pose >= 0) {
    listing.has_poses = !s.poses.empty();
    listing.poses_source = rec->topics()[pose].name + " (" + rec->topics()[pose].type + ")";
    pose_at = [&](double t) { return interpolatePose(s.poses, t, options.max_pose_dt_s); };
  } else if (!tf_topics.empty() && s.tf.has(camera_frame)) {
    const std::string world = want.world_frame.empty() ? s.tf.root(camera_frame) : TfTree::name(want.world_frame);
    if (world == camera_frame)
      throw InputError(name, "tf: the depth frame '" + camera_frame + "' has no parent to take poses from");
    try {
      s.tf.lookup(world, camera_frame, s.depth.front().stamp, 1e9);
    } catch (const std::invalid_argument& e) {
      std::string frames;
      for (const std::string& f : s.tf.frames()) frames += (frames.empty() ? "" : ", ") + f;
      throw InputError(name, std::string(e.what()) + " (tf has frames: " + frames + "); --pose-frames WORLD:CAMERA");
    }
    listing.has_poses = true;
    listing.poses_source = "tf " + world + " -> " + camera_frame;
    pose_at = [&, world](double t) { return s.tf.lookup(world, camera_frame, t, options.max_pose_dt_s); };
  } else if (!want.world_frame.empty() || !want.camera_frame.empty()) {
    throw InputError(name, "--pose-frames: tf has no frame '" + camera_frame + "'");
  }
  listing.poses_file = file;

  // Frames: each depth frame with the nearest colour frame in time, and its pose.
  ImageRefs refs;
  for (const StampedImage& d : s.depth) {
    ListedFrame frame{{d.stamp, file, file, 0}, std::nullopt, std::nullopt};
    auto it = std::lower_bound(s.rgb.begin(), s.rgb.end(), d.stamp,
                               [](const StampedImage& c, double t) { return c.stamp < t; });
    const StampedImage* best = nullptr;
    for (auto c : {it, it == s.rgb.begin() ? s.rgb.end() : std::prev(it)}) {
      if (c == s.rgb.end() || std::abs(c->stamp - d.stamp) > options.max_rgb_dt_s) continue;
      if (!best || std::abs(c->stamp - d.stamp) < std::abs(best->stamp - d.stamp)) best = &*c;
    }
    refs.depth.push_back(d.ref);
    refs.rgb.push_back(best ? best->ref : ros::MessageRef{});
    if (best) frame.rgb = ListedImage{best->stamp, file, file, 0};
    if (pose_at) frame.pose = pose_at(d.stamp);
    listing.frames.push_back(std::move(frame));
  }
  listing.decoder = std::make_shared<RecordingDecoder>(
      rec, depth_name, rgb_name, coding, cv::Size(listing.camera.camera.width, listing.camera.camera.height), rgb_size,
      std::move(refs));
  return listing;
}

}  // namespace vdmap::detail
