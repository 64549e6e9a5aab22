// Receiver profile YAML (receiver::parse_profile).
#include <cstddef>
#include <cstdint>

#include "fuzz_support.hpp"
#include "skytrace/receiver/profile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::receiver::parse_profile(skytrace::fuzz::as_string(data, size), "fuzz.yaml");
  return 0;
}
