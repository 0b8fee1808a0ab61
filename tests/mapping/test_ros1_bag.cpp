// The ROS 1 bag reader (mapping/ros/ros1_bag.h) and the ROS 1 message decoders
// (mapping/ros/detail/decoders.h) on the recordings of ../shared/data/bags: what they hold, read
// as rosbag_storage reads them, and what damage leaves of them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "mapping/core/error.h"
#include "mapping/ros/detail/decoders.h"
#include "mapping/ros/ros1_bag.h"
#include "tests/support/ros1_bag_writer.h"
#include "tests/support/test_util.h"

namespace vdmap::ros::ros1_bag_test {

namespace fs = std::filesystem;
using test::BagConnection;
using test::BagMessage;
using test::BagWriter;
using test::Ros1Bytes;

/// A bag of ../shared/data/bags, or empty (the test skips) when absent.
fs::path bagFile(const fs::path& bags, const std::string& name) {
  const fs::path file = bags / name;
  return fs::exists(file) ? file : fs::path();
}

#define VDMAP_REQUIRE_BAG(var, name)                \
  VDMAP_REQUIRE_SHARED_DATA(var##_folder, "bags");  \
  const fs::path var = bagFile(var##_folder, name); \
  if (var.empty()) GTEST_SKIP() << "shared data bags/" << name << " not found (real-data test skipped)"

constexpr const char* kTumBag = "7scenes-redkitchen-tum-layout.bag";
constexpr const char* kRealSenseBag = "realsense-d400-single-depth-color.bag";

std::uint64_t fnv1a(const std::vector<std::uint8_t>& bytes, std::uint64_t hash = 1469598103934665603ull) {
  for (const std::uint8_t b : bytes) hash = (hash ^ b) * 1099511628211ull;
  return hash;
}

/// What a scan gave of one message (its bytes hashed: the TUM-layout bag holds 64 MB of them).
struct Seen {
  int topic = -1;
  std::int64_t log_time_ns = 0;
  MessageRef ref;
  std::uint64_t hash = 0;
  std::size_t size = 0;
  bool operator==(const Seen& o) const {
    return topic == o.topic && log_time_ns == o.log_time_ns && hash == o.hash && size == o.size;
  }
};

struct ScanResult {
  std::vector<Seen> messages;
  ScanEnd end;
};

std::vector<int> allTopics(const Recording& recording) {
  std::vector<int> topics(recording.topics().size());
  for (std::size_t i = 0; i < topics.size(); ++i) topics[i] = static_cast<int>(i);
  return topics;
}

ScanResult scanAll(const Recording& recording) {
  ScanResult result;
  result.end = recording.scan(allTopics(recording), [&](const Message& m) {
    EXPECT_EQ(m.encoding, Encoding::kRos1);
    result.messages.push_back({m.topic, m.log_time_ns, m.ref, fnv1a(*m.bytes), m.bytes->size()});
    return true;
  });
  return result;
}

int topicIndex(const Recording& recording, const std::string& name) {
  for (std::size_t i = 0; i < recording.topics().size(); ++i)
    if (recording.topics()[i].name == name) return static_cast<int>(i);
  return -1;
}

/// The first message on `topic`, undecoded.
std::vector<std::uint8_t> firstMessage(const Recording& recording, const std::string& topic) {
  std::vector<std::uint8_t> bytes;
  recording.scan({topicIndex(recording, topic)}, [&](const Message& m) {
    bytes = *m.bytes;
    return false;
  });
  return bytes;
}

/// The first `n` of `bytes` written to `out`.
void writeCut(const std::string& bytes, std::uint64_t n, const fs::path& out) {
  test::writeText(out, bytes.substr(0, n));
}

/// The bag header's index_pos: where the index starts (the connection and chunk info records).
std::uint64_t indexPos(const fs::path& file) {
  const std::string head = test::readFile(file).substr(0, 4096);
  const auto field = head.find("index_pos=");
  std::uint64_t pos = 0;
  if (field != std::string::npos) std::memcpy(&pos, head.data() + field + 10, 8);
  return pos;
}

// Per topic: message count, total bytes and the FNV-1a hash of their bytes in log-time order, as
// Debian's rosbag_storage (rosbag::View, MessageInstance::write) reads these bags: the reference
// this reader must agree with (a 20-line rosbag::View program, run once; linking rosbag_storage
// here would load ten more libraries into every test process).
struct Expected {
  const char* topic;
  int count;
  std::size_t bytes;
  std::uint64_t hash;
};
const Expected kTumByRosbagStorage[] = {
    {"/camera/depth/camera_info", 30, 11130, 0x8a06c7d23b628574ull},
    {"/camera/depth/image", 30, 36866010, 0x3eed8bc754d3bba1ull},
    {"/camera/rgb/camera_info", 30, 11130, 0x8a06c7d23b628574ull},
    {"/camera/rgb/image_color", 30, 27649980, 0xda8fffe72cfd8cecull},
    {"/tf", 30, 6030, 0x699ea3f2f4fb4413ull},
};
const Expected kRealSenseByRosbagStorage[] = {
    {"/device_0/sensor_0/Depth_0/image/data", 2, 1228888, 0xd67e482cd23f0c04ull},
    {"/device_0/sensor_0/Depth_0/info/camera_info", 1, 350, 0x04fd8f71d3609742ull},
    {"/device_0/sensor_0/Depth_0/tf/0", 1, 56, 0x48bd6fcb06cdb6baull},
    {"/device_0/sensor_0/option/Depth Units/value", 1, 4, 0x6cbf2c0c3c6b476bull},
    {"/device_0/sensor_1/Color_0/image/data", 1, 921642, 0x2b84bb88d0a1f57bull},
    {"/device_0/sensor_1/Color_0/info/camera_info", 1, 350, 0x41018d68343f5670ull},
    {"/device_0/sensor_1/Color_0/tf/0", 1, 56, 0x60708b1bcb223de8ull},
    {"/file_version", 1, 4, 0x516442878400fb80ull},
};

void expectAsRosbagStorageReads(const Recording& bag, const ScanResult& scan, std::span<const Expected> expected) {
  std::map<int, std::pair<int, std::size_t>> by_topic;  // messages, bytes
  for (const Seen& m : scan.messages) {
    ++by_topic[m.topic].first;
    by_topic[m.topic].second += m.size;
  }
  for (const Expected& e : expected) {
    const int topic = topicIndex(bag, e.topic);
    ASSERT_GE(topic, 0) << e.topic;
    EXPECT_EQ(bag.topics()[topic].count, static_cast<std::uint64_t>(e.count)) << e.topic;
    EXPECT_EQ(by_topic[topic].first, e.count) << e.topic;
    EXPECT_EQ(by_topic[topic].second, e.bytes) << e.topic;
    // The hash runs over the topic's bytes end to end, so it is taken again by a scan of the topic.
    std::uint64_t hash = 1469598103934665603ull;
    bag.scan({topic}, [&](const Message& m) {
      hash = fnv1a(*m.bytes, hash);
      return true;
    });
    EXPECT_EQ(hash, e.hash) << e.topic;
  }
}

TEST(Ros1Bag, TumLayoutTopicsTypesAndCounts) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  EXPECT_EQ(bag->describe(), "ROS 1 bag (format 2.0, lz4 chunks)");
  EXPECT_EQ(bag->path(), file);
  const std::map<std::string, std::pair<std::string, MessageType>> expected = {
      {"/camera/rgb/image_color", {"sensor_msgs/Image", MessageType::kImage}},
      {"/camera/depth/image", {"sensor_msgs/Image", MessageType::kImage}},
      {"/camera/rgb/camera_info", {"sensor_msgs/CameraInfo", MessageType::kCameraInfo}},
      {"/camera/depth/camera_info", {"sensor_msgs/CameraInfo", MessageType::kCameraInfo}},
      {"/tf", {"tf2_msgs/TFMessage", MessageType::kTfMessage}},
  };
  ASSERT_EQ(bag->topics().size(), expected.size());
  for (const Topic& topic : bag->topics()) {
    ASSERT_TRUE(expected.contains(topic.name)) << topic.name;
    EXPECT_EQ(topic.type, expected.at(topic.name).first);
    EXPECT_EQ(topic.kind, expected.at(topic.name).second);
    EXPECT_EQ(topic.count, 30u) << topic.name;
  }
}

TEST(Ros1Bag, TumLayoutScanReadsWhatRosbagStorageReadsInLogTimeOrder) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  const ScanResult scan = scanAll(*bag);
  EXPECT_TRUE(scan.end.complete);
  EXPECT_EQ(scan.end.damage, "");
  ASSERT_EQ(scan.messages.size(), 150u);
  for (std::size_t i = 1; i < scan.messages.size(); ++i)
    EXPECT_LE(scan.messages[i - 1].log_time_ns, scan.messages[i].log_time_ns) << i;
  // Stamps are the 7-Scenes folder's plus 1.6e9 s: 30 frames, every 5th at 30 fps.
  EXPECT_EQ(scan.messages.front().log_time_ns, 1'600'000'000'000'000'000);
  EXPECT_NEAR(scan.messages.back().log_time_ns * 1e-9 - 1.6e9, 145 / 30.0, 1e-3);
  expectAsRosbagStorageReads(*bag, scan, kTumByRosbagStorage);
}

TEST(Ros1Bag, ScanVisitsOnlyTheChosenTopicsAndStopsWhenAsked) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  const int depth = topicIndex(*bag, "/camera/depth/image"), tf = topicIndex(*bag, "/tf");
  int seen = 0;
  const ScanEnd end = bag->scan({depth, tf}, [&](const Message& m) {
    EXPECT_TRUE(m.topic == depth || m.topic == tf);
    return ++seen < 7;
  });
  EXPECT_EQ(seen, 7);
  EXPECT_TRUE(end.complete);
  EXPECT_TRUE(bag->scan({}, [](const Message&) { return true; }).complete);
}

// A heads scan gives each image as its first bytes (the rest of the topics whole), and decodes to
// the same header, size and encoding as the whole message; it visits what scan() visits.
TEST(Ros1Bag, HeadsScanGivesEachImagesFirstBytes) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  const int depth = topicIndex(*bag, "/camera/depth/image"), rgb = topicIndex(*bag, "/camera/rgb/image_color");
  std::vector<Message> whole, heads;
  const std::vector<int> topics = allTopics(*bag);
  EXPECT_TRUE(bag->scan(topics, [&](const Message& m) { return whole.push_back(m), true; }).complete);
  EXPECT_TRUE(
      bag->scanHeads(topics, {depth, rgb}, [&](const Message& m) { return heads.push_back(m), true; }).complete);
  ASSERT_EQ(heads.size(), whole.size());
  int images = 0;
  for (std::size_t i = 0; i < heads.size(); ++i) {
    const Message &h = heads[i], &w = whole[i];
    ASSERT_EQ(h.topic, w.topic);
    EXPECT_EQ(h.log_time_ns, w.log_time_ns);
    ASSERT_LE(h.bytes->size(), w.bytes->size());
    EXPECT_TRUE(std::equal(h.bytes->begin(), h.bytes->end(), w.bytes->begin())) << i;
    if (h.topic != depth && h.topic != rgb) {
      EXPECT_FALSE(h.head_only);
      EXPECT_EQ(h.bytes->size(), w.bytes->size());
      continue;
    }
    ++images;
    EXPECT_TRUE(h.head_only);
    EXPECT_LT(h.bytes->size(), 2000u);
    const Image a = decodeImageHead(*h.bytes, Encoding::kRos1), b = decodeImage(*w.bytes, Encoding::kRos1);
    EXPECT_EQ(a.header.stamp, b.header.stamp);
    EXPECT_EQ(a.header.frame_id, b.header.frame_id);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.encoding, b.encoding);
    EXPECT_TRUE(a.data.empty());
    EXPECT_THROW(decodeImage(*h.bytes, Encoding::kRos1), std::runtime_error) << "a head holds no pixels";
  }
  EXPECT_EQ(images, 60);
}

TEST(Ros1Bag, TumLayoutDepthIs32FC1MetresWithNaNWhereNoMeasurement) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  const auto depth_bytes = firstMessage(*bag, "/camera/depth/image");
  const Image depth = detail::decodeImageRos1(depth_bytes);
  EXPECT_EQ(depth.width, 640u);
  EXPECT_EQ(depth.height, 480u);
  EXPECT_EQ(depth.encoding, "32FC1");
  EXPECT_FALSE(depth.is_bigendian);
  EXPECT_EQ(depth.step, 640u * 4);
  ASSERT_EQ(depth.data.size(), 640u * 480 * 4);
  EXPECT_EQ(depth.header.stamp, 1.6e9);
  EXPECT_EQ(depth.header.frame_id, "/openni_rgb_optical_frame");
  int nan = 0, valid = 0;
  for (std::size_t i = 0; i < depth.data.size(); i += 4) {
    float z;
    std::memcpy(&z, depth.data.data() + i, 4);
    if (std::isnan(z)) {
      ++nan;
    } else {
      ++valid;
      EXPECT_TRUE(z > 0.2f && z < 8.f) << z;  // a kitchen seen by a Kinect
    }
  }
  EXPECT_GT(nan, 0);
  EXPECT_GT(valid, 640 * 480 / 2);
  const auto rgb_bytes = firstMessage(*bag, "/camera/rgb/image_color");
  const Image rgb = detail::decodeImageRos1(rgb_bytes);
  EXPECT_EQ(rgb.encoding, "rgb8");
  EXPECT_EQ(rgb.step, 640u * 3);
  const CameraInfo info = detail::decodeCameraInfoRos1(firstMessage(*bag, "/camera/depth/camera_info"));
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.height, 480u);
  EXPECT_EQ(info.k[0], 585.0);
  EXPECT_EQ(info.k[4], 585.0);
  EXPECT_EQ(info.k[2], 320.0);
  EXPECT_EQ(info.k[5], 240.0);
}

TEST(Ros1Bag, TumLayoutTfChainIsTheGroundTruthPose) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  const auto transforms = detail::decodeTransformsRos1(firstMessage(*bag, "/tf"), MessageType::kTfMessage);
  ASSERT_EQ(transforms.size(), 2u);
  EXPECT_EQ(transforms[0].header.frame_id, "/world");
  EXPECT_EQ(transforms[0].child_frame_id, "/kinect");
  EXPECT_EQ(transforms[1].header.frame_id, "/kinect");
  EXPECT_EQ(transforms[1].child_frame_id, "/openni_rgb_optical_frame");
  EXPECT_EQ(transforms[0].header.stamp, 1.6e9);
  EXPECT_TRUE(transforms[1].translation.isApprox(Eigen::Vector3d(0, -0.05, 0)));
  EXPECT_TRUE(transforms[1].rotation.isApprox(Eigen::Quaterniond::Identity()));
  const Eigen::Isometry3d world_kinect = Eigen::Translation3d(transforms[0].translation) * transforms[0].rotation;
  const Eigen::Isometry3d kinect_optical = Eigen::Translation3d(transforms[1].translation) * transforms[1].rotation;
  const Eigen::Isometry3d world_optical = world_kinect * kinect_optical;
  // groundtruth.txt's first pose (frame 0), printed to 7 decimals.
  const Eigen::Vector3d t(-0.3404563, 0.0164698, 0.2965692);
  const Eigen::Quaterniond q(0.9770762, -0.0002124, -0.1608336, -0.1394795);
  EXPECT_LT((world_optical.translation() - t).norm(), 1e-6);
  EXPECT_LT(Eigen::Quaterniond(world_optical.rotation()).angularDistance(q), 1e-6);
}

TEST(Ros1Bag, RealSenseTopicsDepthUnitsAndExtrinsics) {
  VDMAP_REQUIRE_BAG(file, kRealSenseBag);
  const auto bag = Ros1Bag::open(file);
  const ScanResult scan = scanAll(*bag);
  EXPECT_TRUE(scan.end.complete) << scan.end.damage;
  EXPECT_EQ(scan.messages.size(), 135u);  // as rosbag::View counts them
  expectAsRosbagStorageReads(*bag, scan, kRealSenseByRosbagStorage);
  const int depth = topicIndex(*bag, "/device_0/sensor_0/Depth_0/image/data");
  ASSERT_GE(depth, 0);
  EXPECT_EQ(bag->topics()[depth].kind, MessageType::kImage);
  EXPECT_EQ(bag->topics()[depth].count, 2u);
  // Its own message types are listed, as other.
  const int stream_info = topicIndex(*bag, "/device_0/sensor_0/Depth_0/info");
  ASSERT_GE(stream_info, 0);
  EXPECT_EQ(bag->topics()[stream_info].type, "realsense_msgs/StreamInfo");
  EXPECT_EQ(bag->topics()[stream_info].kind, MessageType::kOther);
  EXPECT_EQ(bag->topics()[topicIndex(*bag, "/device_0/info")].kind, MessageType::kOther);

  const auto bytes = firstMessage(*bag, "/device_0/sensor_0/Depth_0/image/data");
  const Image image = detail::decodeImageRos1(bytes);
  EXPECT_EQ(image.encoding, "mono16");
  EXPECT_EQ(image.width, 640u);
  EXPECT_EQ(image.height, 480u);
  EXPECT_EQ(image.step, 1280u);
  const std::string units_topic = "/device_0/sensor_0/option/Depth Units/value";
  EXPECT_EQ(bag->topics()[topicIndex(*bag, units_topic)].kind, MessageType::kFloat32);
  EXPECT_FLOAT_EQ(detail::decodeFloat32Ros1(firstMessage(*bag, units_topic)), 0.001f);
  for (const char* topic : {"/device_0/sensor_0/Depth_0/tf/0", "/device_0/sensor_1/Color_0/tf/0"}) {
    EXPECT_EQ(bag->topics()[topicIndex(*bag, topic)].kind, MessageType::kTransform);
    const auto extrinsics = detail::decodeTransformsRos1(firstMessage(*bag, topic), MessageType::kTransform);
    ASSERT_EQ(extrinsics.size(), 1u);
    EXPECT_EQ(extrinsics[0].child_frame_id, "");
    EXPECT_NEAR(extrinsics[0].rotation.norm(), 1.0, 1e-6) << topic;
    EXPECT_LT(extrinsics[0].translation.norm(), 0.1) << topic;  // colour and depth sit centimetres apart
  }
}

TEST(Ros1Bag, ReadGivesTheScannedMessageInAnyOrder) {
  VDMAP_REQUIRE_BAG(file, kRealSenseBag);
  const auto bag = Ros1Bag::open(file);
  const ScanResult scan = scanAll(*bag);
  ASSERT_FALSE(scan.messages.empty());
  auto check = [&](const Seen& seen) {
    const Message m = bag->read(seen.ref);
    EXPECT_EQ((Seen{m.topic, m.log_time_ns, m.ref, fnv1a(*m.bytes), m.bytes->size()}), seen);
    EXPECT_EQ(m.ref.position, seen.ref.position);
    EXPECT_EQ(m.ref.offset, seen.ref.offset);
  };
  for (const Seen& seen : scan.messages) check(seen);
  for (auto it = scan.messages.rbegin(); it != scan.messages.rend(); ++it) check(*it);
  EXPECT_THROW(bag->read({scan.messages[0].ref.position + 1, 0}), InputError);
  EXPECT_THROW(bag->read({scan.messages[0].ref.position, scan.messages[0].ref.offset + 1}), InputError);
  EXPECT_THROW(bag->read({scan.messages[0].ref.position, 1ull << 40}), InputError);
}

TEST(Ros1Bag, TumLayoutReadGivesTheScannedMessage) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  const ScanResult scan = scanAll(*bag);
  for (std::size_t i = 0; i < scan.messages.size(); i += 7) {
    const Message m = bag->read(scan.messages[i].ref);
    EXPECT_EQ((Seen{m.topic, m.log_time_ns, m.ref, fnv1a(*m.bytes), m.bytes->size()}), scan.messages[i]) << i;
  }
}

/// A cut bag gives a prefix of the whole bag's messages in each topic, and a damage note.
void expectCutGivesAPrefix(const Recording& whole_bag, const ScanResult& whole, const fs::path& cut, std::uint64_t n,
                           std::size_t at_least) {
  SCOPED_TRACE("cut at byte " + std::to_string(n));
  const auto bag = Ros1Bag::open(cut);
  const ScanResult scan = scanAll(*bag);
  EXPECT_FALSE(scan.end.complete);
  EXPECT_NE(scan.end.damage.find(cut.string() + ": truncated at byte " + std::to_string(n)), std::string::npos)
      << scan.end.damage;
  EXPECT_EQ(scan.end.damage.find('\n'), std::string::npos);
  EXPECT_GE(scan.messages.size(), at_least);
  // Each topic's messages are its first ones in the whole bag, topics matched by name.
  std::map<std::string, std::vector<Seen>> whole_topics, cut_topics;
  for (const Seen& m : whole.messages) whole_topics[whole_bag.topics()[m.topic].name].push_back(m);
  for (const Seen& m : scan.messages) cut_topics[bag->topics()[m.topic].name].push_back(m);
  for (const auto& [topic, messages] : cut_topics) {
    const auto& all = whole_topics[topic];
    ASSERT_LE(messages.size(), all.size()) << topic;
    for (std::size_t i = 0; i < messages.size(); ++i) {
      EXPECT_EQ(messages[i].log_time_ns, all[i].log_time_ns) << topic << " " << i;
      EXPECT_EQ(messages[i].hash, all[i].hash) << topic << " " << i;
    }
    EXPECT_EQ(bag->topics()[topicIndex(*bag, topic)].count, messages.size()) << topic;
  }
  for (std::size_t i = 1; i < scan.messages.size(); ++i)
    EXPECT_LE(scan.messages[i - 1].log_time_ns, scan.messages[i].log_time_ns);
  for (const Seen& m : scan.messages) EXPECT_EQ(fnv1a(*bag->read(m.ref).bytes), m.hash);
}

TEST(Ros1Bag, TruncatedBagGivesTheMessagesBeforeTheCut) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto whole_bag = Ros1Bag::open(file);
  const ScanResult whole = scanAll(*whole_bag);
  const std::string bytes = test::readFile(file);
  const std::uint64_t size = bytes.size(), index = indexPos(file);
  ASSERT_GT(index, 0u);
  ASSERT_LT(index, size);
  test::TempDir tmp;
  const fs::path cut = tmp / "cut.bag";
  // In the header record's padding, in the first chunk, in the middle, in the last index records
  // after a chunk: the bag's index (at its end) is lost.
  for (const auto& [n, at_least] :
       std::vector<std::pair<std::uint64_t, std::size_t>>{{100, 0}, {5000, 0}, {size / 2, 60}, {index - 1, 140}}) {
    writeCut(bytes, n, cut);
    expectCutGivesAPrefix(*whole_bag, whole, cut, n, at_least);
    const auto bag = Ros1Bag::open(cut);
    const std::string damage = scanAll(*bag).end.damage;
    EXPECT_NE(damage.find("(the bag's index is missing); "), std::string::npos) << damage;
    EXPECT_NE(bag->describe().find("index rebuilt"), std::string::npos);
  }
  // Cut where the index starts or inside it: no message is lost.
  for (const std::uint64_t n : {index, size - 10}) {
    writeCut(bytes, n, cut);
    const ScanResult scan = scanAll(*Ros1Bag::open(cut));
    EXPECT_EQ(scan.messages, whole.messages);
    EXPECT_EQ(scan.end.damage, cut.string() + ": truncated at byte " + std::to_string(n) +
                                   ", inside the bag's index; every message was read from its chunks");
  }
}

TEST(Ros1Bag, EveryCutOfARealSenseBagGivesAPrefixOrAnInputError) {
  VDMAP_REQUIRE_BAG(file, kRealSenseBag);
  const auto whole_bag = Ros1Bag::open(file);
  const ScanResult whole = scanAll(*whole_bag);
  const std::string bytes = test::readFile(file);
  // The format line, the bag header's length, fields and data length: a bag cut before their end
  // holds nothing.
  std::uint32_t header_len = 0;
  std::memcpy(&header_len, bytes.data() + 13, 4);
  const std::uint64_t readable = 13 + 4 + header_len + 4;
  test::TempDir tmp;
  const fs::path cut = tmp / "cut.bag";
  for (std::uint64_t n = 0; n < bytes.size(); n += n < 200 ? 7 : bytes.size() / 97) {
    writeCut(bytes, n, cut);
    if (n < readable) {
      EXPECT_THROW(Ros1Bag::open(cut), InputError) << n;
    } else {
      expectCutGivesAPrefix(*whole_bag, whole, cut, n, 0);
    }
  }
}

TEST(Ros1Bag, DamagedIndexIsRebuiltFromTheChunks) {
  VDMAP_REQUIRE_BAG(file, kRealSenseBag);
  const ScanResult whole = scanAll(*Ros1Bag::open(file));
  std::string bytes = test::readFile(file);
  const std::uint64_t index = indexPos(file);
  test::TempDir tmp;
  const fs::path damaged = tmp / "damaged.bag";
  // The first connection record's header length, made absurd.
  for (int i = 0; i < 4; ++i) bytes[index + i] = '\xff';
  test::writeText(damaged, bytes);
  const auto bag = Ros1Bag::open(damaged);
  const ScanResult scan = scanAll(*bag);
  EXPECT_EQ(scan.messages, whole.messages);
  EXPECT_FALSE(scan.end.complete);
  EXPECT_NE(scan.end.damage.find(damaged.string() + ": bad record at byte " + std::to_string(index)), std::string::npos)
      << scan.end.damage;
}

TEST(Ros1Bag, DamagedChunkEndsTheScanWithANote) {
  VDMAP_REQUIRE_BAG(file, kRealSenseBag);
  const auto whole_bag = Ros1Bag::open(file);
  const ScanResult whole = scanAll(*whole_bag);
  // The chunk of the last depth image (the second of two chunks): its compressed data overwritten
  // in the middle.
  const int depth = topicIndex(*whole_bag, "/device_0/sensor_0/Depth_0/image/data");
  const auto last_depth =
      std::find_if(whole.messages.rbegin(), whole.messages.rend(), [&](const Seen& m) { return m.topic == depth; });
  ASSERT_NE(last_depth, whole.messages.rend());
  const std::uint64_t chunk = last_depth->ref.position;
  ASSERT_NE(chunk, whole.messages.front().ref.position);
  std::string bytes = test::readFile(file);
  test::TempDir tmp;
  const fs::path damaged = tmp / "damaged.bag";
  for (std::uint64_t i = chunk + 1000; i < chunk + 1200; ++i) bytes[i] = '\x5a';
  test::writeText(damaged, bytes);
  const auto bag = Ros1Bag::open(damaged);  // the index is whole: the damage shows in the scan
  const ScanResult scan = scanAll(*bag);
  EXPECT_FALSE(scan.end.complete);
  EXPECT_NE(scan.end.damage.find(damaged.string() + ": bad chunk at byte " + std::to_string(chunk)), std::string::npos)
      << scan.end.damage;
  EXPECT_NE(scan.end.damage.find(" s are lost"), std::string::npos) << scan.end.damage;
  ASSERT_LT(scan.messages.size(), whole.messages.size());
  for (std::size_t i = 0; i < scan.messages.size(); ++i) EXPECT_EQ(scan.messages[i], whole.messages[i]);
  EXPECT_THROW(bag->read(last_depth->ref), InputError);
}

TEST(Ros1Bag, NotABagIsAnInputError) {
  test::TempDir tmp;
  const fs::path file = tmp / "x.bag";
  auto expectOpenError = [&](const std::string& bytes, const std::string& what) {
    test::writeText(file, bytes);
    try {
      Ros1Bag::open(file);
      ADD_FAILURE() << "opened " << printable(bytes);
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), file.string() + ": " + what);
    }
  };
  expectOpenError("", "not a ROS 1 bag: it does not start with '#ROSBAG V2.0'");
  expectOpenError("\x89PNG\r\n\x1a\n and more bytes", "not a ROS 1 bag: it does not start with '#ROSBAG V2.0'");
  expectOpenError("#ROSBAG V1.2\nxx", "a ROS bag of format '1.2': only format 2.0 is read");
  expectOpenError("#ROSBAG V2", "truncated at byte 10, inside its '#ROSBAG V2.0' line");
  expectOpenError(std::string("#ROSBAG V2.0\n\x04\0\0\0abcd\0\0\0\0", 25),
                  "no bag header record after '#ROSBAG V2.0' (a header field runs past its header)");
  EXPECT_THROW(Ros1Bag::open(tmp / "missing.bag"), InputError);
}

// --- Bags written here: chunks of each compression, chunks that overlap in time, no index ---------

std::vector<std::uint8_t> float32Message(float value) {
  std::vector<std::uint8_t> bytes(4);
  std::memcpy(bytes.data(), &value, 4);
  return bytes;
}

/// Two topics, the second with two connections (two publishers), over three chunks that overlap
/// in time: message i has value i and is logged at 100 + i seconds.
std::string overlappingBag(const std::string& compression, bool indexed = true) {
  const std::vector<BagConnection> connections = {
      {0, "/a", "std_msgs/Float32"}, {1, "/b", "std_msgs/Float32"}, {5, "/b", "std_msgs/Float32"}};
  auto m = [](std::uint32_t conn, int i) {
    return BagMessage{conn, (100 + i) * 1'000'000'000ll, float32Message(static_cast<float>(i))};
  };
  return BagWriter::write(connections, {{m(0, 0), m(1, 2), m(0, 4)}, {m(5, 1), m(0, 3)}, {m(1, 5), m(5, 6)}},
                          compression, indexed);
}

TEST(Ros1Bag, ReadsEachChunkCompressionInLogTimeOrderAcrossOverlappingChunks) {
  test::TempDir tmp;
  for (const std::string compression : {"none", "bz2"}) {
    SCOPED_TRACE(compression);
    const fs::path file = tmp / (compression + ".bag");
    test::writeText(file, overlappingBag(compression));
    const auto bag = Ros1Bag::open(file);
    EXPECT_EQ(bag->describe(),
              "ROS 1 bag (format 2.0, " + std::string(compression == "none" ? "uncompressed" : "bz2") + " chunks)");
    ASSERT_EQ(bag->topics().size(), 2u);  // the two connections on /b are one topic
    EXPECT_EQ(bag->topics()[0].name, "/a");
    EXPECT_EQ(bag->topics()[0].count, 3u);
    EXPECT_EQ(bag->topics()[1].name, "/b");
    EXPECT_EQ(bag->topics()[1].count, 4u);
    EXPECT_EQ(bag->topics()[1].kind, MessageType::kFloat32);
    std::vector<float> values;
    const ScanEnd end = bag->scan({0, 1}, [&](const Message& m) {
      const float value = detail::decodeFloat32Ros1(*m.bytes);
      EXPECT_EQ(m.log_time_ns, (100 + static_cast<std::int64_t>(value)) * 1'000'000'000);
      EXPECT_EQ(m.topic, value == 0 || value == 3 || value == 4 ? 0 : 1);
      EXPECT_EQ(detail::decodeFloat32Ros1(*bag->read(m.ref).bytes), value);
      values.push_back(value);
      return true;
    });
    EXPECT_TRUE(end.complete) << end.damage;
    EXPECT_EQ(values, (std::vector<float>{0, 1, 2, 3, 4, 5, 6}));
    // Chunks decompressed only as far as asked: the same messages (each shorter than a head).
    std::vector<float> heads;
    EXPECT_TRUE(bag->scanHeads({0, 1}, {0, 1},
                               [&](const Message& m) {
                                 EXPECT_FALSE(m.head_only);
                                 heads.push_back(detail::decodeFloat32Ros1(*m.bytes));
                                 return true;
                               })
                    .complete);
    EXPECT_EQ(heads, values);
  }
}

TEST(Ros1Bag, BagItsRecorderDidNotCloseIsReadWithANote) {
  test::TempDir tmp;
  const fs::path file = tmp / "unindexed.bag";
  test::writeText(file, overlappingBag("bz2", false));
  const auto bag = Ros1Bag::open(file);
  ASSERT_EQ(bag->topics().size(), 2u);
  EXPECT_EQ(bag->topics()[1].count, 4u);
  const ScanResult scan = scanAll(*bag);
  EXPECT_EQ(scan.messages.size(), 7u);
  for (std::size_t i = 1; i < scan.messages.size(); ++i)
    EXPECT_LT(scan.messages[i - 1].log_time_ns, scan.messages[i].log_time_ns);
  EXPECT_FALSE(scan.end.complete);
  EXPECT_EQ(scan.end.damage, file.string() +
                                 ": the bag's index is missing (its recorder did not close it); its messages were "
                                 "found by reading it to the end");
}

TEST(Ros1Bag, IndexPointingOutsideItsChunkIsRebuiltFromTheChunks) {
  test::TempDir tmp;
  const fs::path file = tmp / "bad-index.bag";
  std::string bytes = overlappingBag("none");
  // The first index data record's first entry: its offset made to point past its chunk.
  const auto entry = bytes.find(std::string("ver=\x01\0\0\0", 8), 4096);
  ASSERT_NE(entry, std::string::npos);
  const auto data = bytes.find("count=", entry) + 6 + 4 + 4;  // past the count and the data length
  bytes.replace(data + 8, 4, std::string("\xff\xff\0\0", 4));
  test::writeText(file, bytes);
  const auto bag = Ros1Bag::open(file);
  const ScanResult scan = scanAll(*bag);
  EXPECT_EQ(scan.messages.size(), 7u);
  // The first chunk starts after the format line (13 bytes) and the padded bag header (4096).
  EXPECT_NE(scan.end.damage.find("its index is damaged: the index points past the end of the chunk at byte 4109"),
            std::string::npos)
      << scan.end.damage;
}

// --- The ROS 1 decoders on bytes that are not their message ------------------------------------

/// Every proper prefix of `bytes` throws std::runtime_error from `decode` (all of them up to
/// 400 bytes, then 200 spread over the rest).
template <typename Decode>
void expectEveryPrefixThrows(const std::vector<std::uint8_t>& bytes, Decode decode) {
  ASSERT_NO_THROW(decode(bytes));
  std::vector<std::size_t> lengths;
  for (std::size_t n = 0; n < std::min<std::size_t>(bytes.size(), 400); ++n) lengths.push_back(n);
  for (std::size_t n = 400; n < bytes.size(); n += std::max<std::size_t>(1, bytes.size() / 200)) lengths.push_back(n);
  lengths.push_back(bytes.size() - 1);
  for (const std::size_t n : lengths) {
    const std::vector<std::uint8_t> prefix(bytes.begin(), bytes.begin() + n);
    EXPECT_THROW(decode(prefix), std::runtime_error) << n << " of " << bytes.size() << " bytes";
  }
}

/// ROS 1 serialisation of fields, to make messages the bags do not hold.

TEST(Ros1Messages, EveryPrefixOfARealMessageThrows) {
  VDMAP_REQUIRE_BAG(file, kRealSenseBag);
  const auto bag = Ros1Bag::open(file);
  expectEveryPrefixThrows(firstMessage(*bag, "/device_0/sensor_0/Depth_0/image/data"),
                          [](const auto& b) { return detail::decodeImageRos1(b); });
  expectEveryPrefixThrows(firstMessage(*bag, "/device_0/sensor_0/Depth_0/info/camera_info"),
                          [](const auto& b) { return detail::decodeCameraInfoRos1(b); });
  expectEveryPrefixThrows(firstMessage(*bag, "/device_0/sensor_0/Depth_0/tf/0"),
                          [](const auto& b) { return detail::decodeTransformsRos1(b, MessageType::kTransform); });
  expectEveryPrefixThrows(firstMessage(*bag, "/device_0/sensor_0/option/Depth Units/value"),
                          [](const auto& b) { return detail::decodeFloat32Ros1(b); });
}

TEST(Ros1Messages, EveryPrefixOfATfMessageThrows) {
  VDMAP_REQUIRE_BAG(file, kTumBag);
  const auto bag = Ros1Bag::open(file);
  expectEveryPrefixThrows(firstMessage(*bag, "/tf"),
                          [](const auto& b) { return detail::decodeTransformsRos1(b, MessageType::kTfMessage); });
}

TEST(Ros1Messages, PosesTransformsAndCompressedImages) {
  const auto pose = Ros1Bytes().header(12, 500'000'000, "map").pose(1, 2, 3, 0, 0, 0.6, 0.8).bytes;
  const PoseStamped p = detail::decodePoseRos1(pose, MessageType::kPoseStamped);
  EXPECT_EQ(p.header.stamp, 12.5);
  EXPECT_EQ(p.header.frame_id, "map");
  EXPECT_EQ(p.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.orientation.coeffs(), Eigen::Vector4d(0, 0, 0.6, 0.8));
  expectEveryPrefixThrows(pose, [](const auto& b) { return detail::decodePoseRos1(b, MessageType::kPoseStamped); });

  Ros1Bytes odometry;
  odometry.header(3, 0, "odom").text("base_link").pose(4, 5, 6, 0, 0, 0, 1);
  for (int i = 0; i < 36 + 6 + 36; ++i) odometry.put(0.0);  // pose covariance, twist, twist covariance
  const PoseStamped o = detail::decodePoseRos1(odometry.bytes, MessageType::kOdometry);
  EXPECT_EQ(o.child_frame_id, "base_link");
  EXPECT_EQ(o.position, Eigen::Vector3d(4, 5, 6));
  expectEveryPrefixThrows(odometry.bytes,
                          [](const auto& b) { return detail::decodePoseRos1(b, MessageType::kOdometry); });

  const auto stamped = Ros1Bytes().header(1, 0, "a").text("b").pose(1, 0, 0, 0, 0, 0, 1).bytes;
  const auto t = detail::decodeTransformsRos1(stamped, MessageType::kTransformStamped);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].child_frame_id, "b");
  EXPECT_EQ(t[0].translation, Eigen::Vector3d(1, 0, 0));
  expectEveryPrefixThrows(
      stamped, [](const auto& b) { return detail::decodeTransformsRos1(b, MessageType::kTransformStamped); });

  const auto jpeg = Ros1Bytes().header(2, 0, "cam").text("jpeg").text("\xff\xd8\xff").bytes;
  const CompressedImage c = detail::decodeCompressedImageRos1(jpeg);
  EXPECT_EQ(c.format, "jpeg");
  EXPECT_EQ(std::vector<std::uint8_t>(c.data.begin(), c.data.end()), (std::vector<std::uint8_t>{0xff, 0xd8, 0xff}));
  expectEveryPrefixThrows(jpeg, [](const auto& b) { return detail::decodeCompressedImageRos1(b); });

  EXPECT_THROW(detail::decodePoseRos1(pose, MessageType::kImage), std::runtime_error);
  EXPECT_THROW(detail::decodeTransformsRos1(pose, MessageType::kOther), std::runtime_error);
}

TEST(Ros1Messages, GiantLengthsAreRefusedBeforeAnythingIsAllocated) {
  // A TFMessage claiming four billion transforms in 8 bytes.
  const auto tf = Ros1Bytes().put(std::uint32_t{0xFFFFFFFF}).put(std::uint32_t{0}).bytes;
  try {
    detail::decodeTransformsRos1(tf, MessageType::kTfMessage);
    ADD_FAILURE() << "decoded";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "field 'transforms' claims 4294967295 elements, the message holds 4 bytes more");
  }
  // An image whose data claim 4 GiB, and one whose data are shorter than height * step.
  const auto image = Ros1Bytes().header(0, 0, "").put(2u).put(2u).text("mono8").put(std::uint8_t{0}).put(2u);
  auto giant = image;
  giant.put(std::uint32_t{0xFFFFFFF0}).put(std::uint32_t{0});
  try {
    detail::decodeImageRos1(giant.bytes);
    ADD_FAILURE() << "decoded";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "message ends inside field 'data'");
  }
  auto short_data = image;
  short_data.text("abc");
  try {
    detail::decodeImageRos1(short_data.bytes);
    ADD_FAILURE() << "decoded";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "image data holds 3 bytes, height * step needs 4");
  }
  // Camera intrinsics with a distortion vector longer than the message.
  const auto info = Ros1Bytes().header(0, 0, "").put(1u).put(1u).text("plumb_bob").put(std::uint32_t{1u << 30}).bytes;
  EXPECT_THROW(detail::decodeCameraInfoRos1(info), std::runtime_error);
}

}  // namespace vdmap::ros::ros1_bag_test
