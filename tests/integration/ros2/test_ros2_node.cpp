// skytrace_ros2_node (Cyclone DDS) against an independent ROS 2 peer on Fast DDS 2.9, decoding with
// Fast CDR: the node's topics and types as ROS 2 names them, its graph entry on
// ros_discovery_info (Humble and Jazzy GIDs), every message decoded to its last byte with sane
// values for the quick start (open sky near Munich), and the node driven as a robot's graph would:
// /clock, /tf and /tf_static, a pose topic, odometry with a lever arm. Bad input (NaN and stale
// poses, unknown frames, the clock going back, incompatible QoS) is logged and survived; SIGINT
// and SIGTERM end the node at once. Each test has a DDS domain from its process id and a
// namespace of its own, on the loopback interface (ROS_LOCALHOST_ONLY=1).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fastdds_peer.hpp"
#include "process.hpp"
#include "ros2_wire.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

using namespace std::chrono_literals;
using test::ros2_peer::Peer;
using test::ros2_peer::Qos;
using test::ros2_peer::Subscription;
namespace wire = test::ros2_wire;

// The quick start's receiver: courtyard world origin (its <spherical_coordinates>) and the
// receiver's position in it, east-north-up.
constexpr double kOriginLatitudeDeg = 48.1507, kOriginLongitudeDeg = 11.5690, kOriginHeightM = 560.0;

// A fix in the world frame, east-north-up metres from the origin (a local approximation, good to
// millimetres within a few hundred metres).
std::array<double, 3> world_of(const wire::NavSatFix& fix) {
  constexpr double kPi = 3.14159265358979323846;
  const double lat0 = kOriginLatitudeDeg * kPi / 180.0;
  const double north_m_per_deg = 111132.954 - 559.822 * std::cos(2 * lat0) + 1.175 * std::cos(4 * lat0);
  const double east_m_per_deg = kPi / 180.0 * 6378137.0 * std::cos(lat0) / std::sqrt(1 - 0.00669438 * std::pow(std::sin(lat0), 2));
  return {(fix.longitude - kOriginLongitudeDeg) * east_m_per_deg, (fix.latitude - kOriginLatitudeDeg) * north_m_per_deg,
          fix.altitude - kOriginHeightM};
}

double horizontal_distance_m(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1]);
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}
wire::Time ros_time(double seconds) {
  const long long ns = std::llround(seconds * 1e9);
  wire::Time t;
  t.sec = static_cast<std::int32_t>(ns / 1000000000);
  t.nanosec = static_cast<std::uint32_t>(ns % 1000000000);
  return t;
}

std::string dds_type(const std::string& pkg, const std::string& name) { return pkg + "::msg::dds_::" + name + "_"; }

// A DDS domain of this test process alone: the first of 1-100 (from the process id on) whose lock
// no other process holds; the kernel drops the lock when the process ends, however it ends.
int claim_domain(int& lock_fd) {
  for (int i = 0; i < 100; ++i) {
    const int domain = 1 + static_cast<int>((getpid() + i) % 100);
    const auto path = std::filesystem::temp_directory_path() / ("skytrace-ros2-test-domain-" + std::to_string(domain));
    const int fd = open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
      lock_fd = fd;
      return domain;
    }
    close(fd);
  }
  return 1 + static_cast<int>(getpid() % 100);
}

template <typename F>
bool wait_until(F condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(50ms);
  }
  return condition();
}

class Ros2NodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    node_binary_ = test::binary_dir() / "bin" / "skytrace_ros2_node";
    if (!std::filesystem::exists(node_binary_)) GTEST_SKIP() << "skytrace_ros2_node not built (Cyclone DDS missing)";
    scenario_ = test::source_dir() / "examples" / "quickstart.yaml";
    // A domain and a namespace per test process: tests running side by side do not see each other.
    domain_id_ = claim_domain(domain_lock_);
    namespace_ = "/t" + std::to_string(getpid());
    dir_ = test::make_temp_dir("ros2_node");
    peer_ = Peer::create(domain_id_);
    ASSERT_TRUE(peer_) << "Fast DDS participant on domain " << domain_id_;
  }
  void TearDown() override {
    if (node_ && node_->running()) {
      const int status = node_->stop(SIGINT);
      EXPECT_EQ(status, 0) << "asked to stop with SIGINT, the node exits 0; log:\n" << log_text();
    }
    node_.reset();
    peer_.reset();
    if (domain_lock_ >= 0) close(domain_lock_);
  }

  [[nodiscard]] std::string topic(const std::string& name) const { return "rt" + namespace_ + "/" + name; }

  // Starts the node with ROS 2 arguments (e.g. "-p", "rate_hz:=5").
  void start_node(const std::vector<std::string>& args) {
    std::string command = "env ROS_DOMAIN_ID=" + std::to_string(domain_id_) + " ROS_LOCALHOST_ONLY=1 " +
                          test::shell_quote(node_binary_.string()) + " --ros-args -r __ns:=" + namespace_;
    bool has_scenario = false;
    for (const auto& a : args) {
      command += " " + test::shell_quote(a);
      has_scenario = has_scenario || a.rfind("scenario:=", 0) == 0;
    }
    if (!has_scenario) command += " -p " + test::shell_quote("scenario:=" + scenario_.string());
    log_ = dir_ / "node.log";
    node_ = std::make_unique<test::Background>(command, log_);
  }

  [[nodiscard]] std::string log_text() const {
    std::ifstream in(log_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  [[nodiscard]] bool log_has(const std::string& text) const { return log_text().find(text) != std::string::npos; }

  // Waits for `count` samples, failing with the node's log.
  void expect_samples(const Subscription& s, size_t count, const std::string& what, std::chrono::milliseconds timeout = 30s) {
    ASSERT_TRUE(s.wait_for(count, timeout)) << "no " << what << " from the node; log:\n" << log_text();
  }

  std::filesystem::path node_binary_, scenario_, dir_, log_;
  int domain_id_ = 0;
  int domain_lock_ = -1;
  std::string namespace_;
  std::unique_ptr<Peer> peer_;
  std::unique_ptr<test::Background> node_;
};

TEST_F(Ros2NodeTest, PeerDiscoversTheNodeAndDecodesEveryTopic) {
  // Parameters as ros2 run reads them: a wildcard entry, then the node's own.
  const auto params = dir_ / "params.yaml";
  std::ofstream(params) << "/**:\n  ros__parameters:\n    rate_hz: 5.0\n    scenario: " << scenario_.string()
                        << "\nskytrace:\n  ros__parameters:\n    frame_id: antenna_link\n";
  const Qos sensor = Qos::sensor_data(), reliable = Qos::default_profile();
  Qos latched = reliable;
  latched.transient_local = true;
  latched.depth = 500;
  Qos graph = latched;
  graph.depth = 10;
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), sensor);
  Subscription& velocity = peer_->subscribe(topic("velocity"), dds_type("geometry_msgs", "TwistWithCovarianceStamped"), sensor);
  Subscription& time_reference = peer_->subscribe(topic("time_reference"), dds_type("sensor_msgs", "TimeReference"), sensor);
  Subscription& nmea = peer_->subscribe(topic("nmea"), dds_type("nmea_msgs", "Sentence"), reliable);
  Qos deep = reliable;
  deep.depth = 100;  // an epoch sends several frames at once
  Subscription& rtcm = peer_->subscribe(topic("rtcm"), dds_type("rtcm_msgs", "Message"), deep);
  Subscription& meas = peer_->subscribe(topic("gnss/measurements"), dds_type("gnss_comm", "GnssMeasMsg"), sensor);
  Subscription& ephem = peer_->subscribe(topic("gnss/ephemeris"), dds_type("gnss_comm", "GnssEphemMsg"), latched);
  Subscription& glo_ephem = peer_->subscribe(topic("gnss/glonass_ephemeris"), dds_type("gnss_comm", "GnssGloEphemMsg"), latched);
  Subscription& observations = peer_->subscribe(topic("observations"), dds_type("skytrace_msgs", "Observations"), sensor);
  Subscription& sky = peer_->subscribe(topic("sky"), dds_type("skytrace_msgs", "Sky"), sensor);
  Subscription& rays = peer_->subscribe(topic("rays"), dds_type("visualization_msgs", "MarkerArray"), reliable);
  Subscription& discovery =
      peer_->subscribe("ros_discovery_info", dds_type("rmw_dds_common", "ParticipantEntitiesInfo"), graph);
  start_node({"--params-file", params.string()});

  for (auto* s : {&fix, &time_reference, &observations, &sky, &rays, &meas}) expect_samples(*s, 3, "epochs");
  for (auto* s : {&velocity, &nmea, &rtcm, &ephem, &glo_ephem, &discovery}) expect_samples(*s, 1, "messages");

  // Discovery: every topic under its ROS 2 name and type, reliable as REP 2003 has sensor drivers
  // publish (the best-effort subscriptions above match them, as rclcpp's SensorDataQoS does).
  const std::map<std::string, std::pair<std::string, bool>> expected_writers = {
      {"fix", {dds_type("sensor_msgs", "NavSatFix"), true}},
      {"velocity", {dds_type("geometry_msgs", "TwistWithCovarianceStamped"), true}},
      {"time_reference", {dds_type("sensor_msgs", "TimeReference"), true}},
      {"nmea", {dds_type("nmea_msgs", "Sentence"), true}},
      {"rtcm", {dds_type("rtcm_msgs", "Message"), true}},
      {"gnss/measurements", {dds_type("gnss_comm", "GnssMeasMsg"), true}},
      {"gnss/ephemeris", {dds_type("gnss_comm", "GnssEphemMsg"), true}},
      {"gnss/glonass_ephemeris", {dds_type("gnss_comm", "GnssGloEphemMsg"), true}},
      {"observations", {dds_type("skytrace_msgs", "Observations"), true}},
      {"sky", {dds_type("skytrace_msgs", "Sky"), true}},
      {"rays", {dds_type("visualization_msgs", "MarkerArray"), true}},
  };
  std::map<std::string, test::ros2_peer::Guid> writer_guid;
  for (const auto& w : peer_->remote_writers()) {
    if (w.topic.rfind(topic(""), 0) == 0) writer_guid[w.topic.substr(topic("").size())] = w.guid;
    const auto it = expected_writers.find(w.topic.substr(std::min(w.topic.size(), topic("").size())));
    if (w.topic.rfind(topic(""), 0) != 0 || it == expected_writers.end()) continue;
    EXPECT_EQ(w.type, it->second.first) << w.topic;
    EXPECT_EQ(w.reliable, it->second.second) << w.topic;
  }
  for (const auto& [name, type] : expected_writers) EXPECT_TRUE(writer_guid.count(name)) << "no writer on " << topic(name);

  // The graph: this node, its namespace, and the GIDs of exactly its writers (it reads nothing).
  bool found = false;
  for (const auto& sample : discovery.samples()) {
    size_t left = 0;
    const auto info = wire::decode_participant_entities(sample, 16, left);  // Jazzy, the default
    EXPECT_LE(left, 3U);
    for (const auto& node : info.nodes) {
      if (node.node_namespace != namespace_) continue;
      found = true;
      EXPECT_EQ(node.node_name, "skytrace");
      EXPECT_TRUE(node.reader_gids.empty());
      std::set<std::string> gids;
      for (const auto& g : node.writer_gids) gids.emplace(g.begin(), g.end());
      EXPECT_EQ(gids.size(), expected_writers.size());
      for (const auto& [name, guid] : writer_guid) {
        EXPECT_TRUE(gids.count(std::string(guid.begin(), guid.end()))) << "writer of " << name << " not listed";
        // The participant's GID shares the writers' GUID prefix.
        EXPECT_TRUE(std::equal(guid.begin(), guid.begin() + 12, info.gid.begin())) << name;
      }
    }
  }
  EXPECT_TRUE(found) << "the node's entry on ros_discovery_info";

  // Every message decoded to its last byte, values sane for an open-sky static receiver.
  size_t left = 0;
  double last_stamp_s = 0.0;
  for (const auto& sample : fix.samples()) {
    const auto m = wire::decode_navsat_fix(sample, left);
    EXPECT_LE(left, 3U);
    EXPECT_EQ(m.header.frame_id, "antenna_link");  // from the node's own entry of the params file
    EXPECT_GE(m.status, 0);
    EXPECT_NE(m.service & 1, 0);  // GPS
    EXPECT_NE(m.service & 8, 0);  // Galileo
    EXPECT_EQ(m.position_covariance_type, 3);  // KNOWN
    EXPECT_GT(m.position_covariance[0], 0.0);
    EXPECT_GT(m.position_covariance[8], 0.0);
    EXPECT_LT(horizontal_distance_m(world_of(m), {-5.0, 0.0, 1.5}), 30.0) << m.latitude << " " << m.longitude;
    EXPECT_NEAR(world_of(m)[2], 1.5, 60.0);
    const double stamp_s = m.header.stamp.seconds();
    EXPECT_NEAR(stamp_s, now_s(), 60.0);  // system time
    if (last_stamp_s > 0.0) EXPECT_NEAR(std::fmod(stamp_s - last_stamp_s + 1e-6, 0.2), 0.0, 1e-3);  // 5 Hz epochs
    last_stamp_s = stamp_s;
  }
  const auto v = wire::decode_twist(velocity.samples().front(), left);
  EXPECT_LE(left, 3U);
  EXPECT_LT(std::hypot(v.linear.x, v.linear.y), 1.0);  // a static receiver
  EXPECT_GT(v.covariance[0], 0.0);
  const auto tr = wire::decode_time_reference(time_reference.samples().front(), left);
  EXPECT_LE(left, 3U);
  EXPECT_EQ(tr.source, "gps");
  // The quick start begins 2026-03-01T12:00:00 GPST = 11:59:42 UTC (Unix 1772366382).
  EXPECT_GE(tr.time_ref.seconds(), 1772366382.0 - 1.0);
  EXPECT_LT(tr.time_ref.seconds(), 1772366382.0 + 120.0);
  for (const auto& sample : nmea.samples()) {
    const auto s = wire::decode_sentence(sample, left);
    EXPECT_LE(left, 3U);
    ASSERT_GE(s.sentence.size(), 6U);
    EXPECT_EQ(s.sentence[0], '$') << s.sentence;
    EXPECT_NE(s.sentence.find('*'), std::string::npos) << s.sentence;
    EXPECT_EQ(s.sentence.find_first_of("\r\n"), std::string::npos);
  }
  // The station message comes every 10 s (the first one may go before the peer matched).
  const auto message_number = [](const wire::RtcmMessage& m) { return (m.message[3] << 4) | (m.message[4] >> 4); };
  EXPECT_TRUE(wait_until(
      [&] {
        for (const auto& sample : rtcm.samples()) {
          size_t n = 0;
          const auto m = wire::decode_rtcm(sample, n);
          if (m.message.size() > 6 && message_number(m) == 1006) return true;
        }
        return false;
      },
      15s))
      << "no RTCM 1006";
  std::set<int> rtcm_messages;
  for (const auto& sample : rtcm.samples()) {
    const auto m = wire::decode_rtcm(sample, left);
    EXPECT_LE(left, 3U);
    ASSERT_GE(m.message.size(), 6U);
    EXPECT_EQ(m.message[0], 0xD3);
    const size_t length = (static_cast<size_t>(m.message[1] & 0x03) << 8) | m.message[2];
    ASSERT_EQ(m.message.size(), length + 6);
    const std::uint32_t crc = (std::uint32_t{m.message[length + 3]} << 16) | (std::uint32_t{m.message[length + 4]} << 8) |
                              m.message[length + 5];
    EXPECT_EQ(wire::crc24q(m.message.data(), length + 3), crc);
    rtcm_messages.insert(message_number(m));
  }
  EXPECT_TRUE(rtcm_messages.count(1006)) << "station message";
  EXPECT_TRUE(rtcm_messages.count(1077)) << "GPS MSM7";
  const auto mm = wire::decode_gnss_meas(meas.samples().back(), left);
  EXPECT_LE(left, 3U);
  EXPECT_GE(mm.meas.size(), 10U);
  for (const auto& o : mm.meas) {
    EXPECT_GE(o.sat, 1U);
    EXPECT_LE(o.sat, 160U);
    ASSERT_FALSE(o.psr.empty());
    for (auto* field : {&o.cn0, &o.psr_std, &o.cp, &o.cp_std, &o.dopp, &o.dopp_std}) EXPECT_EQ(field->size(), o.freqs.size());
    EXPECT_EQ(o.lli.size(), o.freqs.size());
    EXPECT_EQ(o.status.size(), o.freqs.size());
    for (size_t k = 0; k < o.psr.size(); ++k) {
      EXPECT_GT(o.psr[k], 1.8e7) << o.sat;
      EXPECT_LT(o.psr[k], 4.5e7) << o.sat;
      EXPECT_GT(o.freqs[k], 1.1e9);
      EXPECT_LT(o.freqs[k], 1.7e9);
      EXPECT_GT(o.psr_std[k], 0.0);
    }
  }
  for (const auto& sample : ephem.samples()) {
    const auto e = wire::decode_gnss_ephem(sample, left);
    EXPECT_LE(left, 3U);
    EXPECT_GE(e.sat, 1U);
    EXPECT_LE(e.sat, 160U);
    EXPECT_GT(e.A, 2.5e7) << e.sat;  // semi-major axis: MEO, IGSO and GEO orbits
    EXPECT_LT(e.A, 4.3e7) << e.sat;
    EXPECT_LT(e.e, 0.1);
  }
  for (const auto& sample : glo_ephem.samples()) {
    const auto e = wire::decode_gnss_glo_ephem(sample, left);
    EXPECT_LE(left, 3U);
    EXPECT_GE(e.sat, 33U);
    EXPECT_LE(e.sat, 59U);
    EXPECT_NEAR(std::sqrt(e.pos_x * e.pos_x + e.pos_y * e.pos_y + e.pos_z * e.pos_z), 25.5e6, 0.3e6);
  }
  const auto obs = wire::decode_observations(observations.samples().back(), left);
  EXPECT_LE(left, 3U);
  EXPECT_EQ(obs.header.frame_id, "antenna_link");
  EXPECT_GE(obs.observations.size(), 20U);
  for (const auto& o : obs.observations) {
    EXPECT_GT(o.pseudorange_m, 1.8e7) << o.satellite << o.signal;
    EXPECT_GE(o.elevation_deg, 0.0);
    EXPECT_GT(o.cn0_dbhz, 20.0);
  }
  const auto s = wire::decode_sky(sky.samples().back(), left);
  EXPECT_LE(left, 3U);
  EXPECT_GE(s.satellites.size(), 20U);
  size_t used = 0;
  for (const auto& sat : s.satellites) used += sat.used_in_fix ? 1 : 0;
  EXPECT_GE(used, 5U);
  const auto r = wire::decode_marker_array(rays.samples().back(), left);
  EXPECT_LE(left, 3U);
  ASSERT_EQ(r.markers.size(), 1U);
  EXPECT_EQ(r.markers[0].type, 5);  // LINE_LIST
  EXPECT_EQ(r.markers[0].header.frame_id, "world");
  EXPECT_GT(r.markers[0].points, 0U);
  EXPECT_EQ(r.markers[0].points % 2, 0U);
  EXPECT_EQ(r.markers[0].points, r.markers[0].colors);
}

TEST_F(Ros2NodeTest, HumbleGraphInfoCarries24ByteGids) {
  Qos graph = Qos::default_profile();
  graph.transient_local = true;
  Subscription& discovery =
      peer_->subscribe("ros_discovery_info", dds_type("rmw_dds_common", "ParticipantEntitiesInfo"), graph);
  start_node({"-p", "ros_distro:=humble", "-p", "rate_hz:=2"});
  bool found = false;
  ASSERT_TRUE(wait_until(
      [&]() -> bool {
        for (const auto& sample : discovery.samples()) {
          size_t left = 0;
          const auto info = wire::decode_participant_entities(sample, 24, left);
          for (const auto& node : info.nodes) {
            if (node.node_namespace != namespace_) continue;
            EXPECT_LE(left, 3U);
            EXPECT_EQ(node.node_name, "skytrace");
            EXPECT_EQ(node.writer_gids.size(), 11U);
            for (const auto& gid : node.writer_gids) {
              EXPECT_EQ(gid.size(), 24U);
              if (gid.size() != 24U) continue;
              // The DDS GUID in the first 16 bytes, zeros after, as rmw_dds_common fills a Humble Gid.
              EXPECT_TRUE(std::all_of(gid.begin() + 16, gid.end(), [](std::uint8_t b) { return b == 0; }));
              EXPECT_TRUE(std::equal(gid.begin(), gid.begin() + 12, info.gid.begin()));
            }
            found = true;
          }
        }
        return found;
      },
      30s))
      << "no Humble graph entry; log:\n"
      << log_text();
}

TEST_F(Ros2NodeTest, SimTimeClockDrivesTheEpochsAndAJumpBackRestartsTheReceiver) {
  Subscription& observations =
      peer_->subscribe(topic("observations"), dds_type("skytrace_msgs", "Observations"), Qos::sensor_data());
  auto& clock = peer_->advertise("rt/clock", dds_type("rosgraph_msgs", "Clock"), Qos::default_profile());
  start_node({"-p", "use_sim_time:=true", "-p", "rate_hz:=2"});
  ASSERT_TRUE(wait_until([&] { return log_has("waiting for the clock"); }, 20s)) << log_text();
  // /clock is volatile: what is written before discovery matched the node's reader is lost (under
  // load, discovery took longer than the 1.2 s of clock below, and the node saw no clock at all).
  ASSERT_TRUE(wait_until([&] { return clock.matched() >= 1; }, 20s)) << "the node's /clock reader was not discovered";
  std::this_thread::sleep_for(300ms);  // the reader's side of the match

  // Simulation time from 100 s, 0.1 s per publication (faster than wall time).
  double sim_s = 100.0;
  const auto run_clock = [&](double until_s) {
    while (sim_s < until_s) {
      clock.write(wire::encode_clock(ros_time(sim_s)));
      sim_s += 0.1;
      std::this_thread::sleep_for(20ms);
    }
  };
  run_clock(106.0);
  expect_samples(observations, 4, "epochs under /clock");
  std::vector<wire::Observations> before;
  size_t left = 0;
  for (const auto& sample : observations.samples()) before.push_back(wire::decode_observations(sample, left));
  for (size_t i = 0; i < before.size(); ++i) {
    const double stamp_s = before[i].header.stamp.seconds();
    EXPECT_GE(stamp_s, 100.0);
    EXPECT_LE(stamp_s, 106.0);
    EXPECT_NEAR(std::fmod(stamp_s, 0.5), 0.0, 1e-6);  // 2 Hz epochs of the simulation clock
    if (i > 0) {
      // The receiver's time tags advance with the simulation clock.
      EXPECT_NEAR(before[i].gps_tow_s - before[i - 1].gps_tow_s, stamp_s - before[i - 1].header.stamp.seconds(), 1e-6);
    }
    EXPECT_FALSE(before[i].restarted);
  }

  // A simulation reset: the clock goes back 50 s.
  sim_s = 50.0;
  const size_t count = observations.samples().size();
  run_clock(53.0);
  expect_samples(observations, count + 2, "epochs after the reset");
  bool restarted = false;
  for (size_t i = count; i < observations.samples().size(); ++i) {
    const auto m = wire::decode_observations(observations.samples()[i], left);
    restarted = restarted || m.restarted;
    EXPECT_LT(m.header.stamp.seconds(), 60.0);
  }
  EXPECT_TRUE(restarted);
  EXPECT_TRUE(log_has("time went back")) << log_text();
  EXPECT_TRUE(node_->running());
}

TEST_F(Ros2NodeTest, TfChainPlacesTheAntennaAndBadTransformsAreReported) {
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  Subscription& observations =
      peer_->subscribe(topic("observations"), dds_type("skytrace_msgs", "Observations"), Qos::sensor_data());
  Qos static_qos = Qos::default_profile();
  static_qos.transient_local = true;
  static_qos.depth = 1;
  Qos dynamic_qos = Qos::default_profile();
  dynamic_qos.depth = 100;
  auto& tf_static = peer_->advertise("rt/tf_static", dds_type("tf2_msgs", "TFMessage"), static_qos);
  auto& tf = peer_->advertise("rt/tf", dds_type("tf2_msgs", "TFMessage"), dynamic_qos);
  start_node({"-p", "pose_source:=tf", "-p", "world_frame:=map", "-p", "antenna_frame:=gnss_antenna", "-p", "rate_hz:=5"});

  // The antenna 1 m above the robot's base (a static transform, as robot_state_publisher sends).
  wire::Transform mount{{ros_time(0.0), "base_link"}, "gnss_antenna", {0.0, 0.0, 1.0}, {}};
  tf_static.write(wire::encode_tf({mount}));
  // Nothing places base_link in map yet: the frame is unknown.
  ASSERT_TRUE(wait_until([&] { return log_has("frame 'map' does not exist"); }, 20s)) << log_text();

  const auto publish_base = [&](const wire::Vector3& p) {
    wire::Transform base{{ros_time(now_s()), "map"}, "base_link", p, {}};
    tf.write(wire::encode_tf({base}));
  };
  const wire::Vector3 a{120.0, -40.0, 0.5};
  const std::array<double, 3> antenna_a{a.x, a.y, a.z + 1.0};
  const auto fix_near = [&](const std::array<double, 3>& p) {
    const auto samples = fix.samples();
    if (samples.empty()) return false;
    size_t left = 0;
    const auto m = wire::decode_navsat_fix(samples.back(), left);
    return m.status >= 0 && horizontal_distance_m(world_of(m), p) < 15.0;
  };
  ASSERT_TRUE(wait_until(
      [&] {
        publish_base(a);
        return fix_near(antenna_a);
      },
      30s))
      << "the fix did not follow tf; log:\n"
      << log_text();

  // A transform with NaN is refused and reported; the antenna stays where it was.
  tf.write(wire::encode_tf({wire::Transform{{ros_time(now_s()), "map"}, "base_link", {NAN, 0.0, 0.0}, {}}}));
  ASSERT_TRUE(wait_until([&] { return log_has("NaN"); }, 10s)) << log_text();
  // No more transforms: tf goes stale and the receiver is held.
  ASSERT_TRUE(wait_until([&] { return log_has("(stale)"); }, 10s)) << log_text();
  ASSERT_TRUE(wait_until(
      [&] {
        size_t left = 0;
        const auto samples = observations.samples();
        return !samples.empty() && wire::decode_observations(samples.back(), left).pose_stale;
      },
      10s))
      << log_text();
  EXPECT_TRUE(fix_near(antenna_a));
  EXPECT_TRUE(node_->running());
}

TEST_F(Ros2NodeTest, MovingModelsFollowTheirTransforms) {
  // A roof over the antenna (a model that is not static: movable in live sessions), then lifted
  // away through /tf as a simulator would move it; a listed model the world lacks is reported.
  const auto world = dir_ / "roof.sdf";
  std::ofstream(world) << R"(<?xml version="1.0"?>
<sdf version="1.9">
  <world name="roof_yard">
    <spherical_coordinates>
      <surface_model>EARTH_WGS84</surface_model>
      <world_frame_orientation>ENU</world_frame_orientation>
      <latitude_deg>48.1507</latitude_deg>
      <longitude_deg>11.5690</longitude_deg>
      <elevation>560.0</elevation>
    </spherical_coordinates>
    <model name="roof">
      <pose>0 0 10 0 0 0</pose>
      <link name="link"><collision name="collision"><geometry><box><size>400 400 1</size></box></geometry></collision></link>
    </model>
  </world>
</sdf>
)";
  const auto scenario = dir_ / "roof.yaml";
  std::ofstream(scenario) << "name: roof\ntime: {start: 2026-03-01T12:00:00, scale: GPST, duration_s: 3600, interval_s: 1}\n"
                          << "receiver:\n  name: ROOF\n  position: {world_enu_m: [0.0, 0.0, 1.5]}\n"
                          << "  elevation_mask_deg: 10\n  profile: ideal\n  signals: [G1C, E1C]\n"
                          << "world: {sdf: " << world.string() << "}\nephemeris: {nominal: true}\n";
  Subscription& sky = peer_->subscribe(topic("sky"), dds_type("skytrace_msgs", "Sky"), Qos::sensor_data());
  Qos dynamic_qos = Qos::default_profile();
  dynamic_qos.depth = 100;
  auto& tf = peer_->advertise("rt/tf", dds_type("tf2_msgs", "TFMessage"), dynamic_qos);
  start_node({"-p", "scenario:=" + scenario.string(), "-p", "moving_models:=[roof, ghost]", "-p", "rate_hz:=5"});
  const auto blocked_in_last_sky = [&]() -> int {
    const auto samples = sky.samples();
    if (samples.empty()) return -1;
    size_t left = 0;
    int blocked = 0;
    for (const auto& sat : wire::decode_sky(samples.back(), left).satellites) blocked += sat.status == 4 ? 1 : 0;
    return blocked;
  };
  ASSERT_TRUE(wait_until([&] { return blocked_in_last_sky() >= 5; }, 30s)) << "the roof blocks the sky; log:\n" << log_text();
  ASSERT_TRUE(wait_until(
      [&] {
        tf.write(wire::encode_tf({wire::Transform{{ros_time(now_s()), "world"}, "roof", {0.0, 0.0, -100.0}, {}},
                                  wire::Transform{{ros_time(now_s()), "world"}, "ghost", {0.0, 0.0, 0.0}, {}}}));
        return blocked_in_last_sky() == 0;
      },
      30s))
      << "the roof did not move; log:\n"
      << log_text();
  EXPECT_TRUE(wait_until([&] { return log_has("moving model 'ghost'"); }, 5s)) << log_text();
  EXPECT_TRUE(node_->running());
}

TEST_F(Ros2NodeTest, PoseTopicMovesTheFixAndBadPosesAreIgnored) {
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  const std::string pose_topic = namespace_ + "/antenna_pose_in";
  auto& pose = peer_->advertise("rt" + pose_topic, dds_type("geometry_msgs", "PoseStamped"), Qos::default_profile());
  start_node({"-p", "pose_source:=pose", "-p", "pose_topic:=" + pose_topic, "-p", "world_frame:=map", "-p", "rate_hz:=5"});

  const auto publish = [&](const wire::Vector3& p, const std::string& frame) {
    pose.write(wire::encode_pose_stamped({ros_time(now_s()), frame}, p, {}));
  };
  const auto drive_to = [&](const wire::Vector3& p) {
    return wait_until(
        [&] {
          publish(p, "map");
          const auto samples = fix.samples();
          if (samples.empty()) return false;
          size_t left = 0;
          const auto m = wire::decode_navsat_fix(samples.back(), left);
          return m.status >= 0 && horizontal_distance_m(world_of(m), {p.x, p.y, p.z}) < 15.0;
        },
        30s);
  };
  ASSERT_TRUE(drive_to({-60.0, 80.0, 2.0})) << log_text();
  for (int k = 0; k < 5; ++k) publish({NAN, 0.0, 0.0}, "map");  // refused with a warning
  publish({-60.0, 80.0, 2.0}, "odom");                            // another frame than world_frame
  ASSERT_TRUE(drive_to({300.0, -250.0, 10.0})) << log_text();
  EXPECT_TRUE(wait_until([&] { return log_has("NaN"); }, 5s)) << log_text();
  EXPECT_TRUE(log_has("pose in frame 'odom', expected world_frame 'map'")) << log_text();
  // The poses stop: stale after pose_timeout_s (1 s).
  EXPECT_TRUE(wait_until([&] { return log_has("antenna pose is stale"); }, 10s)) << log_text();
  EXPECT_TRUE(node_->running());
}

TEST_F(Ros2NodeTest, OdometryPlacesTheAntennaByItsLeverArm) {
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  auto& odom = peer_->advertise("rt/odom", dds_type("nav_msgs", "Odometry"), Qos::default_profile());
  start_node({"-p", "pose_source:=odometry", "-p", "antenna_offset_m:=[40.0, 0.0, 0.0]", "-p", "rate_hz:=5"});
  // Heading north (yaw 90 degrees): the lever arm along the body's x axis points north.
  const double half = 3.14159265358979323846 / 4.0;
  const wire::Quaternion yaw_90{0.0, 0.0, std::sin(half), std::cos(half)};
  const wire::Vector3 base{50.0, 20.0, 1.0};
  const std::array<double, 3> antenna{50.0, 60.0, 1.0}, without_rotation{90.0, 20.0, 1.0};
  std::array<double, 3> got{};
  ASSERT_TRUE(wait_until(
      [&] {
        odom.write(wire::encode_odometry({ros_time(now_s()), "world"}, "base_link", base, yaw_90, {}));
        const auto samples = fix.samples();
        if (samples.empty()) return false;
        size_t left = 0;
        const auto m = wire::decode_navsat_fix(samples.back(), left);
        got = world_of(m);
        return m.status >= 0 && horizontal_distance_m(got, antenna) < 15.0;
      },
      30s))
      << "fix at " << got[0] << ", " << got[1] << "; log:\n"
      << log_text();
  EXPECT_GT(horizontal_distance_m(got, without_rotation), 30.0);
}

// Two antennas on one body (a moving base, the scenario's rtk.moving_base): odometry places both
// by their lever arms, and the heading of the baseline comes as NMEA HDT/THS on the nmea topic.
// The scenario's body faces north; the odometry turns it to face east (yaw 0): the rover antenna
// 1.4 m ahead of the base antenna, heading 90 deg.
TEST_F(Ros2NodeTest, MovingBaseGivesTheHeadingOfTheBody) {
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  if (!std::filesystem::exists(nav)) GTEST_SKIP() << "ESBC navigation file absent";
  const auto scenario = dir_ / "heading.yaml";
  std::ofstream(scenario) << test::moving_base_scenario_yaml(nav, "0.0, 1.4, 1.5", 600);
  Subscription& nmea = peer_->subscribe(topic("nmea"), dds_type("nmea_msgs", "Sentence"), Qos::default_profile());
  auto& odom = peer_->advertise("rt/odom", dds_type("nav_msgs", "Odometry"), Qos::default_profile());
  start_node({"-p", "scenario:=" + scenario.string(), "-p", "receiver:=ANT2", "-p", "pose_source:=odometry", "-p",
              "antenna_offset_m:=[1.4, 0.0, 0.0]", "-p", "base_antenna_offset_m:=[0.0, 0.0, 0.0]", "-p", "rate_hz:=5"});
  const wire::Quaternion facing_east{0.0, 0.0, 0.0, 1.0};
  std::optional<double> heading;
  ASSERT_TRUE(wait_until(
      [&] {
        odom.write(wire::encode_odometry({ros_time(now_s()), "world"}, "base_link", {0.0, 0.0, 1.5}, facing_east, {}));
        for (const auto& sample : nmea.samples()) {
          size_t left = 0;
          const auto s = wire::decode_sentence(sample, left);
          if (s.sentence.size() > 7 && s.sentence.compare(3, 4, "HDT,") == 0) heading = std::stod(s.sentence.substr(7));
        }
        // The scenario's baseline points north (0 deg) until the odometry turns the body.
        return heading.has_value() && std::abs(*heading - 90.0) < 1.0;
      },
      40s))
      << "last heading " << heading.value_or(-1.0) << "; log:\n"
      << log_text();
  node_->stop(SIGINT);
  // A receiver without a moving base refuses the parameter at start (exit 2).
  start_node({"-p", "base_antenna_offset_m:=[0.0, 0.0, 0.0]"});
  EXPECT_TRUE(wait_until([&] { return !node_->running(); }, 20s));
  EXPECT_EQ(node_->stop(SIGINT), 2) << log_text();
  EXPECT_TRUE(log_has("parameter base_antenna_offset_m: the receiver has no moving base")) << log_text();
}

TEST_F(Ros2NodeTest, IncompatibleQosIsLoggedBothWays) {
  // A transient-local subscription to the volatile fix, a best-effort publisher to the reliable /tf.
  Qos latched = Qos::default_profile();
  latched.transient_local = true;
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), latched);
  auto& tf = peer_->advertise("rt/tf", dds_type("tf2_msgs", "TFMessage"), Qos::sensor_data());
  start_node({"-p", "pose_source:=tf", "-p", "rate_hz:=5"});
  EXPECT_TRUE(wait_until([&] { return log_has("requests incompatible QoS (DURABILITY)"); }, 30s)) << log_text();
  EXPECT_TRUE(wait_until([&] { return log_has("offers incompatible QoS (RELIABILITY)"); }, 30s)) << log_text();
  // The peer's own listener hears of it on its own thread, not necessarily before the node logs.
  EXPECT_TRUE(wait_until([&] { return fix.incompatible_qos_count() > 0U; }, 30s));
  EXPECT_EQ(tf.matched(), 0);
  EXPECT_TRUE(fix.samples().empty());
  EXPECT_TRUE(node_->running());
}

TEST_F(Ros2NodeTest, SigintAndSigtermEndTheNodePromptly) {
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  for (const int signal_number : {SIGTERM, SIGINT}) {
    const size_t before = fix.samples().size();
    start_node({"-p", "rate_hz:=10", "-p", "latency_report:=" + (dir_ / "latency.json").string()});
    expect_samples(fix, before + 3, "fixes");
    const auto started = std::chrono::steady_clock::now();
    EXPECT_EQ(node_->stop(signal_number), 0) << "signal " << signal_number << "; log:\n" << log_text();
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 2.0);
    // It finished its outputs on the way out.
    std::ifstream report(dir_ / "latency.json");
    std::string json((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
    EXPECT_NE(json.find("\"p99_ms\""), std::string::npos) << json;
    std::filesystem::remove(dir_ / "latency.json");
  }
}

// bag_out records what the node publishes into a rosbag2 folder that appears when the node stops;
// Foxglove's libraries read it (tests/clients/mcap), and the fixes in it are those the peer got.
TEST_F(Ros2NodeTest, NodeRecordsABagThatFoxgloveReads) {
  const auto client = test::source_dir() / "tests" / "clients" / "mcap";
  if (!std::filesystem::exists(client / "node_modules" / "@mcap" / "core")) GTEST_SKIP() << "npm packages not installed";
  const auto bag = dir_ / "recorded";
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  // The files of the node's outputs beside the bag: the same epochs.
  start_node({"-p", "rate_hz:=10", "-p", "bag_out:=" + bag.string(), "-p", "rinex_out:=" + (dir_ / "node.obs").string(),
              "-p", "nmea_out:=" + (dir_ / "node.nmea").string()});
  expect_samples(fix, 10, "fixes");
  // Recording: only a hidden folder so far.
  EXPECT_FALSE(std::filesystem::exists(bag));
  ASSERT_EQ(node_->stop(SIGINT), 0) << log_text();
  ASSERT_TRUE(std::filesystem::exists(bag / "metadata.yaml")) << log_text();
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".recorded.partial"), std::string::npos) << entry.path();
  }
  const auto checked = test::run_command("node " + test::shell_quote((client / "check_bag.mjs").string()) + " " +
                                         test::shell_quote(bag.string()) + " 2>&1");
  ASSERT_EQ(checked.exit_code, 0) << checked.output.substr(0, 3000);
  std::map<std::string, int> counts;
  size_t at = 0;
  // Topic names and counts from the summary's "topics" list.
  while ((at = checked.output.find("\"name\": \"", at)) != std::string::npos) {
    at += 9;
    const std::string name = checked.output.substr(at, checked.output.find('"', at) - at);
    const size_t count_at = checked.output.find("\"count\": ", at) + 9;
    counts[name] = std::stoi(checked.output.substr(count_at));
  }
  EXPECT_GE(counts[namespace_ + "/fix"], static_cast<int>(fix.samples().size()) - 1) << checked.output.substr(0, 2000);
  EXPECT_GE(counts[namespace_ + "/gnss/ephemeris"], 1);
  EXPECT_EQ(counts[namespace_ + "/observations"], counts[namespace_ + "/fix"]);
  const auto count_lines = [](const std::filesystem::path& path, const std::string& start) {
    std::ifstream in(path);
    int n = 0;
    for (std::string line; std::getline(in, line);) n += line.rfind(start, 0) == 0 ? 1 : 0;
    return n;
  };
  // Every epoch is in the RINEX file; every fix of the open sky gives a GGA sentence.
  EXPECT_EQ(count_lines(dir_ / "node.obs", "> "), counts[namespace_ + "/observations"]) << log_text();
  EXPECT_EQ(count_lines(dir_ / "node.nmea", "$GNGGA") + count_lines(dir_ / "node.nmea", "$GPGGA"), counts[namespace_ + "/fix"]);
}

TEST_F(Ros2NodeTest, BagThatCannotBeWrittenLeavesNothingAndTheNodeGoesOn) {
  // An existing bag is never written over: exit 5 before anything starts.
  std::filesystem::create_directories(dir_ / "taken");
  const auto r = test::run_command("env ROS_DOMAIN_ID=" + std::to_string(domain_id_) + " ROS_LOCALHOST_ONLY=1 " +
                                   test::shell_quote(node_binary_.string()) + " --ros-args -p " +
                                   test::shell_quote("scenario:=" + scenario_.string()) + " -p " +
                                   test::shell_quote("bag_out:=" + (dir_ / "taken").string()) + " 2>&1");
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.output.find("exists"), std::string::npos) << r.output;

  // A full disk (a file size limit) while recording: the bag is given up and removed, the node
  // keeps publishing.
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  const auto bag = dir_ / "full";
  log_ = dir_ / "node.log";
  node_ = std::make_unique<test::Background>(
      "bash -c " + test::shell_quote("ulimit -f 64; exec env ROS_DOMAIN_ID=" + std::to_string(domain_id_) +
                                     " ROS_LOCALHOST_ONLY=1 " + test::shell_quote(node_binary_.string()) +
                                     " --ros-args -r __ns:=" + namespace_ + " -p " +
                                     test::shell_quote("scenario:=" + scenario_.string()) +
                                     " -p rate_hz:=20 -p bag_compression:=none -p " +
                                     test::shell_quote("bag_out:=" + bag.string())),
      log_);
  EXPECT_TRUE(wait_until([&] { return log_has("recording stopped, nothing kept"); }, 60s)) << log_text();
  const size_t before = fix.samples().size();
  expect_samples(fix, before + 5, "fixes after the bag was given up");
  EXPECT_EQ(node_->stop(SIGINT), 0) << log_text();
  EXPECT_FALSE(std::filesystem::exists(bag));
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".full.partial"), std::string::npos) << entry.path();
  }
}

TEST_F(Ros2NodeTest, BadCommandLinesAndParametersExitWithTheirCodes) {
  const std::string node = test::shell_quote(node_binary_.string());
  const auto run = [&](const std::string& args) { return test::run_command(node + " " + args + " 2>&1"); };
  auto r = run("--ros-args");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("scenario is required"), std::string::npos) << r.output;
  r = run("--ros-args -p scenario:=/nonexistent/scenario.yaml");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  r = run("--ros-args --params-file /nonexistent/params.yaml");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const auto other = dir_ / "other_node.yaml";
  std::ofstream(other) << "some_other_node:\n  ros__parameters:\n    rate_hz: 5.0\n";
  r = run("--ros-args --params-file " + test::shell_quote(other.string()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("no entry for node"), std::string::npos) << r.output;
  r = run("--ros-args -p scenario:=" + test::shell_quote(scenario_.string()) + " -p rate_hz:=fast");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = run("--ros-args -p scenario:=" + test::shell_quote(scenario_.string()) + " -p ros_distro:=foxy");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = run("--bogus");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = test::run_command("env ROS_DOMAIN_ID=500 " + node + " --ros-args -p scenario:=" + test::shell_quote(scenario_.string()) +
                        " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("ROS_DOMAIN_ID"), std::string::npos) << r.output;
}

// RTK on ROS 2: a rover node takes its corrections from the rtcm topic of a base node (as it would
// from ntrip_client), both receivers of the RTK pair; its fix becomes GBAS_FIX at the rover.
TEST_F(Ros2NodeTest, RoverNodeFixesFromTheRtcmTopicOfABaseNode) {
  const auto pair = test::shared_data_dir().parent_path() / "contract" / "rtk-pair.yaml";
  if (!std::filesystem::exists(pair) ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  }
  const std::string base_ns = namespace_ + "_base";
  const auto base_log = dir_ / "base.log";
  test::Background base("env ROS_DOMAIN_ID=" + std::to_string(domain_id_) + " ROS_LOCALHOST_ONLY=1 " +
                            test::shell_quote(node_binary_.string()) + " --ros-args -r __ns:=" + base_ns + " -p " +
                            test::shell_quote("scenario:=" + pair.string()) + " -p receiver:=BASE -p rate_hz:=2",
                        base_log);
  Subscription& fix = peer_->subscribe(topic("fix"), dds_type("sensor_msgs", "NavSatFix"), Qos::sensor_data());
  start_node({"-p", "scenario:=" + pair.string(), "-p", "receiver:=ROVR", "-p", "rate_hz:=2", "-p",
              "rtk_base_topic:=" + base_ns + "/rtcm"});
  // GBAS_FIX (2) once the rover has the base's observations and position.
  const auto rtk_fixes = [&] {
    std::vector<wire::NavSatFix> out;
    for (const auto& sample : fix.samples()) {
      size_t left = 0;
      const auto m = wire::decode_navsat_fix(sample, left);
      if (m.status == 2) out.push_back(m);
    }
    return out;
  };
  const auto base_log_text = [&] {
    std::ifstream in(base_log);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  };
  ASSERT_TRUE(wait_until([&] { return rtk_fixes().size() >= 3; }, 40s)) << log_text() << "\nbase:\n" << base_log_text();
  for (const auto& m : rtk_fixes()) {
    // The rover of the pair: 55.4935 N, 8.4880 E, 75 m, to centimetres once fixed (metres while float).
    EXPECT_NEAR(m.latitude, 55.4935, 2e-5);
    EXPECT_NEAR(m.longitude, 8.4880, 3e-5);
    EXPECT_NEAR(m.altitude, 75.0, 2.0);
  }
  EXPECT_EQ(base.stop(SIGINT), 0) << base_log_text();
}

}  // namespace
}  // namespace skytrace
