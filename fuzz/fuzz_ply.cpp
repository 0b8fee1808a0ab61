// The PLY reader: the same bytes as a coloured mesh and as an ellipsoid map.
#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"
#include "mapping/files/ply_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = vdmap::fuzz::writeInput(data, size, "map.ply");
  VDMAP_FUZZ_EXPECTED_ERRORS(vdmap::readPlyMesh(file));
  VDMAP_FUZZ_EXPECTED_ERRORS(vdmap::readPlyEllipsoids(file));
  return 0;
}
