// The MCAP reader and the CDR decoders (fuzz_recording.h). Seeds written without CRCs (a CRC of 0
// means "not computed") let mutations reach the record parsers; with CRCs, nearly every mutation
// stops at the check.
#include "fuzz/fuzz_input.h"
#include "fuzz/fuzz_recording.h"
#include "mapping/ros/mcap_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = vdmap::fuzz::writeInput(data, size, "recording.mcap");
  VDMAP_FUZZ_EXPECTED_ERRORS(vdmap::fuzz::scanEveryMessage(*vdmap::ros::McapFile::open(file)));
  // The same bytes as each CDR message type.
  const std::vector<std::uint8_t> bytes(data, data + size);
  for (int type = 0; type < static_cast<int>(vdmap::ros::MessageType::kOther); ++type)
    vdmap::fuzz::decodeAs(bytes, vdmap::ros::Encoding::kCdr, static_cast<vdmap::ros::MessageType>(type));
  return 0;
}
