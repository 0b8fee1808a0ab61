// The TUM trajectory (pose) parser.
#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"
#include "mapping/io/trajectory_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  VDMAP_FUZZ_EXPECTED_ERRORS(vdmap::readTumTrajectory(vdmap::fuzz::writeInput(data, size, "poses.txt")));
  return 0;
}
