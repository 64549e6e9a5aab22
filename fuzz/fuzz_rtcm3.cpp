// RTCM 3 byte streams: transport frames (io::rtcm3_split_frames) and the fields of their messages
// (io::BitReader). skytrace only encodes messages, so the decoding side is these two; every frame
// found must also survive framing again unchanged.
#include <cstddef>
#include <cstdint>
#include <span>

#include "skytrace/io/rtcm3.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace skytrace::io;
  const std::span<const std::uint8_t> stream(data, size);
  for (const Rtcm3Frame& frame : rtcm3_split_frames(stream)) {
    BitReader header(frame.message);
    const auto number = static_cast<int>(header.get_unsigned(12));
    if (frame.message.size() >= 2 && number != frame.message_number) __builtin_trap();
    auto again = rtcm3_frame(frame.message);
    if (!again.ok()) __builtin_trap();  // a frame found holds at most 1023 bytes
    const auto refound = rtcm3_split_frames(*again);
    if (refound.size() != 1 || refound.front().message != frame.message) __builtin_trap();
  }
  // Fields of every kind and width (0-64 bits, the widths taken from the data) until the end.
  if (size == 0) return 0;
  BitReader reader(stream);
  for (std::size_t k = 0; k <= 8 * size && !reader.overrun(); ++k) {
    const int bits = data[k % size] % 65;
    switch (k % 3) {
      case 0: (void)reader.get_unsigned(bits); break;
      case 1: (void)reader.get_signed(bits); break;
      default: (void)reader.get_sign_magnitude(bits); break;
    }
  }
  return 0;
}
