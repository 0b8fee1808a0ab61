// The camera-file parser (YAML and JSON).
#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"
#include "mapping/io/camera_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  VDMAP_FUZZ_EXPECTED_ERRORS(vdmap::readCameraFile(vdmap::fuzz::writeInput(data, size, "camera.yaml")));
  return 0;
}
