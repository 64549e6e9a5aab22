// RTCM 3 byte streams as a base station's link delivers them (skytrace serve --rtk-base-*, the ROS
// nodes' rtk_base, skytrace position --base FILE.rtcm3): transport frames
// (io::rtcm3_split_frames), the fields of their messages (io::BitReader), and the decoder of station
// and MSM messages into base epochs (io::Rtcm3Decoder, io::RtcmMeasurementConverter), fed in
// pieces as a socket cuts the stream. Every frame found must also survive framing again unchanged.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

#include "skytrace/core/time.hpp"
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
  if (size == 0) return 0;
  // The decoder, fed in pieces of 1-64 bytes (the first byte says how large), then flushed.
  static const auto reference = skytrace::GnssTime::parse_iso8601("2020-06-25T00:00:00", skytrace::TimeScale::kGpst);
  if (!reference.ok()) __builtin_trap();
  Rtcm3Decoder decoder(*reference);
  RtcmMeasurementConverter converter;
  const std::size_t piece = 1 + data[0] % 64;
  for (std::size_t at = 0; at < size; at += piece) {
    decoder.feed(stream.subspan(at, std::min(piece, size - at)));
    for (const auto& epoch : decoder.take_epochs()) (void)converter.convert(epoch);
  }
  decoder.finish();
  for (const auto& epoch : decoder.take_epochs()) (void)converter.convert(epoch);
  // Fields of every kind and width (0-64 bits, the widths taken from the data) until the end.
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
