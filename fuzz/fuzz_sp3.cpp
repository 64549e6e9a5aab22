// SP3-c/d precise orbit files (orbits::parse_sp3).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "skytrace/orbits/precise.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::orbits::parse_sp3("fuzz.sp3", skytrace::fuzz::as_string(data, size));
  return 0;
}
