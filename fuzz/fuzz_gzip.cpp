// gzip data: downloaded bodies (orbits::gunzip) and compressed input files (read_text_file, which
// decompresses through zlib's file interface).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_support.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/orbits/fetch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const skytrace::fuzz::TempInputFile file(".gz");
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  (void)skytrace::orbits::gunzip(bytes);
  if (file.write(bytes)) (void)skytrace::read_text_file(file.path());
  return 0;
}
