// The TUM list parser: the input is a sequence's depth.txt (its rgb.txt and groundtruth.txt are
// valid), then the same bytes as an associations.txt, through Sequence::open.
#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"
#include "mapping/sequence/sequence.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vdmap;
  const std::filesystem::path list = fuzz::writeInput(data, size, "seq/depth.txt");
  const std::filesystem::path folder = list.parent_path();
  static const bool once = [&folder] {
    std::ofstream(folder / "rgb.txt") << "0.0 rgb/0.png\n0.5 rgb/1.png\n";
    std::ofstream(folder / "groundtruth.txt") << "0.0 0 0 0 0 0 0 1\n1.0 1 0 0 0 0 0 1\n";
    std::ofstream(folder / "camera.yaml") << "preset: tum-fr1\n";
    return true;
  }();
  (void)once;
  VDMAP_FUZZ_EXPECTED_ERRORS(Sequence::open(folder));
  // Written like the input, not by std::filesystem::copy_file: on CI that threw once (the copy
  // left an empty associations.txt), a failure of the harness that libFuzzer reported as a crash.
  fuzz::writeInput(data, size, "seq/associations.txt");
  VDMAP_FUZZ_EXPECTED_ERRORS(Sequence::open(folder));
  std::filesystem::remove(folder / "associations.txt");
  return 0;
}
