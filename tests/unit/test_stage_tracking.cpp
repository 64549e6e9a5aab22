// Stages 2 and 4 (propagation paths through the antenna, tracking state): path kinds and rates,
// acquisition time after a signal rises, loss below the tracking threshold, channels, carrier
// arcs, cycle slips at low C/N0 only, the half-cycle flag.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/receiver/stages/propagation.hpp"
#include "skytrace/receiver/stages/tracking.hpp"

namespace skytrace::receiver::stages {
namespace {

using Lock = TrackingState::Lock;

SignalPath path(PathType type, double excess_m, const Eigen::Vector3d& arrival) {
  SignalPath p;
  p.type = type;
  p.excess_delay_m = excess_m;
  p.arrival_direction = arrival.normalized();
  return p;
}

TEST(StagePropagation, PathKindsDirectionsAndDelayRates) {
  const AntennaPattern antenna = builtin_profile("ideal").value().antenna;
  const AzimuthElevation direct{0.0, 60.0};
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  EXPECT_EQ(receive_paths({}, antenna, direct, identity, {}, {}).kind, PathKind::kNone);
  EXPECT_EQ(receive_paths({path(PathType::kDirect, 0.0, up)}, antenna, direct, identity, {}, {}).kind, PathKind::kLos);
  SignalPath reflected = path(PathType::kReflected, 12.0, Eigen::Vector3d(1.0, 0.0, -0.2));
  reflected.delay_gradient_origin = Eigen::Vector3d(0.0, 0.0, -2.0);
  reflected.delay_gradient_direction = Eigen::Vector3d(3.0, 0.0, 0.0);
  const ReceivedPaths both = receive_paths({path(PathType::kDirect, 0.0, up), reflected}, antenna, direct, identity,
                                           Eigen::Vector3d(0.0, 0.0, 1.5), Eigen::Vector3d(1e-4, 0.0, 0.0));
  EXPECT_EQ(both.kind, PathKind::kMultipath);
  ASSERT_EQ(both.received.size(), 2u);
  EXPECT_NEAR(both.arrival_directions[0].elevation_deg, 90.0, 1e-9);
  EXPECT_NEAR(both.arrival_directions[1].azimuth_deg, 90.0, 1e-9);  // world x is east here
  EXPECT_NEAR(both.delay_rates_mps[1], -2.0 * 1.5 + 3.0 * 1e-4, 1e-12);
  EXPECT_DOUBLE_EQ(both.received[1].excess_delay_m, 12.0);
  EXPECT_EQ(receive_paths({reflected}, antenna, direct, identity, {}, {}).kind, PathKind::kNlos);
}

TEST(StagePropagation, DirectionRateIsTheTransverseVelocityOverRange) {
  const Eigen::Vector3d los = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d rate = direction_rate_per_s(los, 2e7, Eigen::Vector3d(3000.0, 0.0, 800.0), Eigen::Vector3d::Zero());
  EXPECT_NEAR(rate.x(), 3000.0 / 2e7, 1e-15);
  EXPECT_NEAR(rate.z(), 0.0, 1e-15);  // along the line of sight the direction does not turn
}

class StageTracking : public ::testing::Test {
 protected:
  const SatelliteId sat_{GnssSystem::kGps, 3};
  const Signal l1_ = Signal::parse("G1C").value();
  const Signal l5_ = Signal::parse("G5Q").value();
  GnssTime t0_ = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  ReceiverProfile profile_ = builtin_profile("septentrio-polarx5").value();

  Lock step(TrackingState& tracking, const Signal& signal, double cn0_dbhz, const GnssTime& tag,
            const std::optional<GnssTime>& last, std::string* why = nullptr) {
    int channels = 0;
    SatelliteAcquisition a = tracking.begin_satellite(profile_, false, last.has_value());
    const Lock lock = tracking.lock(profile_, sat_, signal, cn0_dbhz, tag, last, channels, a);
    if (why != nullptr) *why = a.not_tracked_because;
    return lock;
  }
};

TEST_F(StageTracking, AcquisitionTimeAfterASignalRises) {
  profile_.acquisition_time_s = 5.0;
  TrackingState tracking(1, 0, false);
  const double strong = profile_.acquisition_threshold_dbhz + 5.0;
  // The first epoch: the receiver ran before and tracks at once.
  EXPECT_EQ(step(tracking, l1_, strong, t0_, std::nullopt), Lock::kNewArc);
  (void)tracking.carrier_arc(profile_, sat_, l1_, true, strong, false, true, t0_, std::nullopt);
  EXPECT_EQ(step(tracking, l1_, strong, t0_ + 1.0, t0_), Lock::kContinuing);
  (void)tracking.carrier_arc(profile_, sat_, l1_, false, strong, false, true, t0_ + 1.0, t0_);
  // Lost below the tracking threshold, then above the acquisition threshold again at epoch 3:
  // above since 2.5 s, acquired 5 s later, i.e. tracked from epoch 8 on.
  std::string why;
  EXPECT_EQ(step(tracking, l1_, profile_.tracking_threshold_dbhz - 1.0, t0_ + 2.0, t0_ + 1.0, &why), Lock::kNone);
  EXPECT_EQ(why, "below the tracking threshold");
  for (int k = 3; k <= 7; ++k) {
    EXPECT_EQ(step(tracking, l1_, strong, t0_ + k, t0_ + (k - 1), &why), Lock::kNone) << k;
    EXPECT_EQ(why, "acquiring");
  }
  int channels = 0;
  SatelliteAcquisition a = tracking.begin_satellite(profile_, false, true);
  EXPECT_EQ(tracking.lock(profile_, sat_, l1_, strong, t0_ + 8.0, t0_ + 7.0, channels, a), Lock::kNewArc);
  ASSERT_TRUE(a.acquired.has_value());
  EXPECT_DOUBLE_EQ(*a.acquired - t0_, 7.5);
  EXPECT_EQ(channels, 1);
}

TEST_F(StageTracking, AidedSearchDwellFollowsSquareLawDetection) {
  // K = 25 (1 + 2 rho) / rho^2 coherent blocks of 20 ms, rho = C/N0 T: independent numbers.
  for (const double cn0_dbhz : {15.0, 24.0, 30.0, 45.0}) {
    const double rho = std::pow(10.0, cn0_dbhz / 10.0) * 0.02;
    EXPECT_NEAR(reacquisition_dwell_s(cn0_dbhz, 0.02), 0.02 * 25.0 * (1.0 + 2.0 * rho) / (rho * rho), 1e-12);
  }
  EXPECT_NEAR(reacquisition_dwell_s(15.0, 0.02), 2.83, 0.01);
  EXPECT_NEAR(reacquisition_dwell_s(24.0, 0.02), 0.219, 0.001);
  EXPECT_LT(reacquisition_dwell_s(40.0, 0.02), 0.01);  // a strong signal: within one epoch
}

TEST_F(StageTracking, RunningReceiverReacquiresFromItsAidedThreshold) {
  profile_ = builtin_profile("ublox-m8t").value();
  ASSERT_TRUE(profile_.reacquisition_threshold_dbhz.has_value());
  const double aided_dbhz = *profile_.reacquisition_threshold_dbhz;
  ASSERT_LT(aided_dbhz, profile_.acquisition_threshold_dbhz);
  EXPECT_EQ(search_threshold_dbhz(profile_, false), profile_.acquisition_threshold_dbhz);
  EXPECT_EQ(search_threshold_dbhz(profile_, true), aided_dbhz);
  // A strong signal lost at 1 s comes back at 2 s: reacquired at once (its dwell is milliseconds),
  // where a cold search would take acquisition_time_s.
  TrackingState tracking(1, 0, false);
  EXPECT_EQ(step(tracking, l1_, 45.0, t0_, std::nullopt), Lock::kNewArc);
  (void)tracking.carrier_arc(profile_, sat_, l1_, true, 45.0, false, true, t0_, std::nullopt);
  EXPECT_EQ(step(tracking, l1_, 5.0, t0_ + 1.0, t0_), Lock::kNone);
  EXPECT_EQ(step(tracking, l1_, 45.0, t0_ + 2.0, t0_ + 1.0), Lock::kNewArc);
  // A weak one (just above the aided threshold, below the cold one), at 0.1 s epochs: found after
  // its dwell, counted from half an epoch before it first appeared.
  TrackingState weak(1, 0, false);
  const double cn0_dbhz = aided_dbhz + 1.0;
  const double dwell_s = reacquisition_dwell_s(cn0_dbhz, profile_.integration_time_s);
  ASSERT_GT(dwell_s, 1.0);
  std::optional<GnssTime> last = t0_;
  int epochs = 0;
  std::string why;
  while (step(weak, l1_, cn0_dbhz, *last + 0.1, last, &why) == Lock::kNone && epochs < 1000) {
    EXPECT_EQ(why, "acquiring");
    last = *last + 0.1;
    ++epochs;
  }
  EXPECT_NEAR((epochs + 1) * 0.1, dwell_s + 0.05, 0.1);
  // Steadily 1 dB below the aided threshold: never found (each window ends at the threshold's
  // detection time and starts over).
  TrackingState below(1, 0, false);
  last = t0_;
  for (int k = 1; k <= 300; ++k) {
    EXPECT_EQ(step(below, l1_, aided_dbhz - 1.0, t0_ + 0.1 * k, last, &why), Lock::kNone) << k;
    EXPECT_EQ(why, "below the acquisition threshold");
    last = t0_ + 0.1 * k;
  }
  // A fade of 0.1 s every second within the window slows the detection but does not restart it:
  // found after the steady signal's dwell, before the window ends.
  TrackingState dips(1, 0, false);
  last = t0_;
  int found_at = 0;
  for (int k = 1; k <= 100 && found_at == 0; ++k) {
    const double c = k % 10 == 0 ? 0.0 : cn0_dbhz;
    if (step(dips, l1_, c, t0_ + 0.1 * k, last) == Lock::kNewArc) found_at = k;
    last = t0_ + 0.1 * k;
  }
  ASSERT_GT(found_at, 0);
  EXPECT_GT(found_at * 0.1, dwell_s);
  EXPECT_LE(found_at * 0.1, reacquisition_dwell_s(aided_dbhz, profile_.integration_time_s) + 0.05);
  // A profile without an aided threshold keeps its cold acquisition after the first epoch.
  profile_.reacquisition_threshold_dbhz.reset();
  TrackingState cold(1, 0, false);
  EXPECT_EQ(step(cold, l1_, cn0_dbhz, t0_ + 0.1, t0_, &why), Lock::kNone);
  EXPECT_EQ(why, "below the acquisition threshold");
}

TEST_F(StageTracking, ChannelsRunOut) {
  profile_.channel_count = 1;
  TrackingState tracking(1, 0, false);
  int channels = 0;
  SatelliteAcquisition a = tracking.begin_satellite(profile_, true, false);
  EXPECT_EQ(tracking.lock(profile_, sat_, l1_, 45.0, t0_, std::nullopt, channels, a), Lock::kNewArc);
  EXPECT_EQ(tracking.lock(profile_, sat_, l5_, 45.0, t0_, std::nullopt, channels, a), Lock::kNone);
  EXPECT_EQ(a.not_tracked_because, "no free channel");
}

TEST_F(StageTracking, CarrierArcsAmbiguitiesAndSlips) {
  const double pll_hz = profile_.pll_bandwidth_hz;
  ASSERT_GT(pll_hz, 0.0);
  auto run = [&](double cn0_dbhz, int epochs, int* new_arcs_seen) {
    TrackingState tracking(3, 0, true);
    int slips = 0;
    std::optional<GnssTime> last;
    std::int64_t first_ambiguity = 0;
    for (int k = 0; k < epochs; ++k) {
      const GnssTime tag = t0_ + k;
      const auto arc = tracking.carrier_arc(profile_, sat_, l1_, k == 0, cn0_dbhz, false, true, tag, last);
      if (k == 0) {
        EXPECT_TRUE(arc.loss_of_lock);
        EXPECT_EQ(arc.lock_time_s, 0.0);
        EXPECT_TRUE(arc.half_cycle_unresolved);
        EXPECT_LE(std::abs(arc.ambiguity_cycles), 1000000);
        first_ambiguity = arc.ambiguity_cycles;
      } else if (arc.loss_of_lock) {
        ++slips;
        EXPECT_EQ(arc.lock_time_s, 0.0);
        EXPECT_NE(arc.ambiguity_cycles, first_ambiguity);  // a slip is a whole, non-zero number of cycles
        first_ambiguity = arc.ambiguity_cycles;
      } else {
        EXPECT_GT(arc.lock_time_s, 0.0);
      }
      last = tag;
    }
    if (new_arcs_seen != nullptr) *new_arcs_seen = slips;
    return slips;
  };
  EXPECT_EQ(run(50.0, 2000, nullptr), 0);
  EXPECT_GT(run(profile_.tracking_threshold_dbhz, 2000, nullptr), 5);
  // A new arc draws a new ambiguity; without noise (no slip streams) an arc never slips.
  TrackingState quiet(3, 0, false);
  const auto a = quiet.carrier_arc(profile_, sat_, l1_, true, 10.0, false, true, t0_, std::nullopt);
  const auto b = quiet.carrier_arc(profile_, sat_, l1_, false, 10.0, false, true, t0_ + 1.0, t0_);
  const auto c = quiet.carrier_arc(profile_, sat_, l1_, true, 10.0, false, true, t0_ + 2.0, t0_ + 1.0);
  EXPECT_FALSE(b.loss_of_lock);
  EXPECT_EQ(a.ambiguity_cycles, b.ambiguity_cycles);
  EXPECT_NE(a.ambiguity_cycles, c.ambiguity_cycles);
  // The half-cycle ambiguity resolves after the profile's time on a data signal, never on a pilot.
  const auto later = quiet.carrier_arc(profile_, sat_, l1_, false, 45.0, false, true,
                                       t0_ + 2.0 + profile_.half_cycle_resolution_s + 1.0, t0_ + 2.0);
  EXPECT_FALSE(later.half_cycle_unresolved);
  EXPECT_FALSE(quiet.carrier_arc(profile_, sat_, l5_, true, 45.0, false, false, t0_, std::nullopt).half_cycle_unresolved);
}

}  // namespace
}  // namespace skytrace::receiver::stages
