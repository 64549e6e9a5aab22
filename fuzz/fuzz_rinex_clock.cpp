// RINEX clock files (orbits::parse_rinex_clock).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "skytrace/orbits/precise.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::orbits::parse_rinex_clock("fuzz.clk", skytrace::fuzz::as_string(data, size));
  return 0;
}
