// The .vdmap loader. Checksums are not verified, so that mutated bytes reach every section
// parser (with checksums on, almost every mutation stops at the checksum). A decoded session
// must re-encode to the same bytes.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "mapping/core/error.h"
#include "mapping/files/session_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vdmap;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const Session s = decodeSession(bytes, "fuzz.vdmap", {.verify_checksums = false});
    // Re-encoding writes fresh checksums: the same size, and from then on an exact round trip.
    const std::string again = encodeSession(s.graph, s.info);
    if (again.size() != bytes.size()) std::abort();
    const Session t = decodeSession(again, "again.vdmap");
    if (encodeSession(t.graph, t.info) != again) std::abort();
  } catch (const InputError&) {
  }
  return 0;
}
