// RINEX navigation files, versions 2.x, 3.0x and 4.0x (orbits::parse_rinex_nav).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "skytrace/orbits/rinex_nav.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::orbits::parse_rinex_nav("fuzz.rnx", skytrace::fuzz::as_string(data, size));
  return 0;
}
