// RINEX observation files, versions 2.10/2.11, 3.0x and 4.0x (io::parse_rinex_obs).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "skytrace/io/rinex_obs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto file = skytrace::io::parse_rinex_obs("fuzz.rnx", skytrace::fuzz::as_string(data, size));
  if (file.ok()) {
    // The lookups a user of the file makes first.
    for (const auto& [system, types] : file->header.observation_types) {
      for (const auto& type : types) (void)file->header.type_index(system, type.code);
    }
  }
  return 0;
}
