// Unix compress (.Z) data, the format of older IGS archive products (orbits::uncompress_lzw).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "skytrace/orbits/fetch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::orbits::uncompress_lzw(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
