// IONEX global ionosphere maps (atmosphere::parse_ionex).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "skytrace/atmosphere/ionex.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::atmosphere::parse_ionex("fuzz.inx", skytrace::fuzz::as_string(data, size));
  return 0;
}
