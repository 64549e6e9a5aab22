// The ROS 2 topics of a simulated receiver and their messages from one epoch: shared by the live
// DDS node (skytrace_ros2_node) and the rosbag2 sink of `skytrace run`, so that a bag and a live
// graph carry the same topics, types and values (docs/ros2.md).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/frames.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/positioning/spp.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/ros2/messages.hpp"

namespace skytrace::sim {

// The QoS a receiver's topics are offered with, after REP 2003: a sensor driver publishes with the
// system default profile (reliable, volatile; keep last `depth`), which both reliable and
// best-effort (rclcpp::SensorDataQoS) subscriptions match; records a late subscriber needs
// (ephemerides) are latched (reliable, transient local).
enum class Ros2Qos { kSensorData, kDefault, kLatched };

struct Ros2Topic {
  std::string_view name;  // relative to the node's namespace: "fix", "gnss/measurements"
  std::string_view type;  // "sensor_msgs/msg/NavSatFix"
  Ros2Qos qos;
  int depth = 10;  // history: deeper where one epoch writes several samples (NMEA, RTCM, records)
};
// Every topic a receiver publishes, in a fixed order.
[[nodiscard]] const std::vector<Ros2Topic>& ros2_receiver_topics();

struct Ros2TopicSettings {
  std::string frame_id = "gnss_antenna";  // of fix, velocity, NMEA, RTCM, measurements
  std::string world_frame = "world";      // of the rays
  double ray_length_m = 100.0;
  std::string time_source = "gps";        // TimeReference.source
  bool rtcm = true;                       // the RTCM 3 stream of the receiver as a reference station
  bool nmea = true;                       // NMEA sentences of the fix
};

// The messages of one receiver epoch.
struct Ros2Epoch {
  ros2::NavSatFix fix;
  std::optional<ros2::TwistWithCovarianceStamped> velocity;  // when the fix has a velocity
  ros2::TimeReference time_reference;
  std::vector<ros2::NmeaSentence> nmea;
  std::vector<ros2::RtcmMessage> rtcm;  // one per RTCM 3 frame
  ros2::GnssMeasMsg measurements;       // gnss_comm: GPS, GLONASS, Galileo, BeiDou
  std::vector<ros2::GnssEphemMsg> ephemerides;          // records first used at this epoch
  std::vector<ros2::GnssGloEphemMsg> glonass_ephemerides;
  ros2::Observations observations;
  ros2::Sky sky;
  ros2::MarkerArray rays;
};

// Hands every message of an epoch to `emit(topic, message)` (topic: the name in
// ros2_receiver_topics()), in that table's order: one call per NMEA sentence, RTCM frame and new
// ephemeris, none for an absent velocity. The live node and the bag sink publish through it. Stops
// at the first error `emit` returns.
template <typename Emit>
[[nodiscard]] Status visit_messages(const Ros2Epoch& m, Emit&& emit) {
  auto all = [&](std::string_view topic, const auto& messages) -> Status {
    for (const auto& message : messages) {
      if (auto st = emit(topic, message); !st) return st;
    }
    return Ok{};
  };
  if (auto st = emit("fix", m.fix); !st) return st;
  if (m.velocity) {
    if (auto st = emit("velocity", *m.velocity); !st) return st;
  }
  if (auto st = emit("time_reference", m.time_reference); !st) return st;
  if (auto st = all("nmea", m.nmea); !st) return st;
  if (auto st = all("rtcm", m.rtcm); !st) return st;
  if (auto st = emit("gnss/measurements", m.measurements); !st) return st;
  if (auto st = all("gnss/ephemeris", m.ephemerides); !st) return st;
  if (auto st = all("gnss/glonass_ephemeris", m.glonass_ephemerides); !st) return st;
  if (auto st = emit("observations", m.observations); !st) return st;
  if (auto st = emit("sky", m.sky); !st) return st;
  return emit("rays", m.rays);
}

class Ros2EpochBuilder {
 public:
  // `world`: the frame of the rays (the loaded world's or east-north-up at the first position);
  // `station`: the receiver as a reference station (RTCM 1006), used when settings.rtcm.
  Ros2EpochBuilder(const orbits::BroadcastEphemerides& ephemerides, receiver::ReceiverProfile profile,
                   LocalFrame world, io::RtcmStation station, Ros2TopicSettings settings);
  ~Ros2EpochBuilder();
  Ros2EpochBuilder(const Ros2EpochBuilder&) = delete;
  Ros2EpochBuilder& operator=(const Ros2EpochBuilder&) = delete;

  // `stamp`: the ROS time of the epoch (the bag's or the node's clock); `fix` may be null (no
  // engine: NavSatFix STATUS_NO_FIX). `restarted`/`pose_stale` go into the observations message.
  [[nodiscard]] Result<Ros2Epoch> build(const receiver::EpochObservations& epoch, const positioning::PositionFix* fix,
                                        const ros2::Time& stamp, bool restarted = false, bool pose_stale = false);
  // The same into `out`, reusing its storage (strings and vectors keep their capacity from epoch
  // to epoch: a long run allocates little).
  [[nodiscard]] Status build_into(Ros2Epoch& out, const receiver::EpochObservations& epoch,
                                  const positioning::PositionFix* fix, const ros2::Time& stamp, bool restarted = false,
                                  bool pose_stale = false);
  // A simulation reset: ephemerides are sent again, RTCM starts anew.
  void reset();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Pieces used by the builder, exposed for tests.
// UTC of an instant as seconds since 1970-01-01 (ROS time of a wall clock synchronised to GNSS).
[[nodiscard]] ros2::Time unix_utc_time(const GnssTime& time);
// NavSatFix of a fix: status FIX for single point, SBAS_FIX never, GBAS_FIX for DGNSS and RTK;
// service bits of the systems used; covariance east-north-up of the engine, type KNOWN.
[[nodiscard]] ros2::NavSatFix to_navsat_fix(const positioning::PositionFix* fix, const ros2::Header& header);
// gnss_comm's satellite number (GPS 1-32, GLONASS 33-59, Galileo 60-97, BeiDou 98-160); 0 for
// a satellite gnss_comm cannot number (QZSS, NavIC, SBAS, or a PRN beyond its ranges).
[[nodiscard]] std::uint32_t gnss_comm_satellite(const SatelliteId& satellite);
// gnss_comm's (RTKLIB's) observation code of a RINEX signal code ("1C" -> 1); 0 when it has none.
[[nodiscard]] std::uint8_t gnss_comm_code(const Signal& signal);
// The frames of an RTCM 3 byte stream (0xD3, 10-bit length, payload, CRC-24Q).
[[nodiscard]] std::vector<std::vector<std::uint8_t>> split_rtcm3_frames(const std::vector<std::uint8_t>& stream);

}  // namespace skytrace::sim
