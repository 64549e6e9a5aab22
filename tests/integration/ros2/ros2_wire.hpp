// The ROS 2 messages of the node's tests, encoded and decoded with eProsima Fast CDR from the
// message definitions (common_interfaces, geometry2, rmw_dds_common, nmea_msgs, rtcm_msgs,
// gnss_comm, skytrace_msgs): independent of skytrace's own CDR code, which they check. Decoders
// throw std::runtime_error when a message is shorter than its definition, and report the bytes
// left over so that tests can check that the whole payload was read.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace skytrace::test::ros2_wire {

using Bytes = std::vector<std::uint8_t>;

struct Time {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  [[nodiscard]] double seconds() const { return sec + 1e-9 * nanosec; }
};
struct Header {
  Time stamp;
  std::string frame_id;
};
struct Vector3 {
  double x = 0, y = 0, z = 0;
};
struct Quaternion {
  double x = 0, y = 0, z = 0, w = 1;
};

struct NavSatFix {
  Header header;
  std::int8_t status = 0;
  std::uint16_t service = 0;
  double latitude = 0, longitude = 0, altitude = 0;
  std::array<double, 9> position_covariance{};
  std::uint8_t position_covariance_type = 0;
};
struct TwistWithCovarianceStamped {
  Header header;
  Vector3 linear, angular;
  std::array<double, 36> covariance{};
};
struct TimeReference {
  Header header;
  Time time_ref;
  std::string source;
};
struct Sentence {
  Header header;
  std::string sentence;
};
struct RtcmMessage {
  Header header;
  Bytes message;
};
struct GnssObs {
  std::uint32_t week = 0;
  double tow = 0;
  std::uint32_t sat = 0;
  std::vector<double> freqs, cn0;
  Bytes lli, code;
  std::vector<double> psr, psr_std, cp, cp_std, dopp, dopp_std;
  Bytes status;
};
struct GnssMeas {
  std::vector<GnssObs> meas;
};
struct GnssEphem {
  std::uint32_t sat = 0;
  std::uint32_t toe_week = 0;
  double toe_tow = 0, toe_tow_field = 0;
  std::uint32_t week = 0, iode = 0, health = 0;
  double A = 0, e = 0, af0 = 0;
};
struct GnssGloEphem {
  std::uint32_t sat = 0;
  std::uint32_t toe_week = 0;
  double toe_tow = 0;
  std::int32_t freqo = 0;
  double pos_x = 0, pos_y = 0, pos_z = 0;
  double tau_n = 0;
};
struct Observation {
  std::string satellite, system, signal;
  std::uint16_t prn = 0;
  double pseudorange_m = 0, cn0_dbhz = 0, elevation_deg = 0;
  bool los = false;
};
struct Observations {
  Header header;
  std::uint32_t gps_week = 0;
  double gps_tow_s = 0;
  bool restarted = false, pose_stale = false;
  std::vector<Observation> observations;
};
struct SatelliteSky {
  std::string satellite;
  double elevation_deg = 0;
  std::uint8_t status = 0;
  bool used_in_fix = false;
};
struct Sky {
  Header header;
  std::vector<SatelliteSky> satellites;
};
struct Marker {
  Header header;
  std::string ns;
  std::int32_t type = 0, action = 0;
  size_t points = 0, colors = 0;
};
struct MarkerArray {
  std::vector<Marker> markers;
};
struct NodeEntities {
  std::string node_namespace, node_name;
  std::vector<Bytes> reader_gids, writer_gids;
};
struct ParticipantEntities {
  Bytes gid;
  std::vector<NodeEntities> nodes;
};

// Each decoder sets `left_over` to the bytes after the message (the writer's padding, 0-3).
NavSatFix decode_navsat_fix(const Bytes& cdr, size_t& left_over);
TwistWithCovarianceStamped decode_twist(const Bytes& cdr, size_t& left_over);
TimeReference decode_time_reference(const Bytes& cdr, size_t& left_over);
Sentence decode_sentence(const Bytes& cdr, size_t& left_over);
RtcmMessage decode_rtcm(const Bytes& cdr, size_t& left_over);
GnssMeas decode_gnss_meas(const Bytes& cdr, size_t& left_over);
GnssEphem decode_gnss_ephem(const Bytes& cdr, size_t& left_over);
GnssGloEphem decode_gnss_glo_ephem(const Bytes& cdr, size_t& left_over);
Observations decode_observations(const Bytes& cdr, size_t& left_over);
Sky decode_sky(const Bytes& cdr, size_t& left_over);
MarkerArray decode_marker_array(const Bytes& cdr, size_t& left_over);
// Humble's Gid is char[24], Jazzy's char[16].
ParticipantEntities decode_participant_entities(const Bytes& cdr, size_t gid_size, size_t& left_over);

Bytes encode_clock(const Time& clock);
struct Transform {
  Header header;
  std::string child_frame_id;
  Vector3 translation;
  Quaternion rotation;
};
Bytes encode_tf(const std::vector<Transform>& transforms);
Bytes encode_pose_stamped(const Header& header, const Vector3& position, const Quaternion& orientation);
Bytes encode_odometry(const Header& header, const std::string& child_frame_id, const Vector3& position,
                      const Quaternion& orientation, const Vector3& linear_velocity);

// CRC-24Q of RTCM 3 frames (polynomial 0x1864CFB), written here from the standard.
std::uint32_t crc24q(const std::uint8_t* data, size_t size);

}  // namespace skytrace::test::ros2_wire
