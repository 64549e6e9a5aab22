// Real against simulated observations: two synthetic RINEX files where SIM = REAL + a known clock
// per epoch + known per-satellite offsets. The clock part must vanish and the per-satellite offsets
// come out as residuals computed by hand below.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/io/compare.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace::io {
namespace {

using G = GnssSystem;

const GnssTime kT0 =
    GnssTime::from_calendar(CalendarTime{2020, 6, 25, 0, 0, 0.0}, TimeScale::kGpst);
const std::array<double, 3> kStationEcef_m = {3582105.2910, 532589.7313, 5232754.8054};
constexpr double kLambdaL1_m = constants::kSpeedOfLight_mps / 1575.42e6;
constexpr double kRealInterval_s = 30.0;
constexpr double kSimInterval_s = 10.0;
constexpr int kRealEpochs = 10;  // 0 .. 270 s
constexpr int kSimEpochs = 31;   // 0 .. 300 s: every third one is a real epoch

// Known per-satellite offsets added to the simulation (index = satellite number).
const std::map<int, double> kGpsPseudorangeOffset_m = {{1, 0.0}, {2, 1.5},  {3, -2.0},
                                                       {4, 4.0}, {5, 10.0}, {6, 0.0}};
const std::map<int, double> kGalileoPseudorangeOffset_m = {{1, 0.2}, {2, -0.2}, {3, 0.4}, {4, 1.0}};
const std::map<int, double> kGpsDopplerOffset_hz = {{1, 0.0}, {2, 0.5},   {3, -0.25},
                                                    {4, 1.0}, {5, 0.125}, {6, 0.0}};
// Phase drift per real interval, in cycles (GPS) and metres (GLONASS).
const std::map<int, double> kGpsPhaseDrift_cycles = {{1, 0.0},  {2, 0.0},   {3, 0.0},
                                                     {4, 0.01}, {5, -0.02}, {6, 0.0}};
const std::map<int, double> kGlonassRangeRateOffset_mps = {{1, 0.0}, {2, 0.05}, {3, -0.03}};
const std::map<int, double> kGlonassPhaseDrift_m = {{1, 0.0}, {2, 0.002}, {3, -0.001}};
const std::map<int, double> kGpsCn0Offset_dbhz = {{1, 1.0},  {2, 2.0}, {3, 3.0},
                                                  {4, -1.0}, {5, 0.0}, {6, 0.0}};
const std::map<int, int> kGlonassChannel = {{1, 1}, {2, -4}, {3, 5}};

double glonass_lambda_m(int slot) {
  return constants::kSpeedOfLight_mps / (1602.0e6 + 0.5625e6 * kGlonassChannel.at(slot));
}

ObservationHeader header(bool with_glonass_slots) {
  ObservationHeader h;
  h.program = "unit test";
  h.date = "20200625 000000 UTC";
  h.marker_name = "CMP";
  h.approx_position_ecef_m = kStationEcef_m;
  for (G system : {G::kGps, G::kGalileo, G::kGlonass}) {
    h.observation_types[system] = {{"C1C", {}}, {"L1C", {}}, {"D1C", {}}, {"S1C", {}}};
  }
  h.signal_strength_unit = "DBHZ";
  if (with_glonass_slots) {
    for (const auto& [slot, channel] : kGlonassChannel) h.glonass_slots.push_back({slot, channel});
  }
  return h;
}

// "Real" observables of satellite n of a system at k real intervals after the start: multiples of
// 0.001 so the files hold them exactly.
struct Observables {
  double pseudorange_m, phase_cycles, doppler_hz, cn0_dbhz;
};
Observables real_observables(G system, int n, double k) {
  const double system_offset_m =
      system == G::kGalileo ? 5.0e5 : (system == G::kGlonass ? 7.0e5 : 0.0);
  return {2.0e7 + 1000.0 * n + 100.0 * k + system_offset_m, 1.0e8 + 10000.0 * n + 500.25 * k,
          -1000.0 + 10.0 * n + 0.5 * k, 40.0 + n};
}

// The simulation: the real values plus a receiver clock common to all satellites (different in each
// epoch, with an inter-system bias) plus the per-satellite offsets above.
Observables sim_observables(G system, int n, double k) {
  Observables o = real_observables(system, n, k);
  const double clock_m = 29979.246 + 299.792 * k;
  const double clock_phase_m = 1000.0 * k * k;
  const double clock_rate_mps = 150.0 + 3.0 * k;
  if (system == G::kGps) {
    o.pseudorange_m += clock_m + kGpsPseudorangeOffset_m.at(n);
    o.phase_cycles += 157.542 * k * k + kGpsPhaseDrift_cycles.at(n) * k;
    o.doppler_hz += 250.0 + 7.0 * k + kGpsDopplerOffset_hz.at(n);
    o.cn0_dbhz -= kGpsCn0Offset_dbhz.at(n);
  } else if (system == G::kGalileo) {
    o.pseudorange_m += clock_m + 12.345 + kGalileoPseudorangeOffset_m.at(n);
    o.phase_cycles += 157.542 * k * k;
    o.doppler_hz += 250.0 + 7.0 * k;
  } else {
    // GLONASS FDMA: a clock common in metres is a different number of cycles and hertz per
    // satellite.
    const double lambda_m = glonass_lambda_m(n);
    o.pseudorange_m += clock_m - 7.5;
    o.phase_cycles += (clock_phase_m + kGlonassPhaseDrift_m.at(n) * k) / lambda_m;
    o.doppler_hz -= (clock_rate_mps + kGlonassRangeRateOffset_mps.at(n)) / lambda_m;
  }
  return o;
}

SatelliteObservations record(G system, int n, const Observables& o, std::uint8_t phase_lli = 0,
                             bool with_phase = true) {
  SatelliteObservations s;
  s.satellite = SatelliteId{system, static_cast<std::uint8_t>(n)};
  s.values = {ObservationValue{o.pseudorange_m, 0, 0},
              with_phase ? ObservationValue{o.phase_cycles, phase_lli, 0} : ObservationValue{},
              ObservationValue{o.doppler_hz, 0, 0}, ObservationValue{o.cn0_dbhz, 0, 0}};
  return s;
}

// REAL: 30 s epochs with G01-G05, E01-E04, R01-R03; G02 loses lock at 180 s.
std::vector<ObservationEpoch> real_epochs(double time_shift_s = 0.0) {
  std::vector<ObservationEpoch> epochs;
  for (int e = 0; e < kRealEpochs; ++e) {
    const double k = e;
    ObservationEpoch epoch;
    epoch.time = kT0 + kRealInterval_s * k + time_shift_s;
    for (int n = 1; n <= 5; ++n) {
      epoch.satellites.push_back(
          record(G::kGps, n, real_observables(G::kGps, n, k), (n == 2 && e == 6) ? 1 : 0));
    }
    for (int n = 1; n <= 4; ++n)
      epoch.satellites.push_back(record(G::kGalileo, n, real_observables(G::kGalileo, n, k)));
    for (int n = 1; n <= 3; ++n)
      epoch.satellites.push_back(record(G::kGlonass, n, real_observables(G::kGlonass, n, k)));
    epochs.push_back(std::move(epoch));
  }
  return epochs;
}

// SIM: 10 s epochs; G05 only from 150 s, G06 (which REAL never sees) always, G03 without phase at
// 70 s (an epoch REAL does not have: the phase step 60 -> 90 s must be dropped).
std::vector<ObservationEpoch> sim_epochs() {
  std::vector<ObservationEpoch> epochs;
  for (int e = 0; e < kSimEpochs; ++e) {
    const double t_s = kSimInterval_s * e;
    const double k = t_s / kRealInterval_s;
    ObservationEpoch epoch;
    epoch.time = kT0 + t_s;
    for (int n = 1; n <= 6; ++n) {
      if (n == 5 && t_s < 150.0) continue;
      epoch.satellites.push_back(
          record(G::kGps, n, sim_observables(G::kGps, n, k), 0, !(n == 3 && e == 7)));
    }
    for (int n = 1; n <= 4; ++n)
      epoch.satellites.push_back(record(G::kGalileo, n, sim_observables(G::kGalileo, n, k)));
    for (int n = 1; n <= 3; ++n)
      epoch.satellites.push_back(record(G::kGlonass, n, sim_observables(G::kGlonass, n, k)));
    epochs.push_back(std::move(epoch));
  }
  return epochs;
}

class Compare : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir(std::string("compare_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    real_ = dir_ / "real.rnx";
    sim_ = dir_ / "sim.rnx";
    // GLONASS SLOT / FRQ # only in the real file: the channels of either file serve.
    ASSERT_TRUE(write_rinex_obs(real_, header(true), real_epochs()).ok());
    ASSERT_TRUE(write_rinex_obs(sim_, header(false), sim_epochs()).ok());
  }
  static const SignalComparison& row(const ComparisonReport& report, const char* name) {
    for (const auto& s : report.signals) {
      if (s.signal.to_string() == name) return s;
    }
    throw std::runtime_error(std::string("no row ") + name);
  }
  std::filesystem::path dir_, real_, sim_;
};

TEST(ResidualStatistics, PercentilesInterpolateLikeNumpy) {
  // numpy.percentile(|r|, 68) = 3.72, (|r|, 95) = 4.8 for |r| = 1..5.
  const auto s = residual_statistics({1.0, -2.0, 3.0, -4.0, 5.0});
  EXPECT_EQ(s.count, 5u);
  EXPECT_NEAR(s.abs_p68, 3.72, 1e-12);
  EXPECT_NEAR(s.abs_p95, 4.8, 1e-12);
  EXPECT_NEAR(s.mean, 0.6, 1e-12);
  EXPECT_NEAR(s.rms, std::sqrt(11.0), 1e-12);
  EXPECT_TRUE(std::isnan(residual_statistics({}).abs_p68));
  EXPECT_EQ(residual_statistics({-2.5}).abs_p95, 2.5);
}

TEST_F(Compare, ClockRemovedAndKnownPseudorangeResidualsComeOut) {
  auto report = compare_observation_files(real_, sim_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->real_epochs, 10u);
  EXPECT_EQ(report->sim_epochs, 31u);
  EXPECT_EQ(report->common_epochs, 10u);
  EXPECT_FALSE(report->elevation_mask_applied);
  ASSERT_EQ(report->signals.size(), 3u);  // G1C R1C E1C, in system order
  EXPECT_EQ(report->signals[0].signal.to_string(), "G1C");
  EXPECT_EQ(report->signals[1].signal.to_string(), "R1C");
  EXPECT_EQ(report->signals[2].signal.to_string(), "E1C");

  // GPS: offsets {0, 1.5, -2, 4} (G01-G04) at 0-120 s, median 0.75, residuals -(offset - median) =
  // {0.75, -0.75, 2.75, -3.25}; with G05 (offset 10) at 150-270 s, median 1.5: {1.5, 0, 3.5, -2.5,
  // -8.5}. Sorted |r| (45 values): 0 x5, 0.75 x10, 1.5 x5, 2.5 x5, 2.75 x5, 3.25 x5, 3.5 x5, 8.5
  // x5.
  const auto& gps = row(*report, "G1C");
  EXPECT_EQ(gps.pseudorange_m.count, 45u);
  EXPECT_NEAR(gps.pseudorange_m.mean, (5 * -0.5 + 5 * -6.0) / 45.0, 1e-6);
  EXPECT_NEAR(gps.pseudorange_m.rms, std::sqrt((5 * 19.25 + 5 * 93.0) / 45.0), 1e-6);
  EXPECT_NEAR(gps.pseudorange_m.abs_p68, 2.75 + 0.92 * 0.5, 1e-6);  // rank 0.68 * 44 = 29.92
  EXPECT_NEAR(gps.pseudorange_m.abs_p95, 8.5, 1e-6);
  EXPECT_EQ(gps.single_satellite_epochs, 0u);
  // The same residuals per satellite: G01 0.75 then 1.5, G02 -0.75 then 0, G05 -8.5 (from 150 s).
  const auto& by_satellite = gps.pseudorange_by_satellite_m;
  ASSERT_EQ(by_satellite.size(), 5u);
  const SatelliteId g01{G::kGps, 1}, g02{G::kGps, 2}, g05{G::kGps, 5};
  EXPECT_EQ(by_satellite.at(g01).count, 10u);
  EXPECT_NEAR(by_satellite.at(g01).mean, 1.125, 1e-6);
  EXPECT_NEAR(by_satellite.at(g02).mean, -0.375, 1e-6);
  EXPECT_EQ(by_satellite.at(g05).count, 5u);
  EXPECT_NEAR(by_satellite.at(g05).mean, -8.5, 1e-6);
  EXPECT_NEAR(by_satellite.at(g05).rms, 8.5, 1e-6);

  // Galileo: the inter-system bias goes with the clock. Offsets {0.2, -0.2, 0.4, 1.0}, median 0.3.
  const auto& gal = row(*report, "E1C");
  EXPECT_EQ(gal.pseudorange_m.count, 40u);
  EXPECT_NEAR(gal.pseudorange_m.mean, -0.05, 1e-6);
  EXPECT_NEAR(gal.pseudorange_m.rms, std::sqrt((0.01 + 0.25 + 0.01 + 0.49) / 4.0), 1e-6);
  EXPECT_NEAR(gal.pseudorange_m.abs_p95, 0.7, 1e-6);
  EXPECT_NEAR(gal.pseudorange_by_satellite_m.at(SatelliteId{G::kGalileo, 4}).mean, -0.7, 1e-6);
  // Nothing but the clock in Galileo Doppler and phase: zero residuals.
  EXPECT_EQ(gal.doppler_mps.count, 40u);
  EXPECT_NEAR(gal.doppler_mps.rms, 0.0, 1e-9);
  EXPECT_EQ(gal.phase_difference_m.count, 36u);
  EXPECT_NEAR(gal.phase_difference_m.rms, 0.0, 1e-9);
}

TEST_F(Compare, DopplerInMetresPerSecondWithGlonassChannels) {
  auto report = compare_observation_files(real_, sim_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  // GPS: SIM Doppler = REAL + clock + offset (Hz); range-rate residual = lambda (offset - median):
  // 0-120 s median 0.25 -> lambda {-0.25, 0.25, -0.5, 0.75}; 150-270 s median 0.125 ->
  // lambda {-0.125, 0.375, -0.375, 0.875, 0}: mean lambda (5 * 0.25 + 5 * 0.75) / 45 = lambda / 9.
  const auto& gps = row(*report, "G1C");
  EXPECT_EQ(gps.doppler_mps.count, 45u);
  EXPECT_NEAR(gps.doppler_mps.mean, kLambdaL1_m / 9.0, 1e-9);
  EXPECT_NEAR(gps.doppler_mps.abs_p95, 0.875 * kLambdaL1_m, 1e-9);

  // GLONASS: a common 150 + 3k m/s in Hz at each satellite's own wavelength, offsets {0, 0.05,
  // -0.03} m/s, median 0 -> residuals {0, -0.05, 0.03}. A wrong channel would leave metres per
  // second. Tolerance: the simulated Doppler is rounded to 0.001 Hz in the file (0.0002 m/s).
  const auto& glo = row(*report, "R1C");
  EXPECT_EQ(glo.doppler_mps.count, 30u);
  EXPECT_EQ(glo.unknown_channel_satellite_epochs, 0u);
  EXPECT_NEAR(glo.doppler_mps.mean, -0.02 / 3.0, 2e-4);
  EXPECT_NEAR(glo.doppler_mps.rms, std::sqrt((0.0025 + 0.0009) / 3.0), 2e-4);
  EXPECT_NEAR(glo.doppler_mps.abs_p95, 0.05, 2e-4);
}

TEST_F(Compare, EpochDifferencedPhaseSkipsLossOfLockAndGaps) {
  auto report = compare_observation_files(real_, sim_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  // GPS steps between the 10 common epochs: G01-G04 for steps ending at 30-150 s (G05 appears in
  // SIM at 150 s, so it has no step ending there), G01-G05 for 180-270 s = 4 * 5 + 5 * 4 = 40, less
  // G02 at 180 s (REAL loss of lock) and G03 at 90 s (SIM phase gap at 70 s): 38.
  // Drift {0, 0, 0, 0.01, -0.02} cycles per step: every median is 0, residuals -lambda drift.
  const auto& gps = row(*report, "G1C");
  EXPECT_EQ(gps.phase_difference_m.count, 38u);
  EXPECT_NEAR(gps.phase_difference_m.mean, (9 * -0.01 + 4 * 0.02) * kLambdaL1_m / 38.0, 1e-7);
  EXPECT_NEAR(gps.phase_difference_m.rms, kLambdaL1_m * std::sqrt((9 * 1e-4 + 4 * 4e-4) / 38.0),
              1e-7);
  EXPECT_NEAR(gps.phase_difference_m.abs_p68, 0.01 * kLambdaL1_m, 1e-7);
  EXPECT_NEAR(gps.phase_difference_m.abs_p95, 0.02 * kLambdaL1_m, 1e-7);

  // GLONASS: a clock of 1000 k^2 m in cycles of each channel, drift {0, 0.002, -0.001} m per step.
  // Tolerance: the simulated phase is rounded to 0.001 cycle (0.19 mm) at both ends of a step.
  const auto& glo = row(*report, "R1C");
  EXPECT_EQ(glo.phase_difference_m.count, 27u);
  EXPECT_NEAR(glo.phase_difference_m.mean, -0.001 / 3.0, 4e-4);
  EXPECT_NEAR(glo.phase_difference_m.abs_p95, 0.002, 4e-4);
}

TEST_F(Compare, Cn0AndTrackedOverlap) {
  auto report = compare_observation_files(real_, sim_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  const auto& gps = row(*report, "G1C");
  // REAL G01-G05 x 10 = 50; SIM G01-G04 x 10 + G05 x 5 + G06 x 10 = 55; both 45.
  EXPECT_EQ(gps.real_tracked, 50u);
  EXPECT_EQ(gps.sim_tracked, 55u);
  EXPECT_EQ(gps.both_tracked, 45u);
  EXPECT_DOUBLE_EQ(gps.real_in_sim_fraction(), 0.9);
  EXPECT_DOUBLE_EQ(gps.sim_in_real_fraction(), 45.0 / 55.0);
  // C/N0 real - sim = offsets {1, 2, 3, -1} at 5 epochs, {1, 2, 3, -1, 0} at 5 epochs.
  EXPECT_EQ(gps.cn0_count, 45u);
  EXPECT_NEAR(gps.cn0_bias_dbhz, 50.0 / 45.0, 1e-9);
  EXPECT_NEAR(gps.cn0_mean_abs_difference_dbhz, 70.0 / 45.0, 1e-9);
  const auto& gal = row(*report, "E1C");
  EXPECT_DOUBLE_EQ(gal.real_in_sim_fraction(), 1.0);
  EXPECT_DOUBLE_EQ(gal.sim_in_real_fraction(), 1.0);
  EXPECT_NEAR(gal.cn0_mean_abs_difference_dbhz, 0.0, 1e-9);
}

TEST_F(Compare, FileAgainstItselfIsZero) {
  auto report = compare_observation_files(real_, real_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  for (const auto& s : report->signals) {
    EXPECT_GT(s.pseudorange_m.count, 0u) << s.signal.to_string();
    EXPECT_EQ(s.pseudorange_m.rms, 0.0) << s.signal.to_string();
    EXPECT_EQ(s.doppler_mps.rms, 0.0) << s.signal.to_string();
    EXPECT_EQ(s.phase_difference_m.rms, 0.0) << s.signal.to_string();
    EXPECT_EQ(s.cn0_mean_abs_difference_dbhz, 0.0) << s.signal.to_string();
    EXPECT_EQ(s.real_in_sim_fraction(), 1.0) << s.signal.to_string();
    EXPECT_EQ(s.sim_in_real_fraction(), 1.0) << s.signal.to_string();
  }
}

// Receivers write .000 for observables they do not produce (NetR9 D5X at NYA1): not a Doppler of 0.
TEST_F(Compare, ZeroValuesCountAsAbsent) {
  auto epochs = real_epochs();
  for (auto& epoch : epochs) {
    for (auto& sat : epoch.satellites) {
      if (sat.satellite.system == G::kGps) sat.values[2].value = 0.0;
    }
  }
  ASSERT_TRUE(write_rinex_obs(real_, header(true), epochs).ok());
  auto report = compare_observation_files(real_, sim_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(row(*report, "G1C").doppler_mps.count, 0u);
  EXPECT_EQ(row(*report, "G1C").pseudorange_m.count, 45u);
  EXPECT_EQ(row(*report, "E1C").doppler_mps.count, 40u);
}

TEST_F(Compare, SystemAndSignalSelection) {
  CompareOptions options;
  options.systems = *parse_system_letters("GE");
  auto report = compare_observation_files(real_, sim_, options);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->signals.size(), 2u);
  EXPECT_EQ(report->signals[1].signal.to_string(), "E1C");

  options.systems.clear();
  options.signals = *parse_signal_list("E1C, G1C");
  report = compare_observation_files(real_, sim_, options);
  ASSERT_TRUE(report.ok()) << report.error().message;
  ASSERT_EQ(report->signals.size(), 2u);
  EXPECT_EQ(report->signals[0].signal.to_string(), "G1C");

  options.signals = *parse_signal_list("G2W");
  report = compare_observation_files(real_, sim_, options);
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.error().code, ErrorCode::kNotFound);
  EXPECT_NE(report.error().message.find("G2W"), std::string::npos) << report.error().message;

  EXPECT_FALSE(parse_system_letters("GX").ok());
  EXPECT_FALSE(parse_signal_list("G9Z").ok());
  EXPECT_FALSE(parse_signal_list(" , ").ok());
}

// A satellite source with hand-placed satellites: G05 5 degrees above the horizon, G06 unknown,
// every other satellite 60 degrees up.
class FakeSky final : public orbits::SatelliteStateSource {
 public:
  [[nodiscard]] Result<orbits::SatelliteState> state(const SatelliteId& satellite,
                                                     const GnssTime&) const override {
    if (satellite == SatelliteId{G::kGps, 6})
      return make_error(ErrorCode::kNotFound, "no ephemeris for G06");
    const double elevation_rad =
        (satellite == SatelliteId{G::kGps, 5} ? 5.0 : 60.0) * constants::kPi / 180.0;
    const Geodetic station =
        ecef_to_geodetic(Eigen::Vector3d(kStationEcef_m[0], kStationEcef_m[1], kStationEcef_m[2]));
    orbits::SatelliteState s;
    s.position_m = enu_to_ecef(
        2.0e7 * Eigen::Vector3d(0.0, std::cos(elevation_rad), std::sin(elevation_rad)), station);
    return s;
  }
  [[nodiscard]] std::vector<SatelliteId> satellites() const override { return {}; }
  [[nodiscard]] std::string_view name() const override { return "fake"; }
};

TEST_F(Compare, ElevationMaskDropsLowAndUnknownSatellites) {
  const FakeSky sky;
  CompareOptions options;
  options.satellite_source = &sky;
  options.min_elevation_deg = 10.0;
  auto report = compare_observation_files(real_, sim_, options);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_TRUE(report->elevation_mask_applied);
  EXPECT_EQ(report->below_mask_satellite_epochs, 10u);        // G05 at the 10 common epochs
  EXPECT_EQ(report->without_position_satellite_epochs, 10u);  // G06
  EXPECT_EQ(report->without_position_by_system, (std::map<GnssSystem, size_t>{{G::kGps, 10u}}));
  const auto& gps = row(*report, "G1C");
  EXPECT_EQ(gps.real_tracked, 40u);
  EXPECT_EQ(gps.sim_tracked, 40u);
  EXPECT_EQ(gps.both_tracked, 40u);
  // G01-G04 only: residuals {0.75, -0.75, 2.75, -3.25} at every epoch.
  EXPECT_EQ(gps.pseudorange_m.count, 40u);
  EXPECT_NEAR(gps.pseudorange_m.mean, -0.125, 1e-6);

  options.min_elevation_deg = 4.0;
  report = compare_observation_files(real_, sim_, options);
  ASSERT_TRUE(report.ok());
  EXPECT_EQ(report->below_mask_satellite_epochs, 0u);
  EXPECT_EQ(row(*report, "G1C").real_tracked, 50u);

  // The mask needs the receiver position from the real file.
  auto real = read_rinex_obs(real_);
  auto sim = read_rinex_obs(sim_);
  ASSERT_TRUE(real.ok() && sim.ok());
  real->header.approx_position_ecef_m.reset();
  const auto no_position = compare_observations(*real, *sim, options);
  ASSERT_FALSE(no_position.ok());
  EXPECT_NE(no_position.error().message.find("APPROX POSITION XYZ"), std::string::npos);
}

TEST_F(Compare, EpochsMatchToOneMillisecond) {
  auto real = read_rinex_obs(real_);
  auto sim = read_rinex_obs(sim_);
  ASSERT_TRUE(real.ok() && sim.ok());
  for (auto& e : real->epochs) e.time += 0.0009;
  auto report = compare_observations(*real, *sim, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->common_epochs, 10u);
  for (auto& e : real->epochs) e.time += 0.0002;  // 1.1 ms apart now
  report = compare_observations(*real, *sim, {});
  ASSERT_FALSE(report.ok());
}

// A moving receiver: without APPROX POSITION XYZ the mask looks from its track, and epochs outside
// the track count as without position.
TEST_F(Compare, ElevationMaskFromAMovingReceiversTrack) {
  const FakeSky sky;
  auto real = read_rinex_obs(real_);
  auto sim = read_rinex_obs(sim_);
  ASSERT_TRUE(real.ok() && sim.ok());
  real->header.approx_position_ecef_m.reset();
  CompareOptions options;
  options.satellite_source = &sky;
  options.min_elevation_deg = 10.0;
  const Eigen::Vector3d station(kStationEcef_m[0], kStationEcef_m[1], kStationEcef_m[2]);
  options.receiver_position = [&](const GnssTime&) -> std::optional<Eigen::Vector3d> { return station; };
  auto report = compare_observations(*real, *sim, options);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_TRUE(report->mask_from_receiver_track);
  EXPECT_EQ(report->below_mask_satellite_epochs, 10u);
  EXPECT_EQ(row(*report, "G1C").real_tracked, 40u);
  options.receiver_position = [](const GnssTime&) -> std::optional<Eigen::Vector3d> { return std::nullopt; };
  report = compare_observations(*real, *sim, options);
  ASSERT_TRUE(report.ok());
  EXPECT_EQ(row(*report, "G1C").real_tracked, 0u);
  EXPECT_GT(report->without_position_satellite_epochs, 40u);
}

// Epochs a few ms apart match within a wider tolerance.
TEST_F(Compare, EpochToleranceMatchesUnsteeredClocks) {
  auto real = read_rinex_obs(real_);
  auto sim = read_rinex_obs(sim_);
  ASSERT_TRUE(real.ok() && sim.ok());
  for (auto& e : real->epochs) e.time += 0.004;
  CompareOptions options;
  EXPECT_FALSE(compare_observations(*real, *sim, options).ok());
  options.epoch_tolerance_s = 0.01;
  auto report = compare_observations(*real, *sim, options);
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->common_epochs, 10u);
  options.epoch_tolerance_s = 1.0;
  EXPECT_FALSE(compare_observations(*real, *sim, options).ok());
}

TEST_F(Compare, ClearErrors) {
  // No common epochs: both spans named.
  const auto later = dir_ / "later.rnx";
  ASSERT_TRUE(write_rinex_obs(later, header(true), real_epochs(86400.0)).ok());
  auto report = compare_observation_files(real_, later, {});
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.error().code, ErrorCode::kOutOfRange);
  EXPECT_NE(report.error().message.find("REAL covers 2020-06-25T00:00:00 to 2020-06-25T00:04:30"),
            std::string::npos)
      << report.error().message;
  EXPECT_NE(report.error().message.find("SIM covers 2020-06-26T00:00:00"), std::string::npos)
      << report.error().message;

  // No common signals.
  auto galileo_only = header(false);
  galileo_only.observation_types.erase(G::kGps);
  galileo_only.observation_types.erase(G::kGlonass);
  std::vector<ObservationEpoch> epochs = real_epochs();
  for (auto& e : epochs)
    std::erase_if(e.satellites, [](const auto& s) { return s.satellite.system != G::kGalileo; });
  const auto galileo = dir_ / "galileo.rnx";
  ASSERT_TRUE(write_rinex_obs(galileo, galileo_only, epochs).ok());
  CompareOptions gps_only;
  gps_only.systems = {G::kGps};
  report = compare_observation_files(real_, galileo, gps_only);
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.error().code, ErrorCode::kNotFound);
  EXPECT_NE(report.error().message.find("no common signals"), std::string::npos)
      << report.error().message;

  // Unreadable file: the message says which one.
  report = compare_observation_files(real_, dir_ / "missing.rnx", {});
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.error().message.rfind("SIM", 0), 0u) << report.error().message;
}

TEST_F(Compare, TableAndJsonCarryTheSameNumbers) {
  auto report = compare_observation_files(real_, sim_, {});
  ASSERT_TRUE(report.ok()) << report.error().message;
  const std::string table = format_comparison_table(*report);
  EXPECT_NE(table.find("elevation mask: none"), std::string::npos) << table;
  EXPECT_NE(table.find("pr_p68_m"), std::string::npos) << table;
  std::istringstream lines(table);
  std::string line;
  std::map<std::string, std::string> rows;
  std::string header_line;
  while (std::getline(lines, line)) {
    if (line.rfind("signal", 0) == 0) header_line = line;
    if (line.rfind("G1C", 0) == 0 || line.rfind("E1C", 0) == 0 || line.rfind("R1C", 0) == 0)
      rows[line.substr(0, 3)] = line;
  }
  ASSERT_EQ(rows.size(), 3u) << table;
  // Aligned: every row as long as the header.
  for (const auto& [name, text] : rows) EXPECT_EQ(text.size(), header_line.size()) << text;
  std::istringstream g1c(rows["G1C"]);
  std::string name, count, p68;
  g1c >> name >> count >> p68;
  EXPECT_EQ(count, "45");
  EXPECT_EQ(p68, "3.210");

  const auto j = nlohmann::json::parse(comparison_to_json(*report));
  EXPECT_EQ(j["common_epochs"], 10);
  EXPECT_FALSE(j["elevation_mask"]["applied"].get<bool>());
  ASSERT_EQ(j["signals"].size(), 3u);
  EXPECT_EQ(j["signals"][0]["signal"], "G1C");
  EXPECT_NEAR(j["signals"][0]["pseudorange_m"]["abs_p68"].get<double>(), 3.21, 1e-6);
  EXPECT_EQ(j["signals"][0]["overlap"]["both_tracked"], 45);
  EXPECT_NEAR(j["signals"][0]["overlap"]["real_in_sim"].get<double>(), 0.9, 1e-12);
  // Per satellite, with the catalogue's block at the first common epoch (G01: SVN 63, Block IIF).
  const auto& g01 = j["signals"][0]["pseudorange_by_satellite_m"]["G01"];
  EXPECT_EQ(g01["count"], 10);
  EXPECT_NEAR(g01["mean"].get<double>(), 1.125, 1e-6);
  EXPECT_EQ(g01["block"], "GPS-IIF");
}

}  // namespace
}  // namespace skytrace::io
