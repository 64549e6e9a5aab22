#include "skytrace/ros2/messages.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace skytrace::ros2 {
namespace {

// Encodes or decodes each field in order through one function per message, so that the two
// directions cannot disagree. `Io` is CdrWriter (values read from `m`) or CdrReader (values
// written into `m`).
template <typename T>
void field(CdrWriter& w, const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    w.write_bool(value);
  } else if constexpr (std::is_same_v<T, std::uint8_t>) {
    w.write_u8(value);
  } else if constexpr (std::is_same_v<T, std::int8_t>) {
    w.write_i8(value);
  } else if constexpr (std::is_same_v<T, std::uint16_t>) {
    w.write_u16(value);
  } else if constexpr (std::is_same_v<T, std::int32_t>) {
    w.write_i32(value);
  } else if constexpr (std::is_same_v<T, std::uint32_t>) {
    w.write_u32(value);
  } else if constexpr (std::is_same_v<T, float>) {
    w.write_f32(value);
  } else if constexpr (std::is_same_v<T, double>) {
    w.write_f64(value);
  } else if constexpr (std::is_same_v<T, std::string>) {
    w.write_string(value);
  } else {
    encode(w, value);
  }
}
template <typename T>
void field(CdrReader& r, T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    value = r.read_bool();
  } else if constexpr (std::is_same_v<T, std::uint8_t>) {
    value = r.read_u8();
  } else if constexpr (std::is_same_v<T, std::int8_t>) {
    value = r.read_i8();
  } else if constexpr (std::is_same_v<T, std::uint16_t>) {
    value = r.read_u16();
  } else if constexpr (std::is_same_v<T, std::int32_t>) {
    value = r.read_i32();
  } else if constexpr (std::is_same_v<T, std::uint32_t>) {
    value = r.read_u32();
  } else if constexpr (std::is_same_v<T, float>) {
    value = r.read_f32();
  } else if constexpr (std::is_same_v<T, double>) {
    value = r.read_f64();
  } else if constexpr (std::is_same_v<T, std::string>) {
    value = r.read_string();
  } else {
    decode(r, value);
  }
}
// Fixed arrays: the elements only.
template <typename T, size_t N>
void field(CdrWriter& w, const std::array<T, N>& values) {
  for (const T& v : values) field(w, v);
}
template <typename T, size_t N>
void field(CdrReader& r, std::array<T, N>& values) {
  for (T& v : values) field(r, v);
}
// Sequences: a count, then the elements. Every element takes at least one byte on the wire (an
// empty string four), which bounds the count by the bytes left.
template <typename T>
void field(CdrWriter& w, const std::vector<T>& values) {
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    w.write_byte_sequence(values);
  } else {
    w.write_count(values.size());
    for (const T& v : values) field(w, v);
  }
}
template <typename T>
void field(CdrReader& r, std::vector<T>& values) {
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    values = r.read_byte_sequence();
  } else {
    const size_t min_bytes = std::is_arithmetic_v<T> ? sizeof(T) : 1;
    const size_t count = r.read_count(min_bytes);
    values.clear();
    values.reserve(count);
    for (size_t i = 0; i < count && r.ok(); ++i) field(r, values.emplace_back());
  }
}

template <typename Io, typename... Fields>
void fields(Io& io, Fields&... values) {
  (field(io, values), ...);
}

// The bound of a `string<=256` field.
constexpr size_t kNodeNameMax = 256;

template <typename Io, typename M>
void gid_fields(Io& io, M& gid, RosDistro distro) {
  const size_t size = distro == RosDistro::kHumble ? 24 : 16;
  if constexpr (std::is_same_v<Io, CdrWriter>) {
    io.write_raw(std::span<const std::uint8_t>(gid.data.data(), size));
  } else {
    gid.data.fill(0);
    io.read_raw(std::span<std::uint8_t>(gid.data.data(), size));
  }
}

template <typename Io, typename M>
void participant_fields(Io& io, M& m, RosDistro distro) {
  gid_fields(io, m.gid, distro);
  auto gids = [&](auto& list) {
    if constexpr (std::is_same_v<Io, CdrWriter>) {
      io.write_count(list.size());
      for (auto& g : list) gid_fields(io, g, distro);
    } else {
      const size_t count = io.read_count(16);
      list.resize(count);
      for (auto& g : list) gid_fields(io, g, distro);
    }
  };
  auto nodes = [&](auto& list) {
    if constexpr (std::is_same_v<Io, CdrWriter>) {
      io.write_count(list.size());
    } else {
      list.resize(io.read_count(8));
    }
    for (auto& node : list) {
      field(io, node.node_namespace);
      field(io, node.node_name);
      if constexpr (std::is_same_v<Io, CdrReader>) {
        if (node.node_namespace.size() > kNodeNameMax || node.node_name.size() > kNodeNameMax) {
          io.fail("node name or namespace longer than 256 characters");
        }
      }
      gids(node.reader_gid_seq);
      gids(node.writer_gid_seq);
    }
  };
  nodes(m.node_entities_info_seq);
}

}  // namespace

Time Time::from_seconds(double seconds) {
  const double whole = std::floor(seconds);
  auto nanoseconds = static_cast<std::int64_t>(std::llround((seconds - whole) * 1e9));
  auto sec = static_cast<std::int64_t>(whole);
  if (nanoseconds >= 1000000000) {
    nanoseconds -= 1000000000;
    ++sec;
  }
  return Time{static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nanoseconds)};
}

// One encode and one decode per message, both through the same field list.
#define SKYTRACE_ROS2_FIELDS(T, ...)                                  \
  void encode(CdrWriter& w, const T& m) { fields(w, __VA_ARGS__); } \
  void decode(CdrReader& r, T& m) { fields(r, __VA_ARGS__); }

SKYTRACE_ROS2_FIELDS(Time, m.sec, m.nanosec)
SKYTRACE_ROS2_FIELDS(Duration, m.sec, m.nanosec)
SKYTRACE_ROS2_FIELDS(Header, m.stamp, m.frame_id)
SKYTRACE_ROS2_FIELDS(ColorRGBA, m.r, m.g, m.b, m.a)
SKYTRACE_ROS2_FIELDS(Clock, m.clock)
SKYTRACE_ROS2_FIELDS(Vector3, m.x, m.y, m.z)
SKYTRACE_ROS2_FIELDS(Point, m.x, m.y, m.z)
SKYTRACE_ROS2_FIELDS(Quaternion, m.x, m.y, m.z, m.w)
SKYTRACE_ROS2_FIELDS(Pose, m.position, m.orientation)
SKYTRACE_ROS2_FIELDS(PoseStamped, m.header, m.pose)
SKYTRACE_ROS2_FIELDS(PoseWithCovariance, m.pose, m.covariance)
SKYTRACE_ROS2_FIELDS(Twist, m.linear, m.angular)
SKYTRACE_ROS2_FIELDS(TwistWithCovariance, m.twist, m.covariance)
SKYTRACE_ROS2_FIELDS(TwistWithCovarianceStamped, m.header, m.twist)
SKYTRACE_ROS2_FIELDS(Transform, m.translation, m.rotation)
SKYTRACE_ROS2_FIELDS(TransformStamped, m.header, m.child_frame_id, m.transform)
SKYTRACE_ROS2_FIELDS(TFMessage, m.transforms)
SKYTRACE_ROS2_FIELDS(Odometry, m.header, m.child_frame_id, m.pose, m.twist)
SKYTRACE_ROS2_FIELDS(NavSatStatus, m.status, m.service)
SKYTRACE_ROS2_FIELDS(NavSatFix, m.header, m.status, m.latitude, m.longitude, m.altitude, m.position_covariance,
                     m.position_covariance_type)
SKYTRACE_ROS2_FIELDS(TimeReference, m.header, m.time_ref, m.source)
SKYTRACE_ROS2_FIELDS(CompressedImage, m.header, m.format, m.data)
SKYTRACE_ROS2_FIELDS(NmeaSentence, m.header, m.sentence)
SKYTRACE_ROS2_FIELDS(RtcmMessage, m.header, m.message)
SKYTRACE_ROS2_FIELDS(UVCoordinate, m.u, m.v)
SKYTRACE_ROS2_FIELDS(MeshFile, m.filename, m.data)
SKYTRACE_ROS2_FIELDS(Marker, m.header, m.ns, m.id, m.type, m.action, m.pose, m.scale, m.color, m.lifetime,
                     m.frame_locked, m.points, m.colors, m.texture_resource, m.texture, m.uv_coordinates, m.text,
                     m.mesh_resource, m.mesh_file, m.mesh_use_embedded_materials)
SKYTRACE_ROS2_FIELDS(MarkerArray, m.markers)
SKYTRACE_ROS2_FIELDS(GnssTimeMsg, m.week, m.tow)
SKYTRACE_ROS2_FIELDS(GnssObsMsg, m.time, m.sat, m.freqs, m.cn0, m.lli, m.code, m.psr, m.psr_std, m.cp, m.cp_std,
                     m.dopp, m.dopp_std, m.status)
SKYTRACE_ROS2_FIELDS(GnssMeasMsg, m.meas)
SKYTRACE_ROS2_FIELDS(GnssEphemMsg, m.sat, m.ttr, m.toe, m.toc, m.toe_tow, m.week, m.iode, m.iodc, m.health, m.code,
                     m.ura, m.a, m.e, m.i0, m.omg, m.omg0, m.m0, m.delta_n, m.omg_dot, m.i_dot, m.cuc, m.cus, m.crc,
                     m.crs, m.cic, m.cis, m.af0, m.af1, m.af2, m.tgd0, m.tgd1, m.a_dot, m.n_dot)
SKYTRACE_ROS2_FIELDS(GnssGloEphemMsg, m.sat, m.ttr, m.toe, m.freqo, m.iode, m.health, m.age, m.ura, m.pos_x, m.pos_y,
                     m.pos_z, m.vel_x, m.vel_y, m.vel_z, m.acc_x, m.acc_y, m.acc_z, m.tau_n, m.gamma, m.delta_tau_n)
SKYTRACE_ROS2_FIELDS(Observation, m.satellite, m.system, m.prn, m.glonass_channel, m.signal, m.carrier_frequency_hz,
                     m.pseudorange_m, m.carrier_phase_cycles, m.doppler_hz, m.cn0_dbhz, m.loss_of_lock,
                     m.half_cycle_unresolved, m.lock_time_s, m.azimuth_deg, m.elevation_deg, m.los, m.nlos,
                     m.vegetation, m.blocked, m.vegetation_path_m, m.vegetation_attenuation_db)
SKYTRACE_ROS2_FIELDS(Observations, m.header, m.gps_week, m.gps_tow_s, m.restarted, m.pose_stale, m.observations)
SKYTRACE_ROS2_FIELDS(SatelliteSky, m.satellite, m.system, m.prn, m.azimuth_deg, m.elevation_deg, m.status,
                     m.used_in_fix, m.cn0_dbhz, m.vegetation_path_m, m.vegetation_attenuation_db, m.detail)
SKYTRACE_ROS2_FIELDS(Sky, m.header, m.gps_week, m.gps_tow_s, m.satellites)
#undef SKYTRACE_ROS2_FIELDS

std::vector<std::uint8_t> serialize(const ParticipantEntitiesInfo& message, RosDistro distro) {
  CdrWriter writer;
  participant_fields(writer, message, distro);
  return writer.take();
}

Result<ParticipantEntitiesInfo> deserialize_participant_info(std::span<const std::uint8_t> bytes, RosDistro distro) {
  CdrReader reader(bytes);
  ParticipantEntitiesInfo message;
  participant_fields(reader, message, distro);
  if (!reader.ok()) return make_error(ErrorCode::kParse, std::string(ParticipantEntitiesInfo::kType) + ": " + reader.error());
  return message;
}

Result<RosDistro> parse_ros_distro(std::string_view name) {
  if (name == "humble") return RosDistro::kHumble;
  if (name == "jazzy" || name == "kilted" || name == "rolling") return RosDistro::kJazzy;
  return make_error(ErrorCode::kInvalidArgument,
                    "ros_distro '" + std::string(name) + "': expected humble, jazzy, kilted or rolling");
}

std::string dds_type_name(std::string_view ros_type) {
  // pkg/msg/Name -> pkg::msg::dds_::Name_
  const size_t last = ros_type.rfind('/');
  if (last == std::string_view::npos) return std::string(ros_type);
  std::string name;
  for (char c : ros_type.substr(0, last)) {
    if (c == '/') {
      name += "::";
    } else {
      name += c;
    }
  }
  return name + "::dds_::" + std::string(ros_type.substr(last + 1)) + "_";
}

}  // namespace skytrace::ros2
