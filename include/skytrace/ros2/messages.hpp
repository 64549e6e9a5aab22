// The ROS 2 messages skytrace publishes and reads, field for field as the public packages define
// them in Humble and Jazzy (common_interfaces, rcl_interfaces, geometry2, rmw_dds_common,
// nmea_msgs, rtcm_msgs, gnss_comm; docs/ros2.md gives the versions), with their CDR encoding and
// their definition text as rosbag2 stores it in MCAP schemas. No ROS 2 install is needed: the DDS
// node and the MCAP sink both put these bytes on the wire or into the file.
//
// Every struct names its ROS type (`kType`, "pkg/msg/Name"); dds_type_name() gives the name DDS
// sees ("pkg::msg::dds_::Name_"). serialize() gives the CDR bytes with the encapsulation header;
// deserialize() checks every length against the message size.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/ros2/cdr.hpp"

namespace skytrace::ros2 {

// --- builtin_interfaces, std_msgs, rosgraph_msgs -------------------------------------------------
struct Time {
  static constexpr std::string_view kType = "builtin_interfaces/msg/Time";
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  // Seconds since the epoch of the clock (ROS time); rounds to the nanosecond.
  [[nodiscard]] static Time from_seconds(double seconds);
  [[nodiscard]] double seconds() const { return sec + 1e-9 * nanosec; }
  [[nodiscard]] std::int64_t nanoseconds() const { return std::int64_t{sec} * 1000000000 + nanosec; }
};
struct Duration {
  static constexpr std::string_view kType = "builtin_interfaces/msg/Duration";
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};
struct Header {
  static constexpr std::string_view kType = "std_msgs/msg/Header";
  Time stamp;
  std::string frame_id;
};
struct ColorRGBA {
  static constexpr std::string_view kType = "std_msgs/msg/ColorRGBA";
  float r = 0, g = 0, b = 0, a = 0;
};
struct Clock {
  static constexpr std::string_view kType = "rosgraph_msgs/msg/Clock";
  Time clock;
};

// --- geometry_msgs, nav_msgs, tf2_msgs -----------------------------------------------------------
struct Vector3 {
  static constexpr std::string_view kType = "geometry_msgs/msg/Vector3";
  double x = 0, y = 0, z = 0;
};
struct Point {
  static constexpr std::string_view kType = "geometry_msgs/msg/Point";
  double x = 0, y = 0, z = 0;
};
struct Quaternion {
  static constexpr std::string_view kType = "geometry_msgs/msg/Quaternion";
  double x = 0, y = 0, z = 0, w = 1;
};
struct Pose {
  static constexpr std::string_view kType = "geometry_msgs/msg/Pose";
  Point position;
  Quaternion orientation;
};
struct PoseStamped {
  static constexpr std::string_view kType = "geometry_msgs/msg/PoseStamped";
  Header header;
  Pose pose;
};
struct PoseWithCovariance {
  static constexpr std::string_view kType = "geometry_msgs/msg/PoseWithCovariance";
  Pose pose;
  std::array<double, 36> covariance{};
};
struct Twist {
  static constexpr std::string_view kType = "geometry_msgs/msg/Twist";
  Vector3 linear, angular;
};
struct TwistWithCovariance {
  static constexpr std::string_view kType = "geometry_msgs/msg/TwistWithCovariance";
  Twist twist;
  std::array<double, 36> covariance{};
};
struct TwistWithCovarianceStamped {
  static constexpr std::string_view kType = "geometry_msgs/msg/TwistWithCovarianceStamped";
  Header header;
  TwistWithCovariance twist;
};
struct Transform {
  static constexpr std::string_view kType = "geometry_msgs/msg/Transform";
  Vector3 translation;
  Quaternion rotation;
};
struct TransformStamped {
  static constexpr std::string_view kType = "geometry_msgs/msg/TransformStamped";
  Header header;
  std::string child_frame_id;
  Transform transform;
};
struct TFMessage {
  static constexpr std::string_view kType = "tf2_msgs/msg/TFMessage";
  std::vector<TransformStamped> transforms;
};
struct Odometry {
  static constexpr std::string_view kType = "nav_msgs/msg/Odometry";
  Header header;
  std::string child_frame_id;
  PoseWithCovariance pose;
  TwistWithCovariance twist;
};

// --- sensor_msgs ----------------------------------------------------------------------------------
struct NavSatStatus {
  static constexpr std::string_view kType = "sensor_msgs/msg/NavSatStatus";
  static constexpr std::int8_t kStatusUnknown = -2;  // Jazzy and later
  static constexpr std::int8_t kStatusNoFix = -1;
  static constexpr std::int8_t kStatusFix = 0;
  static constexpr std::int8_t kStatusSbasFix = 1;
  static constexpr std::int8_t kStatusGbasFix = 2;
  static constexpr std::uint16_t kServiceGps = 1;
  static constexpr std::uint16_t kServiceGlonass = 2;
  static constexpr std::uint16_t kServiceCompass = 4;  // includes BeiDou
  static constexpr std::uint16_t kServiceGalileo = 8;
  std::int8_t status = kStatusNoFix;
  std::uint16_t service = 0;
};
struct NavSatFix {
  static constexpr std::string_view kType = "sensor_msgs/msg/NavSatFix";
  static constexpr std::uint8_t kCovarianceUnknown = 0;
  static constexpr std::uint8_t kCovarianceApproximated = 1;
  static constexpr std::uint8_t kCovarianceDiagonalKnown = 2;
  static constexpr std::uint8_t kCovarianceKnown = 3;
  Header header;
  NavSatStatus status;
  double latitude = 0, longitude = 0, altitude = 0;  // degrees, metres above the WGS84 ellipsoid
  std::array<double, 9> position_covariance{};       // m^2, east-north-up, row-major
  std::uint8_t position_covariance_type = kCovarianceUnknown;
};
struct TimeReference {
  static constexpr std::string_view kType = "sensor_msgs/msg/TimeReference";
  Header header;
  Time time_ref;
  std::string source;
};
struct CompressedImage {
  static constexpr std::string_view kType = "sensor_msgs/msg/CompressedImage";
  Header header;
  std::string format;
  std::vector<std::uint8_t> data;
};

// --- nmea_msgs, rtcm_msgs -------------------------------------------------------------------------
struct NmeaSentence {
  static constexpr std::string_view kType = "nmea_msgs/msg/Sentence";
  Header header;
  std::string sentence;
};
struct RtcmMessage {
  static constexpr std::string_view kType = "rtcm_msgs/msg/Message";
  Header header;
  std::vector<std::uint8_t> message;
};

// --- visualization_msgs ---------------------------------------------------------------------------
struct UVCoordinate {
  static constexpr std::string_view kType = "visualization_msgs/msg/UVCoordinate";
  float u = 0, v = 0;
};
struct MeshFile {
  static constexpr std::string_view kType = "visualization_msgs/msg/MeshFile";
  std::string filename;
  std::vector<std::uint8_t> data;
};
struct Marker {
  static constexpr std::string_view kType = "visualization_msgs/msg/Marker";
  static constexpr std::int32_t kLineList = 5;
  static constexpr std::int32_t kActionAdd = 0;
  static constexpr std::int32_t kActionDeleteAll = 3;
  Header header;
  std::string ns;
  std::int32_t id = 0, type = 0, action = 0;
  Pose pose;
  Vector3 scale;
  ColorRGBA color;
  Duration lifetime;
  bool frame_locked = false;
  std::vector<Point> points;
  std::vector<ColorRGBA> colors;
  std::string texture_resource;
  CompressedImage texture;
  std::vector<UVCoordinate> uv_coordinates;
  std::string text;
  std::string mesh_resource;
  MeshFile mesh_file;
  bool mesh_use_embedded_materials = false;
};
struct MarkerArray {
  static constexpr std::string_view kType = "visualization_msgs/msg/MarkerArray";
  std::vector<Marker> markers;
};

// --- gnss_comm (GVINS and other GNSS-fusion estimators) -------------------------------------------
// gnss_comm is a ROS 1 package; ROS 2 (rosidl) accepts lower-case field names only, so its
// messages in ROS 2 name CN0, LLI, A, OMG0, OMG_dot and A_dot in lower case. Field order and types,
// hence the bytes on the wire, are those of gnss_comm.
struct GnssTimeMsg {
  static constexpr std::string_view kType = "gnss_comm/msg/GnssTimeMsg";
  std::uint32_t week = 0;
  double tow = 0;
};
struct GnssObsMsg {
  static constexpr std::string_view kType = "gnss_comm/msg/GnssObsMsg";
  GnssTimeMsg time;
  std::uint32_t sat = 0;  // gnss_comm's sat_no()
  std::vector<double> freqs, cn0;
  std::vector<std::uint8_t> lli, code;
  std::vector<double> psr, psr_std, cp, cp_std, dopp, dopp_std;
  std::vector<std::uint8_t> status;
};
struct GnssMeasMsg {
  static constexpr std::string_view kType = "gnss_comm/msg/GnssMeasMsg";
  std::vector<GnssObsMsg> meas;
};
struct GnssEphemMsg {
  static constexpr std::string_view kType = "gnss_comm/msg/GnssEphemMsg";
  std::uint32_t sat = 0;
  GnssTimeMsg ttr, toe, toc;
  double toe_tow = 0;
  std::uint32_t week = 0, iode = 0, iodc = 0, health = 0, code = 0;
  double ura = 0, a = 0, e = 0, i0 = 0, omg = 0, omg0 = 0, m0 = 0, delta_n = 0, omg_dot = 0, i_dot = 0;
  double cuc = 0, cus = 0, crc = 0, crs = 0, cic = 0, cis = 0;
  double af0 = 0, af1 = 0, af2 = 0, tgd0 = 0, tgd1 = 0, a_dot = 0, n_dot = 0;
};
struct GnssGloEphemMsg {
  static constexpr std::string_view kType = "gnss_comm/msg/GnssGloEphemMsg";
  std::uint32_t sat = 0;
  GnssTimeMsg ttr, toe;
  std::int32_t freqo = 0;
  std::uint32_t iode = 0, health = 0, age = 0;
  double ura = 0, pos_x = 0, pos_y = 0, pos_z = 0, vel_x = 0, vel_y = 0, vel_z = 0, acc_x = 0, acc_y = 0, acc_z = 0;
  double tau_n = 0, gamma = 0, delta_tau_n = 0;
};

// --- skytrace_msgs (the same definitions as the ROS 1 node's, apps/ros/skytrace_msgs) ------------
struct Observation {
  static constexpr std::string_view kType = "skytrace_msgs/msg/Observation";
  std::string satellite, system;
  std::uint16_t prn = 0;
  std::int8_t glonass_channel = 0;
  std::string signal;
  double carrier_frequency_hz = 0, pseudorange_m = 0, carrier_phase_cycles = 0, doppler_hz = 0, cn0_dbhz = 0;
  bool loss_of_lock = false, half_cycle_unresolved = false;
  double lock_time_s = 0, azimuth_deg = 0, elevation_deg = 0;
  bool los = false, nlos = false, vegetation = false, blocked = false;
  double vegetation_path_m = 0, vegetation_attenuation_db = 0;
};
struct Observations {
  static constexpr std::string_view kType = "skytrace_msgs/msg/Observations";
  Header header;
  std::uint32_t gps_week = 0;
  double gps_tow_s = 0;
  bool restarted = false, pose_stale = false;
  std::vector<Observation> observations;
};
struct SatelliteSky {
  static constexpr std::string_view kType = "skytrace_msgs/msg/SatelliteSky";
  static constexpr std::uint8_t kTracked = 0, kBelowMask = 1, kNoEphemeris = 2, kNoSignal = 3, kBlocked = 4,
                                kAttenuated = 5;
  std::string satellite, system;
  std::uint16_t prn = 0;
  double azimuth_deg = 0, elevation_deg = 0;
  std::uint8_t status = kTracked;
  bool used_in_fix = false;
  double cn0_dbhz = 0, vegetation_path_m = 0, vegetation_attenuation_db = 0;
  std::string detail;
};
struct Sky {
  static constexpr std::string_view kType = "skytrace_msgs/msg/Sky";
  Header header;
  std::uint32_t gps_week = 0;
  double gps_tow_s = 0;
  std::vector<SatelliteSky> satellites;
};

// --- rmw_dds_common: the graph information every ROS 2 participant publishes ---------------------
// The distribution decides the wire form: Humble's Gid is char[24], Jazzy's and later char[16].
enum class RosDistro { kHumble, kJazzy };
struct Gid {
  static constexpr std::string_view kType = "rmw_dds_common/msg/Gid";
  std::array<std::uint8_t, 24> data{};  // the DDS GUID in the first 16 bytes
};
struct NodeEntitiesInfo {
  static constexpr std::string_view kType = "rmw_dds_common/msg/NodeEntitiesInfo";
  std::string node_namespace, node_name;  // each at most 256 characters
  std::vector<Gid> reader_gid_seq, writer_gid_seq;
};
struct ParticipantEntitiesInfo {
  static constexpr std::string_view kType = "rmw_dds_common/msg/ParticipantEntitiesInfo";
  Gid gid;
  std::vector<NodeEntitiesInfo> node_entities_info_seq;
};
[[nodiscard]] std::vector<std::uint8_t> serialize(const ParticipantEntitiesInfo& message, RosDistro distro);
[[nodiscard]] Result<ParticipantEntitiesInfo> deserialize_participant_info(std::span<const std::uint8_t> bytes,
                                                                          RosDistro distro);
[[nodiscard]] Result<RosDistro> parse_ros_distro(std::string_view name);  // humble, jazzy, kilted, rolling

// --- encoding -------------------------------------------------------------------------------------
#define SKYTRACE_ROS2_CODEC(T)                  \
  void encode(CdrWriter& writer, const T& message); \
  void decode(CdrReader& reader, T& message);
SKYTRACE_ROS2_CODEC(Time)
SKYTRACE_ROS2_CODEC(Duration)
SKYTRACE_ROS2_CODEC(Header)
SKYTRACE_ROS2_CODEC(ColorRGBA)
SKYTRACE_ROS2_CODEC(Clock)
SKYTRACE_ROS2_CODEC(Vector3)
SKYTRACE_ROS2_CODEC(Point)
SKYTRACE_ROS2_CODEC(Quaternion)
SKYTRACE_ROS2_CODEC(Pose)
SKYTRACE_ROS2_CODEC(PoseStamped)
SKYTRACE_ROS2_CODEC(PoseWithCovariance)
SKYTRACE_ROS2_CODEC(Twist)
SKYTRACE_ROS2_CODEC(TwistWithCovariance)
SKYTRACE_ROS2_CODEC(TwistWithCovarianceStamped)
SKYTRACE_ROS2_CODEC(Transform)
SKYTRACE_ROS2_CODEC(TransformStamped)
SKYTRACE_ROS2_CODEC(TFMessage)
SKYTRACE_ROS2_CODEC(Odometry)
SKYTRACE_ROS2_CODEC(NavSatStatus)
SKYTRACE_ROS2_CODEC(NavSatFix)
SKYTRACE_ROS2_CODEC(TimeReference)
SKYTRACE_ROS2_CODEC(CompressedImage)
SKYTRACE_ROS2_CODEC(NmeaSentence)
SKYTRACE_ROS2_CODEC(RtcmMessage)
SKYTRACE_ROS2_CODEC(UVCoordinate)
SKYTRACE_ROS2_CODEC(MeshFile)
SKYTRACE_ROS2_CODEC(Marker)
SKYTRACE_ROS2_CODEC(MarkerArray)
SKYTRACE_ROS2_CODEC(GnssTimeMsg)
SKYTRACE_ROS2_CODEC(GnssObsMsg)
SKYTRACE_ROS2_CODEC(GnssMeasMsg)
SKYTRACE_ROS2_CODEC(GnssEphemMsg)
SKYTRACE_ROS2_CODEC(GnssGloEphemMsg)
SKYTRACE_ROS2_CODEC(Observation)
SKYTRACE_ROS2_CODEC(Observations)
SKYTRACE_ROS2_CODEC(SatelliteSky)
SKYTRACE_ROS2_CODEC(Sky)
#undef SKYTRACE_ROS2_CODEC

template <typename Message>
[[nodiscard]] std::vector<std::uint8_t> serialize(const Message& message) {
  CdrWriter writer;
  encode(writer, message);
  return writer.take();
}

// The same into `out`, reusing its capacity (a publisher's buffer from message to message).
template <typename Message>
void serialize_into(const Message& message, std::vector<std::uint8_t>& out) {
  CdrWriter writer(std::move(out));
  encode(writer, message);
  out = writer.take();
}

template <typename Message>
[[nodiscard]] Result<Message> deserialize(std::span<const std::uint8_t> bytes) {
  CdrReader reader(bytes);
  Message message;
  decode(reader, message);
  if (!reader.ok()) return make_error(ErrorCode::kParse, std::string(Message::kType) + ": " + reader.error());
  return message;
}

// "sensor_msgs/msg/NavSatFix" -> "sensor_msgs::msg::dds_::NavSatFix_" (the type name on the wire).
[[nodiscard]] std::string dds_type_name(std::string_view ros_type);

// The definition text of a message type as rosbag2 stores it in an MCAP schema (encoding
// "ros2msg"): the type's fields and constants, then each type it uses once, after a line of 80
// '=' and "MSG: pkg/Name". Empty for a type this file does not define.
[[nodiscard]] std::string message_definition(std::string_view ros_type);

}  // namespace skytrace::ros2
