// The query records reader (`vdmap query --points`): the same bytes as a text file and as a PLY,
// read for each kind of record (points, spheres, rays) in small batches, as the verb streams them.
#include "app/query_files/query_io.h"
#include "fuzz/fuzz_input.h"
#include "mapping/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using vdmap::app::QueryOp;
  for (const char* name : {"points.txt", "points.ply"}) {
    const std::filesystem::path file = vdmap::fuzz::writeInput(data, size, name);
    for (const QueryOp op : {QueryOp::kClassify, QueryOp::kCollide, QueryOp::kRay}) {
      const auto read_all = [&] {
        vdmap::app::QueryRecordReader reader(file, op, 10.0);
        vdmap::app::QueryInput batch;
        while (reader.next(7, &batch)) {
        }
      };
      VDMAP_FUZZ_EXPECTED_ERRORS(read_all());
    }
  }
  return 0;
}
