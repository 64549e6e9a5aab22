// Stages 3, 5 and 6 (signal power, measurement errors, observables) against independent numbers:
// C/N0 from the link budget at the ICD reference geometry, the ionosphere's 1/f^2 scaling and its
// opposite signs on code and phase, the Klobuchar night-time delay, Doppler signs, loop noise level.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/satellite_catalog.hpp"
#include "skytrace/receiver/stages/measurement_errors.hpp"
#include "skytrace/receiver/stages/observables.hpp"
#include "skytrace/receiver/stages/signal_power.hpp"

namespace skytrace::receiver::stages {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;

ReceiverProfile flat_profile() {
  ReceiverProfile p = builtin_profile("ideal").value();
  p.antenna = AntennaPattern{};
  p.antenna.elevation_deg = {-90.0, 90.0};
  p.antenna.rhcp_gain_dbic = {{0.0, 0.0}};
  p.antenna.lhcp_gain_dbic = {{-30.0, -30.0}};
  p.implementation_loss_db = 0.0;
  p.system_noise_temperature_k = 290.0;
  return p;
}

// A receiver on the mean-radius sphere and a GPS satellite seen at `elevation_deg` due north.
std::pair<Eigen::Vector3d, Eigen::Vector3d> geometry_at(double elevation_deg) {
  const double r = kEarthRadiusMean_m, a = 26560e3, e = elevation_deg * M_PI / 180.0;
  const double slant_m = -r * std::sin(e) + std::sqrt(a * a - r * r * std::cos(e) * std::cos(e));
  const Eigen::Vector3d receiver(r, 0.0, 0.0);  // up = x, north = z
  return {receiver + slant_m * Eigen::Vector3d(std::sin(e), 0.0, std::cos(e)), receiver};
}

TEST(StageSignalPower, Cn0AtTheIcdReferenceGeometry) {
  const ReceiverProfile profile = flat_profile();
  const TrackedSignal g1c{Signal::parse("G1C").value(), 0.0};
  const auto [satellite, receiver] = geometry_at(5.0);
  const AzimuthElevation direction{0.0, 5.0};
  SatelliteLink link(satellite, receiver);
  // IS-GPS-200 minimum -158.5 dBW plus the usual 3 dB; N0 = 10 log10(k 290 K) = -204.0 dBW/Hz.
  const double expected_dbhz = -158.5 + 3.0 - (-228.5991631 + 10.0 * std::log10(290.0));
  EXPECT_NEAR(signal_cn0_dbhz(profile, g1c, link, direction, 0.0, 0.0, 0.0), expected_dbhz, 0.01);
  // Vegetation, the block's offset and multipath enter dB for dB.
  EXPECT_NEAR(signal_cn0_dbhz(profile, g1c, link, direction, 6.0, 1.5, -2.0), expected_dbhz - 6.5, 0.01);
  // The shared terms give the free function's budget to the bit.
  EXPECT_EQ(link_budget(profile, g1c, link, 5.0, 0.0, 0.0).cn0_dbhz(),
            link_budget(profile, g1c, satellite, receiver, 5.0, 0.0, 0.0).cn0_dbhz());
  // Higher up the satellite is nearer: more power (free-space ratio less the satellite's limb boost).
  const auto [satellite_high, receiver_high] = geometry_at(90.0);
  SatelliteLink link_high(satellite_high, receiver_high);
  const double zenith_dbhz =
      signal_cn0_dbhz(profile, g1c, link_high, AzimuthElevation{0.0, 90.0}, 0.0, 0.0, 0.0);
  const double free_space_db = 20.0 * std::log10((satellite - receiver).norm() / (satellite_high - receiver_high).norm());
  EXPECT_GT(zenith_dbhz - expected_dbhz, free_space_db - kSatelliteLimbBoost_db - 0.3);
  EXPECT_LT(zenith_dbhz - expected_dbhz, free_space_db);
}

TEST(StageSignalPower, TransmittedSignalsFollowTheCatalogue) {
  SatelliteSignals cache;
  const GnssTime t = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  const Signal l5 = Signal::parse("G5Q").value();
  int with_l5 = 0, without_l5 = 0;
  for (int prn = 1; prn <= 32; ++prn) {
    const SatelliteId sat{GnssSystem::kGps, static_cast<std::uint8_t>(prn)};
    const bool expected = transmits(sat, l5, t);
    EXPECT_EQ(cache.facts(sat, l5, t).transmitted, expected);
    EXPECT_EQ(cache.facts(sat, l5, t + 3600.0).transmitted, expected);  // from the cache
    (expected ? with_l5 : without_l5)++;
  }
  EXPECT_GT(with_l5, 0);     // Block IIF and III
  EXPECT_GT(without_l5, 0);  // IIR and IIR-M
}

// GPS L5 from an LNAV record: T_GD scaled by (f1/f5)^2 for every block, and Block III's code later
// by its block term; a CNAV record's ISC describes the signal itself, so the term is not added.
TEST(StageMeasurementErrors, GpsL5CodeOfBlockIiiIsLateWhereLnavSaysNothing) {
  const Signal l5 = Signal::parse("G5Q").value();
  const Signal l1 = Signal::parse("G1C").value();
  EXPECT_DOUBLE_EQ(block_code_bias_m(SatelliteBlock::kGpsIIIA, l5), 4.1);
  EXPECT_DOUBLE_EQ(block_code_bias_m(SatelliteBlock::kGpsIIIA, Signal::parse("G5X").value()), 4.1);
  EXPECT_DOUBLE_EQ(block_code_bias_m(SatelliteBlock::kGpsIIF, l5), 0.0);
  EXPECT_DOUBLE_EQ(block_code_bias_m(SatelliteBlock::kGpsIIIA, l1), 0.0);
  EXPECT_DOUBLE_EQ(block_code_bias_m(SatelliteBlock::kGalileoFoc, Signal::parse("E5Q").value()), 0.0);

  orbits::KeplerEphemeris lnav;
  lnav.satellite = SatelliteId{GnssSystem::kGps, 18};
  lnav.message = orbits::NavMessage::kGpsLnav;
  lnav.group_delays.tgd_s = -4.0e-9;
  RecordState record;
  record.kepler = &lnav;
  const double gamma15 = std::pow(kFrequencyL1_Hz / kFrequencyL5_Hz, 2);
  EXPECT_NEAR(kC * signal_group_delay_s(record, record, l5, false), kC * gamma15 * -4.0e-9, 1e-9);
  EXPECT_NEAR(kC * signal_group_delay_s(record, record, l5, false, 4.1), kC * gamma15 * -4.0e-9 + 4.1, 1e-9);
  orbits::KeplerEphemeris cnav = lnav;
  cnav.message = orbits::NavMessage::kGpsCnav;
  cnav.group_delays.isc_l5q5_s = 1.0e-9;
  RecordState cnav_record;
  cnav_record.kepler = &cnav;
  EXPECT_NEAR(kC * signal_group_delay_s(cnav_record, cnav_record, l5, false, 4.1), kC * (-4.0e-9 - 1.0e-9), 1e-9);

  // The per-day facts carry the block's term: G18 was a GPS III satellite in 2020, G27 a IIF.
  SatelliteSignals cache;
  const GnssTime t = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  EXPECT_DOUBLE_EQ(cache.facts(SatelliteId{GnssSystem::kGps, 18}, l5, t).code_bias_m, 4.1);
  EXPECT_DOUBLE_EQ(cache.facts(SatelliteId{GnssSystem::kGps, 27}, l5, t).code_bias_m, 0.0);
  EXPECT_DOUBLE_EQ(cache.facts(SatelliteId{GnssSystem::kGps, 18}, l1, t).code_bias_m, 0.0);
}

TEST(StageMeasurementErrors, IonosphereScalesWithTheInverseSquareOfTheCarrier) {
  EXPECT_DOUBLE_EQ(ionosphere_code_delay_m(3.0, kFrequencyL1_Hz), 3.0);
  EXPECT_NEAR(ionosphere_code_delay_m(3.0, kFrequencyL5_Hz), 3.0 * 1.793270, 1e-5);
  EXPECT_NEAR(ionosphere_code_delay_m(3.0, kFrequencyL2_Hz), 3.0 * 1.646944, 1e-5);
}

TEST(StageMeasurementErrors, AtmosphereTerms) {
  const GnssTime t = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  const Geodetic site{55.49, 8.46, 0.0};
  // Klobuchar without amplitude: the night-time 5 ns times the obliquity factor 1 + 16 (0.53 - el/180)^3.
  const atmosphere::KlobucharIonosphere night(orbits::KlobucharCoefficients{});
  const auto zenith = atmosphere_terms(atmosphere::TroposphereModel::kSaastamoinen, &night, t, site,
                                       AzimuthElevation{0.0, 90.0});
  ASSERT_TRUE(zenith.ok());
  EXPECT_NEAR(zenith->ionosphere_l1_m, 5e-9 * kC * (1.0 + 16.0 * std::pow(0.53 - 0.5, 3)), 1e-3);
  // 0.002277 (P + (1255 / T + 0.05) e) at sea level: 2.31 m dry, 0.05 to 0.15 m wet.
  EXPECT_NEAR(zenith->troposphere_m, 2.4, 0.1);
  const auto low = atmosphere_terms(atmosphere::TroposphereModel::kSaastamoinen, nullptr, t, site,
                                    AzimuthElevation{0.0, 10.0});
  ASSERT_TRUE(low.ok());
  EXPECT_EQ(low->ionosphere_l1_m, 0.0);
  EXPECT_NEAR(low->troposphere_m / zenith->troposphere_m, 1.0 / std::sin(10.0 * M_PI / 180.0), 0.3);
  const auto none = atmosphere_terms(atmosphere::TroposphereModel::kNone, nullptr, t, site,
                                     AzimuthElevation{0.0, 10.0});
  EXPECT_EQ(none->troposphere_m, 0.0);
  // A wet residual field adds its mapped value at the receiver.
  const atmosphere::ResidualField wet(atmosphere::ResidualField::for_gradient_ppm(2.0, 50e3, 1800.0, 4));
  const auto with_residual = atmosphere_terms(atmosphere::TroposphereModel::kSaastamoinen, nullptr, t, site,
                                              AzimuthElevation{0.0, 90.0}, &wet);
  ASSERT_TRUE(with_residual.ok());
  EXPECT_NEAR(with_residual->troposphere_m - zenith->troposphere_m, wet.value_m(site.latitude_deg, site.longitude_deg, t),
              1e-3);
  EXPECT_NE(with_residual->troposphere_m, zenith->troposphere_m);
}

TEST(StageMeasurementErrors, MultipathOfTheDirectPathAloneIsZero) {
  const SignalInfo& info = *find_signal_info(Signal::parse("G1C").value());
  EXPECT_FALSE(signal_multipath_errors(info, 0, 1.0, {}).any_path);
  const MultipathErrors direct = signal_multipath_errors(info, 0, 1.0, {ReceivedPath{}});
  EXPECT_NEAR(direct.code_m, 0.0, 1e-9);
  EXPECT_NEAR(direct.phase_m, 0.0, 1e-9);
  EXPECT_NEAR(direct.power_db, 0.0, 1e-9);
  // A reflection 30 m late at half amplitude: the code error is positive and below its delay.
  const MultipathErrors reflected =
      signal_multipath_errors(info, 0, 1.0, {ReceivedPath{}, ReceivedPath{30.0, 0.0, {0.5, 0.0}}});
  EXPECT_GT(std::abs(reflected.code_m), 0.1);
  EXPECT_LT(std::abs(reflected.code_m), 30.0);
}

TEST(StageMeasurementErrors, LoopNoiseHasTheLoopsJitter) {
  const ReceiverProfile profile = builtin_profile("septentrio-polarx5").value();
  const Signal g1c = Signal::parse("G1C").value();
  const SignalInfo& info = *find_signal_info(g1c);
  const TrackingNoise sigma = tracking_noise(profile, info, kFrequencyL1_Hz, 40.0);
  LoopNoise noise(7, 0);
  const SatelliteId sat{GnssSystem::kGps, 5};
  GnssTime t = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  double code2 = 0.0, phase2 = 0.0;
  const int n = 4000;
  for (int i = 0; i < n; ++i, t += 1.0) {
    const LoopErrors e = noise.draw(sat, g1c, profile, info, kFrequencyL1_Hz, 40.0, std::nullopt, false, t);
    code2 += e.code_m * e.code_m;
    phase2 += e.phase_m * e.phase_m;
  }
  EXPECT_NEAR(std::sqrt(code2 / n) / sigma.code_m, 1.0, 0.05);
  EXPECT_NEAR(std::sqrt(phase2 / n) / sigma.phase_m, 1.0, 0.05);
  // An aided loop follows the aiding loop's phase error and reports its Doppler error exactly
  // (the C/A Doppler scaled to L2: the same range rate), even at a C/N0 where an FLL of its own
  // would be metres per second off.
  const Signal g2w = Signal::parse("G2W").value();
  const SignalInfo& w = *find_signal_info(g2w);
  const LoopErrors aided = noise.draw(sat, g2w, profile, w, kFrequencyL2_Hz, 40.0, AidingLoop{0.25, 0.031}, false, t);
  EXPECT_NEAR(aided.phase_m, 0.25, 0.01);
  EXPECT_DOUBLE_EQ(aided.doppler_mps, 0.031);
  const LoopErrors weak = noise.draw(sat, g2w, profile, w, kFrequencyL2_Hz, 8.0, AidingLoop{0.0, -0.02}, true, t + 1.0);
  EXPECT_DOUBLE_EQ(weak.doppler_mps, -0.02);
  // Without phase aiding in the profile (a loop of its own), the Doppler still is the C/A loop's.
  ReceiverProfile unaided = profile;
  unaided.semicodeless_aiding_bandwidth_hz = 0.0;
  const LoopErrors own = noise.draw(sat, g2w, unaided, w, kFrequencyL2_Hz, 40.0, AidingLoop{0.25, 0.031}, true, t + 2.0);
  EXPECT_DOUBLE_EQ(own.doppler_mps, 0.031);
  EXPECT_GT(std::abs(own.phase_m - 0.25), 1e-6);
}

SignalMeasurement measurement(double carrier_hz) {
  SignalMeasurement m;
  m.carrier_hz = carrier_hz;
  return m;
}

TEST(StageObservables, IonosphereDelaysCodeAndAdvancesPhase) {
  SatelliteTerms terms;
  terms.range_m = 22e6;
  SignalMeasurement m = measurement(kFrequencyL1_Hz);
  m.ionosphere_code_m = 4.0;
  m.ambiguity_cycles = 12345;
  form_observables(terms, m);
  const double wavelength_m = kC / kFrequencyL1_Hz;
  EXPECT_NEAR(m.pseudorange_m - terms.range_m, 4.0, 1e-6);
  EXPECT_NEAR((m.carrier_phase_cycles - 12345.0) * wavelength_m - terms.range_m, -4.0, 1e-6);
}

TEST(StageObservables, ClocksGroupDelayAndTroposphere) {
  SatelliteTerms terms;
  terms.range_m = 21e6;
  terms.receiver_clock_m = 300.0;
  terms.relativistic_m = 5.0;
  terms.troposphere_m = 2.5;
  SignalMeasurement m = measurement(kFrequencyL5_Hz);
  m.satellite_clock_m = 1000.0;
  m.group_delay_m = 3.0;
  form_observables(terms, m);
  const double wavelength_m = kC / kFrequencyL5_Hz;
  // P = rho + c dt_r - (c dt_k + c dt_rel - c TGD) + T; L without the group delay.
  EXPECT_NEAR(m.pseudorange_m, 21e6 + 300.0 - (1000.0 + 5.0 - 3.0) + 2.5, 1e-6);
  EXPECT_NEAR(m.carrier_phase_cycles * wavelength_m, 21e6 + 300.0 - 1000.0 - 5.0 + 2.5, 1e-6);
}

TEST(StageObservables, DopplerIsPositiveForAnApproachingSatellite) {
  SatelliteTerms terms;
  terms.range_m = 20e6;
  terms.range_rate_mps = -500.0;
  SignalMeasurement m = measurement(kFrequencyL1_Hz);
  form_observables(terms, m);
  EXPECT_NEAR(m.doppler_hz, 500.0 / (kC / kFrequencyL1_Hz), 1e-9);
  EXPECT_GT(m.doppler_hz, 2600.0);
  // A receiver clock running fast (drift > 0) lowers the Doppler as a receding satellite would.
  terms.receiver_clock_rate_mps = 100.0;
  form_observables(terms, m);
  EXPECT_NEAR(m.doppler_hz, 400.0 / (kC / kFrequencyL1_Hz), 1e-9);
}

TEST(StageObservables, Cn0Quantisation) {
  EXPECT_DOUBLE_EQ(quantize(47.3, 0.25), 47.25);
  EXPECT_DOUBLE_EQ(quantize(47.3, 0.0), 47.3);
}

}  // namespace
}  // namespace skytrace::receiver::stages
