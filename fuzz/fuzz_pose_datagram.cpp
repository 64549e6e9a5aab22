// Antenna poses received as UDP datagrams by `skytrace serve --pose-udp` (sim::parse_pose_datagram).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "skytrace/sim/live.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)skytrace::sim::parse_pose_datagram(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
