// The ROS 1 bag reader and the ROS 1 decoders (fuzz_recording.h).
#include "fuzz/fuzz_input.h"
#include "fuzz/fuzz_recording.h"
#include "mapping/ros/ros1_bag.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = vdmap::fuzz::writeInput(data, size, "recording.bag");
  VDMAP_FUZZ_EXPECTED_ERRORS(vdmap::fuzz::scanEveryMessage(*vdmap::ros::Ros1Bag::open(file)));
  // The same bytes as each ROS 1 message type.
  const std::vector<std::uint8_t> bytes(data, data + size);
  for (int type = 0; type < static_cast<int>(vdmap::ros::MessageType::kOther); ++type)
    vdmap::fuzz::decodeAs(bytes, vdmap::ros::Encoding::kRos1, static_cast<vdmap::ros::MessageType>(type));
  return 0;
}
