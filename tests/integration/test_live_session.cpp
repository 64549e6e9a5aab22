// LiveSession: the engine behind the ROS node, the Gazebo bridge and `skytrace serve`. Epochs at
// times the caller picks, poses from outside, resets, bad poses.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/sim/live.hpp"
#include "skytrace/sim/live_outputs.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

// ESBC's antenna reference point: the contract's marker plus 0.2160 m up.
Eigen::Vector3d esbc_antenna_ecef_m() {
  const Eigen::Vector3d marker(3582105.2910, 532589.7313, 5232754.8054);
  return marker + ecef_to_enu_rotation(ecef_to_geodetic(marker)).transpose() * Eigen::Vector3d(0, 0, 0.2160);
}

class LiveSessionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto path = test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
    if (!std::filesystem::exists(path) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
    }
    auto scenario = sim::load_scenario(path);
    ASSERT_TRUE(scenario.ok()) << scenario.error().message;
    scenario_ = *scenario;
  }
  sim::Scenario scenario_;
};

TEST_F(LiveSessionTest, FixOnTheStationFromItsOwnObservations) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  for (int k = 0; k < 5; ++k) {
    auto epoch = (*session)->step(scenario_.time.start + 60.0 * k);
    ASSERT_TRUE(epoch.ok()) << epoch.error().message;
    ASSERT_TRUE(epoch->fix.has_value());
    ASSERT_EQ(epoch->fix->type, positioning::FixType::kFix3D) << epoch->fix->message;
    // Noise-free observations and the same models in the engine: centimetres.
    EXPECT_LT((epoch->fix->position_ecef_m - esbc_antenna_ecef_m()).norm(), 0.05);
    EXPECT_GE(epoch->fix->satellites_used, 20);
    EXPECT_FALSE(epoch->restarted);
  }
}

TEST_F(LiveSessionTest, ExternalPoseMovesTheReceiverAndItsVelocityShowsInTheFix) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  sim::LiveSession& live = **session;
  // The world frame of a scenario without a world: east-north-up at the marker.
  const Eigen::Vector3d marker_world = live.world_frame().from_ecef(live.marker_ecef_m());
  EXPECT_LT(marker_world.norm(), 1e-6);
  // A robot driving north at 2 m/s, 100 m east of the marker; poses 10 times a second.
  const GnssTime t0 = scenario_.time.start + 600.0;
  for (int k = 0; k <= 10; ++k) {
    const double t_s = 0.1 * k;
    ASSERT_TRUE(live.set_antenna_pose_world(t0 + t_s, Eigen::Vector3d(100.0, 2.0 * t_s, 0.0)).ok());
  }
  auto epoch = live.step(t0 + 1.0);
  ASSERT_TRUE(epoch.ok()) << epoch.error().message;
  ASSERT_EQ(epoch->fix->type, positioning::FixType::kFix3D);
  const Eigen::Vector3d fix_world = live.world_frame().from_ecef(epoch->fix->position_ecef_m);
  EXPECT_NEAR(fix_world.x(), 100.0, 0.05);
  EXPECT_NEAR(fix_world.y(), 2.0, 0.05);
  ASSERT_TRUE(epoch->fix->velocity_valid);
  EXPECT_NEAR(epoch->fix->velocity_enu_mps.y(), 2.0, 0.01);
  EXPECT_NEAR(epoch->fix->velocity_enu_mps.x(), 0.0, 0.01);
  EXPECT_FALSE(epoch->pose_stale);
}

TEST_F(LiveSessionTest, PosesThatStopLeaveTheReceiverAtRestAndSaySo) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  sim::LiveSession& live = **session;
  const GnssTime t0 = scenario_.time.start + 600.0;
  ASSERT_TRUE(live.set_antenna_pose_world(t0, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(5, 0, 0)).ok());
  auto epoch = live.step(t0 + 10.0);  // the pose timed out 9 s ago
  ASSERT_TRUE(epoch.ok()) << epoch.error().message;
  EXPECT_TRUE(epoch->pose_stale);
  ASSERT_EQ(epoch->fix->type, positioning::FixType::kFix3D);
  // Held where the last pose's velocity carried it during the timeout (1 s at 5 m/s), at rest.
  const Eigen::Vector3d fix_world = live.world_frame().from_ecef(epoch->fix->position_ecef_m);
  EXPECT_NEAR(fix_world.x(), 5.0, 0.05);
  EXPECT_LT(epoch->fix->velocity_enu_mps.norm(), 0.01);
}

TEST_F(LiveSessionTest, BadPosesAreRefusedAndTheSessionGoesOn) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  sim::LiveSession& live = **session;
  const GnssTime t0 = scenario_.time.start + 60.0;
  EXPECT_FALSE(live.set_antenna_pose_world(t0, Eigen::Vector3d(NAN, 0, 0)).ok());
  EXPECT_FALSE(live.set_antenna_pose_ecef(t0, Eigen::Vector3d(1.0, 2.0, 3.0)).ok());  // at the Earth's centre
  EXPECT_FALSE(live.set_object_pose("box", Eigen::Isometry3d::Identity()).ok());     // no world
  auto epoch = live.step(t0);
  ASSERT_TRUE(epoch.ok()) << epoch.error().message;
  EXPECT_LT((epoch->fix->position_ecef_m - esbc_antenna_ecef_m()).norm(), 0.05);
}

TEST_F(LiveSessionTest, TimeGoingBackwardsRestartsTracking) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  sim::LiveSession& live = **session;
  auto first = live.step(scenario_.time.start + 300.0);
  ASSERT_TRUE(first.ok());
  auto reset = live.step(scenario_.time.start + 30.0);  // a Gazebo reset
  ASSERT_TRUE(reset.ok()) << reset.error().message;
  EXPECT_TRUE(reset->restarted);
  // A new carrier arc for every signal: the loss-of-lock flag is set on the first epoch after it.
  int signals = 0, flagged = 0;
  for (const auto& sat : reset->observations.satellites) {
    for (const auto& m : sat.signals) {
      ++signals;
      flagged += m.loss_of_lock ? 1 : 0;
    }
  }
  EXPECT_GT(signals, 0);
  EXPECT_EQ(flagged, signals);
  EXPECT_EQ(reset->fix->type, positioning::FixType::kFix3D);
}

TEST_F(LiveSessionTest, UnknownReceiverIndexIsAnError) {
  sim::LiveOptions options;
  options.receiver_index = 3;
  auto session = sim::LiveSession::create(scenario_, options);
  ASSERT_FALSE(session.ok());
  EXPECT_NE(session.error().message.find("receiver 3"), std::string::npos) << session.error().message;
}


// The files a node's parameters ask for: the sinks `skytrace run` uses, moved into place when the
// node stops, nothing before; a reset's epochs are left out of them.
TEST_F(LiveSessionTest, OutputFilesAreSinksOfTheEpochsAndAppearOnlyWhenFinished) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  const auto dir = test::make_temp_dir("live_outputs");
  const std::vector<std::pair<std::string, std::string>> paths = {{"rinex_out", (dir / "live.obs").string()},
                                                                  {"nmea_out", (dir / "live.nmea").string()},
                                                                  {"fix_csv_out", ""},
                                                                  {"rtcm_out", (dir / "live.rtcm3").string()}};
  auto outputs = sim::LiveOutputs::open(**session, paths, 30.0);
  ASSERT_TRUE(outputs.ok()) << outputs.error().message;
  int published = 0;
  (*outputs)->add_publisher(std::make_unique<sim::CallbackSink>([&](const sim::SinkEpoch& e) {
    ++published;
    EXPECT_NE(e.fix, nullptr);
    return Status(Ok{});
  }));
  std::vector<size_t> tracked;
  for (const int k : {0, 1, 2, 3, 1}) {  // the last one goes back: published, not written
    auto epoch = (*session)->step(scenario_.time.start + 30.0 * k);
    ASSERT_TRUE(epoch.ok()) << epoch.error().message;
    const auto notes = (*outputs)->add(*epoch);
    if (tracked.size() < 4) {
      EXPECT_TRUE(notes.empty()) << notes.front();
      size_t n = 0;
      for (const auto& sat : epoch->observations.satellites) n += sat.signals.empty() ? 0 : 1;
      tracked.push_back(n);
    } else {
      ASSERT_EQ(notes.size(), 1u);
      EXPECT_NE(notes.front().find("left out of the files"), std::string::npos) << notes.front();
    }
  }
  EXPECT_EQ(published, 5);
  // Nothing at the targets before the end, and only the hidden folders beside them.
  EXPECT_FALSE(std::filesystem::exists(dir / "live.obs"));
  auto finished = (*outputs)->finish();
  EXPECT_TRUE(finished.errors.empty()) << finished.errors.front();
  EXPECT_EQ(finished.written.size(), 3u);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 3);

  auto rinex = io::read_rinex_obs(dir / "live.obs");
  ASSERT_TRUE(rinex.ok()) << rinex.error().message;
  ASSERT_EQ(rinex->epochs.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(rinex->epochs[i].satellites.size(), tracked[i]) << i;
  ASSERT_TRUE(rinex->header.interval_s.has_value());
  EXPECT_DOUBLE_EQ(*rinex->header.interval_s, 30.0);

  auto nmea = read_text_file(dir / "live.nmea");
  ASSERT_TRUE(nmea.ok());
  size_t gga = 0;
  for (size_t at = nmea->find("GGA,"); at != std::string::npos; at = nmea->find("GGA,", at + 1)) ++gga;
  EXPECT_EQ(gga, 4u);

  std::ifstream rtcm_file(dir / "live.rtcm3", std::ios::binary);
  const std::vector<std::uint8_t> rtcm((std::istreambuf_iterator<char>(rtcm_file)), std::istreambuf_iterator<char>());
  io::Rtcm3Decoder decoder(scenario_.time.start);
  decoder.feed(rtcm);
  decoder.finish();
  EXPECT_EQ(decoder.take_epochs().size(), 4u);
  EXPECT_TRUE(decoder.station().has_value());
}

TEST_F(LiveSessionTest, OutputFilesThatCannotBeWrittenNameTheirParameterAndLeaveNothing) {
  auto session = sim::LiveSession::create(scenario_);
  ASSERT_TRUE(session.ok()) << session.error().message;
  const auto dir = test::make_temp_dir("live_outputs_bad");
  auto missing = sim::LiveOutputs::open(**session, {{"rinex_out", (dir / "no/such/folder/obs.rnx").string()}}, 1.0);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("parameter rinex_out"), std::string::npos) << missing.error().message;
  auto unknown = sim::LiveOutputs::open(**session, {{"obs_out", "x"}}, 1.0);
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("obs_out"), std::string::npos);

  // A device that is always full: the file fails when it is put in place, and nothing stays behind.
  auto full = sim::LiveOutputs::open(**session, {{"nmea_out", "/dev/full"}, {"rinex_out", (dir / "ok.obs").string()}}, 30.0);
  ASSERT_TRUE(full.ok()) << full.error().message;
  for (int k = 0; k < 3; ++k) {
    auto epoch = (*session)->step(scenario_.time.start + 30.0 * k);
    ASSERT_TRUE(epoch.ok());
    (void)(*full)->add(*epoch);
  }
  auto finished = (*full)->finish();
  ASSERT_EQ(finished.errors.size(), 1u);
  EXPECT_NE(finished.errors.front().find("nmea_out /dev/full"), std::string::npos) << finished.errors.front();
  ASSERT_EQ(finished.written.size(), 1u);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 1);
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::temp_directory_path())) {
    EXPECT_EQ(entry.path().filename().string().find("full.partial"), std::string::npos) << entry.path();
  }
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// Two antennas on one body in a live session (the receiver's rtk.moving_base): the base antenna is
// simulated beside the rover and the fix carries the heading of the fixed baseline. As given the
// body stands with the baseline at 30 degrees; then the node turns the body to 120 degrees by
// placing both antennas (set_antenna_pose_world, set_base_antenna_pose_world) and the heading
// follows; a receiver without a moving base refuses a base pose.
TEST(LiveSessionMovingBase, HeadingOfTheBaselineFollowsTheBody) {
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  if (!std::filesystem::exists(nav)) GTEST_SKIP() << "ESBC navigation file absent";
  const auto dir = test::make_temp_dir("live_heading");
  std::ofstream(dir / "heading.yaml") << test::moving_base_scenario_yaml(nav, "0.7, 1.2124356, 1.5", 600);
  auto scenario = sim::load_scenario(dir / "heading.yaml");
  ASSERT_TRUE(scenario.ok()) << scenario.error().message;
  sim::LiveOptions options;
  options.receiver_index = 1;
  auto session = sim::LiveSession::create(*scenario, options);
  ASSERT_TRUE(session.ok()) << session.error().message;
  sim::LiveSession& live = **session;
  ASSERT_TRUE(live.has_moving_base());
  const auto heading_at = [&](int from_s, int to_s, const std::optional<double>& body_heading_deg) {
    std::vector<double> headings;
    for (int k = from_s; k < to_s; ++k) {
      const GnssTime t = scenario->time.start + static_cast<double>(k);
      if (body_heading_deg) {
        // Body at the world origin, 1.5 m up; the base antenna at its centre, the rover 1.4 m ahead.
        const double a = *body_heading_deg * M_PI / 180.0;
        EXPECT_TRUE(live.set_base_antenna_pose_world(t, Eigen::Vector3d(0.0, 0.0, 1.5), Eigen::Vector3d::Zero()).ok());
        EXPECT_TRUE(live.set_antenna_pose_world(t, Eigen::Vector3d(1.4 * std::sin(a), 1.4 * std::cos(a), 1.5),
                                                Eigen::Vector3d::Zero()).ok());
      }
      auto epoch = live.step(t);
      EXPECT_TRUE(epoch.ok()) << epoch.error().message;
      if (!epoch.ok() || !epoch->fix || !epoch->fix->relative || !epoch->fix->relative->heading_deg) continue;
      EXPECT_EQ(epoch->fix->type, positioning::FixType::kRtkFixed);
      headings.push_back(*epoch->fix->relative->heading_deg);
    }
    return headings;
  };
  const auto as_given = heading_at(0, 60, std::nullopt);
  ASSERT_GT(as_given.size(), 40u);
  for (const double h : as_given) EXPECT_NEAR(h, 30.0, 0.5);
  const auto turned = heading_at(60, 180, 120.0);
  ASSERT_GT(turned.size(), 30u);
  EXPECT_NEAR(turned.back(), 120.0, 0.5);
  std::printf("[ figures ] live moving base: %zu headings at 30 deg, %zu after turning to 120 deg (last %.3f)\n",
              as_given.size(), turned.size(), turned.back());

  sim::LiveOptions rover_only;
  rover_only.receiver_index = 0;
  auto plain = sim::LiveSession::create(*scenario, rover_only);
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_FALSE((*plain)->has_moving_base());
  const auto refused = (*plain)->set_base_antenna_pose_world(scenario->time.start, Eigen::Vector3d::Zero());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("has no moving base"), std::string::npos) << refused.error().message;
}

}  // namespace
}  // namespace skytrace
