// Antenna poses as text datagrams (`skytrace serve --pose-udp`), apart from the live session so
// that a parser of outside input can be tested and fuzzed alone.
#include <fmt/format.h>

#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "skytrace/core/frames.hpp"
#include "skytrace/sim/live.hpp"

namespace skytrace::sim {

Result<PoseDatagram> parse_pose_datagram(std::string_view text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.remove_suffix(1);
  std::istringstream in{std::string(text)};
  std::string kind;
  in >> kind;
  std::vector<double> values;
  for (std::string token; in >> token;) {
    try {
      size_t used = 0;
      values.push_back(std::stod(token, &used));
      if (used != token.size()) throw std::invalid_argument(token);
    } catch (const std::exception&) {
      return make_error(ErrorCode::kParse, fmt::format("pose datagram '{}': '{}' is not a number", text, token));
    }
  }
  PoseDatagram pose;
  if (kind == "llh" && values.size() == 3) {
    pose.position = geodetic_to_ecef(Geodetic{values[0], values[1], values[2]});
    return pose;
  }
  if ((kind == "ecef" || kind == "world") && (values.size() == 3 || values.size() == 6)) {
    pose.frame = kind == "ecef" ? PoseDatagram::Frame::kEcef : PoseDatagram::Frame::kWorld;
    pose.position = Eigen::Vector3d(values[0], values[1], values[2]);
    if (values.size() == 6) pose.velocity = Eigen::Vector3d(values[3], values[4], values[5]);
    return pose;
  }
  return make_error(ErrorCode::kParse,
                    fmt::format("pose datagram '{}': expected 'ecef X Y Z [VX VY VZ]', 'world X Y Z [VX VY VZ]' "
                                "or 'llh LAT LON H'",
                                text));
}

}  // namespace skytrace::sim
