// LiveSession: the engine behind the ROS node, the Gazebo bridge and `skytrace serve`. Epochs at
// times the caller picks, poses from outside, resets, bad poses.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/core/frames.hpp"
#include "skytrace/sim/live.hpp"
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

}  // namespace
}  // namespace skytrace
