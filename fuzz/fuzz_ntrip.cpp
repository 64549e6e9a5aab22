// The NTRIP caster's answer as `skytrace serve --rtk-base-ntrip` and the ROS nodes' rtk_base read it
// from the network (io::NtripResponse: status line, headers, chunked transfer, source tables), and
// ntrip:// addresses (io::parse_ntrip_url). The first byte sets the size of the pieces the answer
// arrives in, as a socket would cut it.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "skytrace/io/ntrip.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::size_t piece = 1 + data[0] % 64;
  const std::string_view answer(reinterpret_cast<const char*>(data + 1), size - 1);
  skytrace::io::NtripResponse response;
  std::size_t streamed = 0;
  for (std::size_t at = 0; at < answer.size(); at += piece) {
    streamed += response.feed(answer.substr(at, std::min(piece, answer.size() - at))).size();
  }
  response.connection_closed();
  // What comes out of the stream is never more than what went in.
  if (streamed > answer.size()) __builtin_trap();
  const std::string_view first_line = answer.substr(0, answer.find('\n'));
  if (auto endpoint = skytrace::io::parse_ntrip_url(first_line)) {
    (void)skytrace::io::ntrip_request(*endpoint, "fuzz");
    (void)skytrace::io::ntrip_url_for_display(*endpoint);
  }
  return 0;
}
