// The RTK engine's parts: LAMBDA against a published example and brute-force enumeration, the
// double-difference operator, slip detection, and the whole filter on a synthetic base/rover pair
// whose code and phase are computed here by a forward model of their own (light time, Sagnac,
// satellite clocks, integer ambiguities, deterministic noise).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "synthetic_sky.hpp"
#include "skytrace/positioning/rtk.hpp"

namespace skytrace::positioning {
namespace {

// ---- LAMBDA ----

double squared_norm(const Eigen::VectorXd& z, const Eigen::VectorXd& a, const Eigen::MatrixXd& q) {
  const Eigen::VectorXd d = z - a;
  return d.dot(q.ldlt().solve(d));
}

TEST(Lambda, TextbookExampleOfTeunissenAndDeJonge) {
  // The three-dimensional example of the LAMBDA literature (de Jonge & Tiberius 1996, Teunissen
  // 1995): strongly correlated ambiguities whose rounded values (5, 3, 3) are not the integer
  // least-squares solution (5, 3, 4).
  Eigen::Matrix3d q;
  q << 6.290, 5.978, 0.544, 5.978, 6.292, 2.340, 0.544, 2.340, 6.288;
  const Eigen::Vector3d a(5.45, 3.10, 2.97);
  const IntegerSolution s = lambda_search(a, q, 2).value();
  ASSERT_EQ(s.candidates.size(), 2u);
  EXPECT_EQ(s.candidates[0], Eigen::Vector3d(5, 3, 4));
  EXPECT_NEAR(s.squared_norms[0], squared_norm(Eigen::Vector3d(5, 3, 4), a, q), 1e-9);
  EXPECT_LT(s.squared_norms[0], squared_norm(Eigen::Vector3d(5, 3, 3), a, q));  // rounding is worse
  EXPECT_LE(s.squared_norms[0], s.squared_norms[1]);
  EXPECT_GT(s.ratio(), 1.0);
}

TEST(Lambda, AgreesWithBruteForceOnRandomWellConditionedCases) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-50.0, 50.0);
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 2 + trial % 4;  // 2..5
    Eigen::MatrixXd g(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) g(i, j) = normal(rng);
    }
    // Correlated but well conditioned: G G^T / n plus a floor, standard deviations about 0.3-1.
    Eigen::MatrixXd q = 0.3 * g * g.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd a(n);
    for (int i = 0; i < n; ++i) a(i) = uniform(rng);
    const IntegerSolution s = lambda_search(a, q, 2).value();
    ASSERT_EQ(s.candidates.size(), 2u);
    // Every integer vector within +-4 of the rounded float values.
    const Eigen::VectorXd centre = a.array().round();
    double best = INFINITY, second = INFINITY;
    Eigen::VectorXd best_z;
    Eigen::VectorXi offset = Eigen::VectorXi::Constant(n, -4);
    for (;;) {
      const Eigen::VectorXd z = centre + offset.cast<double>();
      const double norm = squared_norm(z, a, q);
      if (norm < best) {
        second = best;
        best = norm;
        best_z = z;
      } else if (norm < second) {
        second = norm;
      }
      int k = 0;
      while (k < n && ++offset(k) > 4) offset(k++) = -4;
      if (k == n) break;
    }
    EXPECT_EQ(s.candidates[0], best_z) << "trial " << trial;
    EXPECT_NEAR(s.squared_norms[0], best, 1e-6 * (1.0 + best)) << "trial " << trial;
    EXPECT_NEAR(s.squared_norms[1], second, 1e-6 * (1.0 + second)) << "trial " << trial;
    EXPECT_NEAR(squared_norm(s.candidates[1], a, q), second, 1e-6 * (1.0 + second)) << "trial " << trial;
  }
}

TEST(Lambda, RefusesACovarianceThatIsNotPositiveDefinite) {
  Eigen::Matrix2d q;
  q << 1.0, 2.0, 2.0, 1.0;
  EXPECT_FALSE(static_cast<bool>(lambda_search(Eigen::Vector2d(0.2, 0.4), q)));
  EXPECT_FALSE(static_cast<bool>(lambda_search(Eigen::Vector2d(0.2, 0.4), Eigen::Matrix3d::Identity())));
}

// ---- Double differences ----

TEST(DoubleDifferences, HighestSatelliteIsTheReferenceAndTheCovarianceIsCorrelated) {
  std::vector<SingleDifference> sds(3);
  sds[0] = {SatelliteId{GnssSystem::kGps, 1}, '1', 0.19, 10.0, 1e-4, 30.0};
  sds[1] = {SatelliteId{GnssSystem::kGps, 2}, '1', 0.19, 4.0, 2e-5, 70.0};
  sds[2] = {SatelliteId{GnssSystem::kGps, 3}, '1', 0.19, -3.0, 5e-5, 45.0};
  const DoubleDifferenceGroup dd = form_double_differences(sds);
  EXPECT_EQ(dd.reference, 1u);
  ASSERT_EQ(dd.others, (std::vector<size_t>{0, 2}));
  EXPECT_NEAR(dd.values_m(0), 6.0, 1e-12);
  EXPECT_NEAR(dd.values_m(1), -7.0, 1e-12);
  EXPECT_NEAR(dd.covariance_m2(0, 0), 1.2e-4, 1e-15);
  EXPECT_NEAR(dd.covariance_m2(1, 1), 7e-5, 1e-15);
  EXPECT_NEAR(dd.covariance_m2(0, 1), 2e-5, 1e-15);
  EXPECT_NEAR(dd.covariance_m2(1, 0), 2e-5, 1e-15);
}

// C/N0 weighting: the reference is the satellite of least variance, not the highest (a high
// satellite seen through a tree crown weighs little).
TEST(DoubleDifferences, WithCn0WeightingTheLeastVarianceIsTheReference) {
  std::vector<SingleDifference> sds(3);
  sds[0] = {SatelliteId{GnssSystem::kGps, 1}, '1', 0.19, 10.0, 1e-4, 30.0};
  sds[1] = {SatelliteId{GnssSystem::kGps, 2}, '1', 0.19, 4.0, 2e-3, 70.0};  // faded: 100 times the variance
  sds[2] = {SatelliteId{GnssSystem::kGps, 3}, '1', 0.19, -3.0, 5e-5, 45.0};
  EXPECT_EQ(form_double_differences(sds).reference, 1u);
  const DoubleDifferenceGroup dd = form_double_differences(sds, true);
  EXPECT_EQ(dd.reference, 2u);
  ASSERT_EQ(dd.others, (std::vector<size_t>{0, 1}));
  EXPECT_NEAR(dd.values_m(1), 7.0, 1e-12);
  EXPECT_NEAR(dd.covariance_m2(1, 1), 2.05e-3, 1e-15);
}

// ---- Slips ----

EpochMeasurements slip_epoch(double t_s, double clock_jump_m, double l1_extra_cycles, bool lli, double l5_extra_cycles) {
  EpochMeasurements e;
  e.receiver_time = GnssTime::from_week_tow(TimeScale::kGpst, 2100, 100.0 + t_s);
  const double l1 = constants::kSpeedOfLight_mps / kFrequencyL1_Hz, l2 = constants::kSpeedOfLight_mps / 1227.60e6;
  for (int sat = 1; sat <= 5; ++sat) {
    const double rate_mps = -300.0 + 150.0 * sat;  // range rate
    const double range_m = 2.2e7 + rate_mps * t_s + clock_jump_m;
    for (int band = 0; band < 2; ++band) {
      if (sat == 5 && band == 1) continue;  // one single-frequency satellite
      SignalMeasurement m;
      m.satellite = {GnssSystem::kGps, static_cast<std::uint8_t>(sat)};
      m.signal = Signal::parse(band == 0 ? "G1C" : "G2W").value();
      const double wavelength = band == 0 ? l1 : l2;
      m.carrier_hz = constants::kSpeedOfLight_mps / wavelength;
      m.pseudorange_m = range_m;
      m.carrier_phase_cycles = range_m / wavelength + 1000.0 * sat;
      if (band == 0 && sat == 2) *m.carrier_phase_cycles += l1_extra_cycles;
      if (band == 0 && sat == 5) *m.carrier_phase_cycles += l5_extra_cycles;
      m.loss_of_lock = lli && sat == 3 && band == 1;
      m.doppler_hz = -rate_mps / wavelength;
      e.signals.push_back(m);
    }
  }
  return e;
}

TEST(SlipDetector, FlagsLliGeometryFreeJumpsAndUnpredictedPhaseButNotClockJumps) {
  SlipDetector detector;
  EXPECT_EQ(detector.update(slip_epoch(0, 0, 0, false, 0)).size(), 9u);  // every arc is new
  EXPECT_TRUE(detector.update(slip_epoch(1, 0, 0, false, 0)).empty());
  // A millisecond receiver clock jump moves every phase alike: no slip.
  EXPECT_TRUE(detector.update(slip_epoch(2, 299792.458, 0, false, 0)).empty());
  using Keys = std::vector<std::pair<SatelliteId, char>>;
  const SatelliteId g2{GnssSystem::kGps, 2}, g3{GnssSystem::kGps, 3}, g5{GnssSystem::kGps, 5};
  // One L1 cycle on G02 (19 cm of geometry-free): both bands of G02 start again.
  EXPECT_EQ(detector.update(slip_epoch(3, 299792.458, 1.0, false, 0)), (Keys{{g2, '1'}, {g2, '2'}}));
  // The LLI flag.
  EXPECT_EQ(detector.update(slip_epoch(4, 299792.458, 1.0, true, 0)), (Keys{{g3, '2'}}));
  // A single-frequency satellite: only the Doppler sees 10 cycles (1.9 m).
  EXPECT_EQ(detector.update(slip_epoch(5, 299792.458, 1.0, false, 10.0)), (Keys{{g5, '1'}}));
  EXPECT_TRUE(detector.update(slip_epoch(6, 299792.458, 1.0, false, 10.0)).empty());
  // A gap longer than the limit.
  EXPECT_EQ(detector.update(slip_epoch(100, 299792.458, 1.0, false, 10.0)).size(), 9u);
}

// ---- The filter on a synthetic pair ----

using namespace test::synthetic;  // kToe, kTag, kSite, make_ephemeris, Truth, light_time_range


const std::vector<SkyPoint> kSky = {{10, 75}, {60, 40}, {110, 20}, {150, 55}, {200, 30},
                                    {245, 65}, {290, 25}, {330, 45}, {20, 18}, {175, 80}};
const Eigen::Vector3d kBase = geodetic_to_ecef(kSite);

// Deterministic noise in [-1, 1] from a key.
double noise(std::uint64_t key) {
  std::mt19937_64 rng(key * 0x9E3779B97F4A7C15ULL + 7);
  return std::uniform_real_distribution<double>(-1.0, 1.0)(rng);
}

struct Receiver {
  Eigen::Vector3d position_m;
  double clock_s = 0.0;
  int id = 0;
};

// Code and phase of every satellite on two bands at time tag `tag` for a receiver; integer
// ambiguities depend on receiver, satellite and band; phase noise 2 mm, code noise 0.3 m.
EpochMeasurements observe(const orbits::BroadcastEphemerides& ephemerides, const Receiver& rx, const GnssTime& tag,
                          const std::set<int>& skip = {}) {
  EpochMeasurements e;
  e.receiver_time = tag;
  const GnssTime t = tag - rx.clock_s;
  const auto epoch_key = static_cast<std::uint64_t>(std::llround((tag - kToe) * 10.0));
  for (const auto& eph : ephemerides.data().kepler) {
    if (skip.count(eph.satellite.number) > 0) continue;
    orbits::SatelliteState state;
    Eigen::Vector3d rotated;
    const double range = light_time_range(eph, t, rx.position_m, &state, &rotated);
    const bool galileo = eph.satellite.system == GnssSystem::kGalileo;
    for (int band = 0; band < 2; ++band) {
      SignalMeasurement m;
      m.satellite = eph.satellite;
      m.signal = Signal::parse(galileo ? (band == 0 ? "E1C" : "E5Q") : (band == 0 ? "G1C" : "G2W")).value();
      m.carrier_hz = find_signal_info(m.signal)->carrier_frequency_hz();
      const double wavelength = kC / m.carrier_hz;
      const double clocks_m = kC * (rx.clock_s - state.clock_bias_s - state.relativistic_s);
      const std::uint64_t key = (static_cast<std::uint64_t>(rx.id) * 1000 + eph.satellite.number * 10 +
                                 static_cast<std::uint64_t>(galileo) * 500 + static_cast<std::uint64_t>(band)) *
                                    100000 + epoch_key;
      m.pseudorange_m = range + clocks_m + kC * orbits::group_delay_s(eph, m.signal) + 0.3 * noise(key);
      const double ambiguity = static_cast<double>((rx.id * 37 + eph.satellite.number * 11 + band * 5) % 200) - 100.0;
      m.carrier_phase_cycles = (range + clocks_m + 0.002 * noise(key + 1)) / wavelength + ambiguity;
      m.cn0_dbhz = 45.0;
      e.signals.push_back(m);
    }
  }
  return e;
}

struct Pair {
  orbits::BroadcastEphemerides ephemerides;
  Receiver base, rover;
};

Pair make_pair() {
  orbits::NavigationData data;
  for (size_t i = 0; i < 8; ++i) {
    data.kepler.push_back(make_ephemeris({GnssSystem::kGps, static_cast<std::uint8_t>(i + 1)}, kSky[i], 0.01));
  }
  for (size_t i = 0; i < 6; ++i) {
    const SkyPoint sky{kSky[i].azimuth_deg + 17.0, std::max(kSky[i].elevation_deg - 8.0, 18.0)};
    data.kepler.push_back(make_ephemeris({GnssSystem::kGalileo, static_cast<std::uint8_t>(i + 3)}, sky, 0.002));
  }
  Pair pair{orbits::BroadcastEphemerides(data), {}, {}};
  pair.base = Receiver{kBase, 2e-4, 1};
  // 1.2 km east, 300 m north, 40 m up.
  pair.rover = Receiver{enu_to_ecef(Eigen::Vector3d(1200.0, 300.0, 40.0), kSite), -3e-4, 2};
  return pair;
}

RtkSettings test_settings() {
  RtkSettings s;
  s.elevation_mask_deg = 10.0;
  s.single_point.elevation_mask_deg = 5.0;
  s.single_point.ionosphere_klobuchar = false;
  s.single_point.troposphere_saastamoinen = false;
  return s;
}

TEST(RtkEngine, FixesASyntheticPairAndRecoversTheBaseline) {
  const Pair pair = make_pair();
  RtkEngine engine(pair.ephemerides, test_settings());
  int fixed = 0;
  PositionFix last;
  for (int k = 0; k < 15; ++k) {
    const GnssTime tag = kTag + static_cast<double>(k);
    BaseEpoch base{observe(pair.ephemerides, pair.base, tag), pair.base.position_m};
    const PositionFix fix = engine.solve(observe(pair.ephemerides, pair.rover, tag), &base).value();
    ASSERT_NE(fix.type, FixType::kNone) << fix.message;
    ASSERT_TRUE(fix.relative.has_value());
    if (fix.type == FixType::kRtkFixed) {
      ++fixed;
      EXPECT_LT((fix.position_ecef_m - pair.rover.position_m).norm(), 0.01) << "epoch " << k;
      EXPECT_GE(fix.relative->ratio, 3.0);
      EXPECT_EQ(fix.relative->fixed_ambiguities, 24);  // (8 - 1) + (6 - 1) per band
    } else {
      EXPECT_EQ(fix.type, FixType::kRtkFloat) << fix.message;
    }
    last = fix;
  }
  EXPECT_GE(fixed, 12);
  ASSERT_EQ(last.type, FixType::kRtkFixed);
  EXPECT_NEAR(last.relative->baseline_enu_m.x(), 1200.0, 0.01);
  EXPECT_NEAR(last.relative->baseline_enu_m.y(), 300.0, 0.01);
  EXPECT_NEAR(last.relative->baseline_enu_m.z(), 40.0, 0.01);
  EXPECT_EQ(last.relative->age_s, 0.0);
}

TEST(RtkEngine, FloatOnlyModeNeverFixesAndTheFloatConverges) {
  const Pair pair = make_pair();
  RtkSettings settings = test_settings();
  settings.ambiguity_mode = AmbiguityMode::kFloat;
  settings.dynamics = RtkDynamics::kStatic;
  RtkEngine engine(pair.ephemerides, settings);
  PositionFix fix;
  for (int k = 0; k < 30; ++k) {
    const GnssTime tag = kTag + static_cast<double>(k);
    BaseEpoch base{observe(pair.ephemerides, pair.base, tag), pair.base.position_m};
    fix = engine.solve(observe(pair.ephemerides, pair.rover, tag), &base).value();
    ASSERT_EQ(fix.type, FixType::kRtkFloat) << fix.message;
  }
  EXPECT_LT((fix.position_ecef_m - pair.rover.position_m).norm(), 0.5);
}

TEST(RtkEngine, WithoutCommonSatellitesFallsBackToTheSinglePointFixAndSaysWhy) {
  const Pair pair = make_pair();
  RtkEngine engine(pair.ephemerides, test_settings());
  // The base has a fix of its own (G01-G04, E03, E04) but none of the rover's satellites.
  BaseEpoch base{observe(pair.ephemerides, pair.base, kTag, {5, 6, 7, 8}), pair.base.position_m};
  const PositionFix fix = engine.solve(observe(pair.ephemerides, pair.rover, kTag, {1, 2, 3, 4}), &base).value();
  EXPECT_EQ(fix.type, FixType::kFix3D);
  EXPECT_NE(fix.message.find("in common with the base"), std::string::npos) << fix.message;
  const PositionFix alone = engine.solve(observe(pair.ephemerides, pair.rover, kTag + 1.0), nullptr).value();
  EXPECT_EQ(alone.type, FixType::kFix3D);
  EXPECT_NE(alone.message.find("no base observations"), std::string::npos) << alone.message;
}

TEST(RtkEngine, ABasePositionKilometresOffOrMissingIsRefused) {
  const Pair pair = make_pair();
  RtkEngine engine(pair.ephemerides, test_settings());
  const Eigen::Vector3d wrong = pair.base.position_m + Eigen::Vector3d(2000.0, -1500.0, 800.0);
  for (int k = 0; k < 5; ++k) {
    const GnssTime tag = kTag + static_cast<double>(k);
    BaseEpoch base{observe(pair.ephemerides, pair.base, tag), wrong};
    const PositionFix fix = engine.solve(observe(pair.ephemerides, pair.rover, tag), &base).value();
    EXPECT_EQ(fix.type, FixType::kFix3D);
    EXPECT_NE(fix.message.find("base position"), std::string::npos) << fix.message;
  }
  BaseEpoch missing{observe(pair.ephemerides, pair.base, kTag + 5.0), Eigen::Vector3d::Zero()};
  const PositionFix fix = engine.solve(observe(pair.ephemerides, pair.rover, kTag + 5.0), &missing).value();
  EXPECT_EQ(fix.type, FixType::kFix3D);
  EXPECT_NE(fix.message.find("no base position"), std::string::npos) << fix.message;
}

TEST(RtkEngine, AnOldBaseEpochIsNotUsed) {
  const Pair pair = make_pair();
  RtkEngine engine(pair.ephemerides, test_settings());
  BaseEpoch base{observe(pair.ephemerides, pair.base, kTag), pair.base.position_m};
  const PositionFix fix = engine.solve(observe(pair.ephemerides, pair.rover, kTag + 45.0), &base).value();
  EXPECT_EQ(fix.type, FixType::kFix3D);
  EXPECT_NEAR(fix.relative->age_s, 45.0, 1e-9);
}

}  // namespace
}  // namespace skytrace::positioning
