// The single-point solver on synthetic satellites: exact pseudoranges and Dopplers computed here by
// a forward model of their own (light time by fixed-point iteration, range rate by central
// differences), so the solver must return the point, clocks and velocity to numerical precision.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "synthetic_sky.hpp"
#include "skytrace/positioning/spp.hpp"

namespace skytrace::positioning {
namespace {

using namespace test::synthetic;  // kToe, kTag, kSite, make_ephemeris, Truth, light_time_range

SignalMeasurement measure(const orbits::KeplerEphemeris& eph, const Truth& truth) {
  const Signal signal = eph.satellite.system == GnssSystem::kGalileo ? Signal::parse("E1C").value() : Signal::parse("G1C").value();
  const double system_clock_s = truth.clock_s + (eph.satellite.system == GnssSystem::kGalileo ? truth.galileo_offset_s : 0.0);
  const GnssTime t = kTag - truth.clock_s;  // true reception time
  orbits::SatelliteState state;
  Eigen::Vector3d rotated;
  const double range = light_time_range(eph, t, truth.position_m, &state, &rotated);
  double atmosphere_m = 0.0;
  if (truth.atmosphere) {
    const Geodetic site = ecef_to_geodetic(truth.position_m);
    const AzimuthElevation direction = azimuth_elevation(truth.position_m, site, rotated);
    atmosphere_m = *atmosphere::klobuchar_delay_l1_m(kKlobuchar, t, site, direction) +
                   *atmosphere::saastamoinen_delay_m(site, direction.elevation_deg);
  }
  SignalMeasurement m;
  m.satellite = eph.satellite;
  m.signal = signal;
  m.carrier_hz = kFrequencyL1_Hz;
  m.cn0_dbhz = 45.0;
  m.pseudorange_m = range + kC * system_clock_s -
                    kC * (state.clock_bias_s + state.relativistic_s - orbits::group_delay_s(eph, signal)) + atmosphere_m;
  // Range rate by central differences of the same model (the receiver moving with its velocity).
  constexpr double h = 0.5;
  orbits::SatelliteState s_plus, s_minus;
  Eigen::Vector3d rot;
  const double range_plus = light_time_range(eph, t + h, truth.position_m + h * truth.velocity_mps, &s_plus, &rot);
  const double range_minus = light_time_range(eph, t - h, truth.position_m - h * truth.velocity_mps, &s_minus, &rot);
  const double range_rate = (range_plus - range_minus) / (2.0 * h);
  const double satellite_clock_rate = state.clock_drift_s_per_s + state.relativistic_drift_s_per_s;
  m.doppler_hz = -(range_rate + kC * (truth.drift_s_per_s - satellite_clock_rate)) / (kC / m.carrier_hz);
  return m;
}

const std::vector<SkyPoint> kSky = {{10, 75}, {60, 40}, {110, 20}, {150, 55}, {200, 30},
                                    {245, 65}, {290, 25}, {330, 45}, {20, 18}, {175, 80}};

struct Scene {
  orbits::BroadcastEphemerides ephemerides;
  EpochMeasurements epoch;
};

Scene make_scene(const Truth& truth, size_t gps_count, size_t galileo_count) {
  orbits::NavigationData data;
  for (size_t i = 0; i < gps_count; ++i) {
    data.kepler.push_back(make_ephemeris({GnssSystem::kGps, static_cast<std::uint8_t>(i + 1)}, kSky[i], 0.01));
  }
  for (size_t i = 0; i < galileo_count; ++i) {
    const SkyPoint sky{kSky[i].azimuth_deg + 17.0, std::max(kSky[i].elevation_deg - 8.0, 15.0)};
    data.kepler.push_back(make_ephemeris({GnssSystem::kGalileo, static_cast<std::uint8_t>(i + 3)}, sky, 0.002));
  }
  Scene scene{orbits::BroadcastEphemerides(data), {}};
  scene.epoch.receiver_time = kTag;
  for (const auto& eph : scene.ephemerides.data().kepler) scene.epoch.signals.push_back(measure(eph, truth));
  return scene;
}

SolverSettings exact_settings(bool atmosphere) {
  SolverSettings s;
  s.elevation_mask_deg = 5.0;
  s.ionosphere_klobuchar = atmosphere;
  s.troposphere_saastamoinen = atmosphere;
  s.convergence_m = 1e-6;
  return s;
}

TEST(SinglePointSolver, RecoversAKnownPointClocksAndVelocityExactly) {
  Truth truth;
  truth.atmosphere = true;
  truth.velocity_mps = enu_to_ecef(Eigen::Vector3d(3.0, -4.0, 0.5), kSite) - geodetic_to_ecef(kSite);
  const Scene scene = make_scene(truth, 8, 6);
  SinglePointSolver solver(scene.ephemerides, exact_settings(true), kKlobuchar);
  const PositionFix fix = solver.solve(scene.epoch).value();
  ASSERT_EQ(fix.type, FixType::kFix3D) << fix.message;
  EXPECT_EQ(fix.satellites_used, 14);
  EXPECT_LT((fix.position_ecef_m - truth.position_m).norm(), 1e-6);
  EXPECT_NEAR(fix.clock_bias_m.at(GnssSystem::kGps), kC * truth.clock_s, 1e-6);
  EXPECT_NEAR(fix.clock_bias_m.at(GnssSystem::kGalileo), kC * (truth.clock_s + truth.galileo_offset_s), 1e-6);
  EXPECT_NEAR(fix.time - kTag, -truth.clock_s, 1e-14);
  EXPECT_NEAR(fix.position.height_m, kSite.height_m, 1e-6);
  ASSERT_TRUE(fix.velocity_valid);
  EXPECT_LT((fix.velocity_ecef_mps - truth.velocity_mps).norm(), 1e-4);
  EXPECT_NEAR(fix.velocity_enu_mps.x(), 3.0, 1e-4);
  EXPECT_NEAR(fix.velocity_enu_mps.y(), -4.0, 1e-4);
  EXPECT_NEAR(fix.velocity_enu_mps.z(), 0.5, 1e-4);
  EXPECT_NEAR(fix.clock_drift_mps, kC * truth.drift_s_per_s, 1e-4);
  EXPECT_LT(fix.chi_square, 1e-9);
  EXPECT_EQ(fix.degrees_of_freedom, 14 - 5);
  for (const auto& use : fix.satellites) {
    EXPECT_TRUE(use.used) << use.satellite.to_string() << ": " << use.note;
    EXPECT_LT(std::abs(use.residual_m), 1e-6);
  }
  // The next epoch starts from this fix and converges in fewer iterations than from the centre.
  const PositionFix again = solver.solve(scene.epoch).value();
  EXPECT_LT(again.iterations, fix.iterations);
  EXPECT_LT((again.position_ecef_m - truth.position_m).norm(), 1e-6);
}

TEST(SinglePointSolver, DopsMatchAHandComputedGeometry) {
  // One satellite at the zenith and three at 30 degrees, 120 degrees apart. With s = sin 30 deg:
  // H^T H = diag-blocks 1.5 cos^2 e (east, north) and [[3 s^2 + 1, -(3 s + 1)], [-(3 s + 1), 4]]
  // (up, clock), whose inverse gives HDOP = sqrt(4/3) / cos e = 4/3, VDOP = 2 / (sqrt 3 (1 - s)),
  // TDOP = sqrt((3 s^2 + 1) / 3) / (1 - s).
  orbits::NavigationData data;
  const std::vector<SkyPoint> sky = {{0, 90}, {0, 30}, {120, 30}, {240, 30}};
  for (size_t i = 0; i < sky.size(); ++i) {
    data.kepler.push_back(make_ephemeris({GnssSystem::kGps, static_cast<std::uint8_t>(i + 1)}, sky[i]));
  }
  const orbits::BroadcastEphemerides ephemerides(data);
  Truth truth;
  EpochMeasurements epoch{kTag, {}};
  for (const auto& eph : ephemerides.data().kepler) epoch.signals.push_back(measure(eph, truth));
  SinglePointSolver solver(ephemerides, exact_settings(false));
  const PositionFix fix = solver.solve(epoch).value();
  ASSERT_EQ(fix.type, FixType::kFix3D) << fix.message;
  const double s = 0.5;
  const double hdop = 4.0 / 3.0, vdop = 2.0 / (std::sqrt(3.0) * (1 - s)), tdop = std::sqrt((3 * s * s + 1) / 3.0) / (1 - s);
  EXPECT_NEAR(fix.hdop, hdop, 1e-3);
  EXPECT_NEAR(fix.vdop, vdop, 1e-3);
  EXPECT_NEAR(fix.tdop, tdop, 1e-3);
  EXPECT_NEAR(fix.pdop, std::hypot(hdop, vdop), 1e-3);
  EXPECT_NEAR(fix.gdop, std::sqrt(hdop * hdop + vdop * vdop + tdop * tdop), 1e-3);
  EXPECT_EQ(fix.degrees_of_freedom, 0);
  EXPECT_LT((fix.position_ecef_m - truth.position_m).norm(), 1e-6);
  // The covariance is the DOP matrix scaled by the a-priori variances: equal weights here would
  // make it DOP^2 sigma^2; with elevation weights it must at least be larger than the zenith case.
  EXPECT_GT(fix.covariance_enu_m2(2, 2), 0.0);
  EXPECT_NEAR(fix.covariance_enu_m2(0, 1), fix.covariance_enu_m2(1, 0), 1e-12);
}

TEST(SinglePointSolver, RejectsAnInjectedOutlier) {
  Truth truth;
  Scene scene = make_scene(truth, 10, 0);
  scene.epoch.signals[3].pseudorange_m += 100.0;
  const SatelliteId bad = scene.epoch.signals[3].satellite;

  SolverSettings settings = exact_settings(false);
  SinglePointSolver plain(scene.ephemerides, settings);
  const PositionFix degraded = plain.solve(scene.epoch).value();
  ASSERT_EQ(degraded.type, FixType::kFix3D);
  EXPECT_GT((degraded.position_ecef_m - truth.position_m).norm(), 5.0);
  EXPECT_GT(degraded.chi_square, degraded.chi_square_threshold);
  EXPECT_EQ(degraded.satellites_used, 10);

  settings.reject_outliers = true;
  SinglePointSolver robust(scene.ephemerides, settings);
  const PositionFix fix = robust.solve(scene.epoch).value();
  ASSERT_EQ(fix.type, FixType::kFix3D) << fix.message;
  EXPECT_EQ(fix.satellites_used, 9);
  EXPECT_LT((fix.position_ecef_m - truth.position_m).norm(), 1e-6);
  EXPECT_LT(fix.chi_square, fix.chi_square_threshold);
  for (const auto& use : fix.satellites) {
    EXPECT_EQ(use.rejected, use.satellite == bad) << use.satellite.to_string();
    EXPECT_EQ(use.used, use.satellite != bad) << use.satellite.to_string();
  }
}

TEST(SinglePointSolver, TooFewSatellitesGiveNoFixWithAReason) {
  Truth truth;
  const Scene three = make_scene(truth, 3, 0);
  SinglePointSolver solver(three.ephemerides, exact_settings(false));
  const PositionFix none = solver.solve(three.epoch).value();
  EXPECT_EQ(none.type, FixType::kNone);
  EXPECT_NE(none.message.find("too few satellites"), std::string::npos) << none.message;
  EXPECT_FALSE(none.velocity_valid);

  // Four GPS and one Galileo satellite: the Galileo clock would absorb its only range, so it is left
  // out and the four GPS satellites still fix. Four GPS and two Galileo: 6 ranges, 5 unknowns.
  const Scene lone = make_scene(truth, 4, 1);
  SinglePointSolver lone_solver(lone.ephemerides, exact_settings(false));
  const PositionFix fix = lone_solver.solve(lone.epoch).value();
  ASSERT_EQ(fix.type, FixType::kFix3D) << fix.message;
  EXPECT_EQ(fix.satellites_used, 4);
  EXPECT_EQ(fix.clock_bias_m.count(GnssSystem::kGalileo), 0u);
  for (const auto& use : fix.satellites) {
    if (use.satellite.system == GnssSystem::kGalileo) {
      EXPECT_EQ(use.note, "only satellite of its system");
    }
  }
  const Scene three_two = make_scene(truth, 3, 2);
  SinglePointSolver three_two_solver(three_two.ephemerides, exact_settings(false));
  const PositionFix five = three_two_solver.solve(three_two.epoch).value();
  ASSERT_EQ(five.type, FixType::kFix3D) << five.message;
  EXPECT_LT((five.position_ecef_m - truth.position_m).norm(), 1e-6);
}

TEST(SinglePointSolver, RejectsInvalidMeasurements) {
  Truth truth;
  Scene scene = make_scene(truth, 5, 0);
  scene.epoch.signals[0].pseudorange_m = std::nan("");
  SinglePointSolver solver(scene.ephemerides, exact_settings(false));
  const auto result = solver.solve(scene.epoch);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("G01"), std::string::npos) << result.error().message;
}

TEST(SinglePointSolver, PrefersTheFirstSignalOfThePriorityList) {
  Truth truth;
  Scene scene = make_scene(truth, 6, 0);
  // A second, garbage signal per satellite (L2 P(Y)) must be ignored in favour of L1 C/A.
  const size_t n = scene.epoch.signals.size();
  for (size_t i = 0; i < n; ++i) {
    SignalMeasurement l2 = scene.epoch.signals[i];
    l2.signal = Signal::parse("G2W").value();
    l2.pseudorange_m += 1000.0;
    scene.epoch.signals.insert(scene.epoch.signals.begin(), l2);
  }
  SinglePointSolver solver(scene.ephemerides, exact_settings(false));
  const PositionFix fix = solver.solve(scene.epoch).value();
  ASSERT_EQ(fix.type, FixType::kFix3D);
  EXPECT_LT((fix.position_ecef_m - truth.position_m).norm(), 1e-6);
  for (const auto& use : fix.satellites) EXPECT_EQ(use.signal.to_string(), "G1C");
}

TEST(ChiSquare, QuantilesMatchTables) {
  // NIST/SEMATECH e-Handbook, table 1.3.6.7.4 (upper critical values).
  EXPECT_NEAR(chi_square_quantile(0.999, 1), 10.828, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.999, 5), 20.515, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.95, 10), 18.307, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.99, 30), 50.892, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.5, 2), 2.0 * std::log(2.0), 1e-9);
  EXPECT_TRUE(std::isnan(chi_square_quantile(1.0, 3)));
}

}  // namespace
}  // namespace skytrace::positioning
