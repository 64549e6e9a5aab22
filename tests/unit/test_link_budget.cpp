// Link budget against hand-computed numbers (GPS orbit radius 26,560 km, mean Earth radius 6,371 km).
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/receiver/link_budget.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kGpsOrbit_m = 26560e3;

TEST(LinkBudget, NoiseDensityOfRoomTemperature) {
  // k T at 290 K: -228.60 + 24.62 = -203.98 dBW/Hz (the textbook -204 dBW/Hz).
  EXPECT_NEAR(noise_density_dbw_per_hz(290.0), -203.975, 0.001);
  EXPECT_NEAR(noise_density_dbw_per_hz(2900.0) - noise_density_dbw_per_hz(290.0), 10.0, 1e-12);
}

TEST(LinkBudget, ReferenceGeometry) {
  // Zenith: the orbit height; 5 degrees: 25,235.28 km (sqrt(a^2 - R^2 cos^2 5) - R sin 5, by hand).
  EXPECT_NEAR(slant_range_m(kGpsOrbit_m, 90.0), 20189e3, 1e-3);
  EXPECT_NEAR(slant_range_m(kGpsOrbit_m, 5.0), 25235.28e3, 10.0);
  // Law of cosines at any elevation: a^2 = R^2 + r^2 + 2 R r sin(el).
  for (double el : {0.0, 12.0, 47.0}) {
    const double r = slant_range_m(kGpsOrbit_m, el);
    const double rr = kEarthRadiusMean_m;
    EXPECT_NEAR(kGpsOrbit_m * kGpsOrbit_m, rr * rr + r * r + 2.0 * rr * r * std::sin(el * M_PI / 180.0), 1e3);
  }
  // Off-boresight: 0 at zenith, the limb asin(R/a) = 13.879 deg at the horizon.
  EXPECT_NEAR(off_boresight_deg(kGpsOrbit_m, 90.0), 0.0, 1e-9);
  EXPECT_NEAR(off_boresight_deg(kGpsOrbit_m, 0.0), 13.879, 0.001);
}

TEST(LinkBudget, SatelliteAntennaRisesTowardsTheLimb) {
  EXPECT_NEAR(satellite_antenna_gain_db(0.0, kGpsOrbit_m), -kSatelliteLimbBoost_db, 1e-12);
  EXPECT_NEAR(satellite_antenna_gain_db(13.879, kGpsOrbit_m), 0.0, 1e-4);
  EXPECT_NEAR(satellite_antenna_gain_db(20.0, kGpsOrbit_m), 0.0, 1e-12);  // flat beyond the limb
  // Half-way to the limb: -2 (1 - 0.25) = -1.5 dB.
  EXPECT_NEAR(satellite_antenna_gain_db(13.878985 / 2.0, kGpsOrbit_m), -1.5, 1e-5);
}

TEST(LinkBudget, IcdMinimaOfTheTrackedComponent) {
  auto power = [](const char* code) { return signal_power_spec(Signal::parse(code).value()).value().minimum_dbw; };
  EXPECT_DOUBLE_EQ(power("G1C"), -158.5);  // IS-GPS-200
  EXPECT_DOUBLE_EQ(power("G2W"), -161.5);
  EXPECT_DOUBLE_EQ(power("G2L"), -163.0);  // half of L2C's -160
  EXPECT_DOUBLE_EQ(power("G5Q"), -157.9);  // IS-GPS-705
  EXPECT_DOUBLE_EQ(power("G1L"), -158.25); // 3/4 of L1C's -157 (IS-GPS-800)
  EXPECT_DOUBLE_EQ(power("E1C"), -160.0);  // half of E1's -157 (Galileo OS SIS ICD)
  EXPECT_DOUBLE_EQ(power("E5X"), -155.0);
  EXPECT_DOUBLE_EQ(power("R1C"), -161.0);  // GLONASS ICD 5.1
  EXPECT_DOUBLE_EQ(power("R2C"), -167.0);
  EXPECT_DOUBLE_EQ(power("C2I"), -163.0);  // BeiDou B1I ICD
  EXPECT_DOUBLE_EQ(power("C5X"), -156.0);  // B2a ICD, MEO
  EXPECT_DOUBLE_EQ(power("I5A"), -159.0);  // NavIC SPS ICD
  EXPECT_DOUBLE_EQ(power("S1C"), -161.0);  // DO-229
  EXPECT_DOUBLE_EQ(signal_power_spec(Signal::parse("E1C").value())->reference_elevation_deg, 10.0);
  EXPECT_DOUBLE_EQ(signal_power_spec(Signal::parse("G1C").value())->reference_elevation_deg, 5.0);
  EXPECT_FALSE(signal_power_spec(Signal::parse("E1A").value()));  // PRS: no public value
}

TEST(LinkBudget, ReceivedPowerIsTheMinimumPlusMarginAtTheReferenceGeometry) {
  const SignalPowerSpec spec = signal_power_spec(Signal::parse("G1C").value()).value();
  const double at_reference = received_power_dbw(spec, slant_range_m(kGpsOrbit_m, 5.0), kGpsOrbit_m,
                                                 off_boresight_deg(kGpsOrbit_m, 5.0));
  EXPECT_NEAR(at_reference, -158.5 + 3.0, 1e-9);
  // Zenith, by hand: -158.5 + 3 + 20 log10(25235.28 / 20189) (1.938) - 2 (nadir) + 0.0155 (the
  // reference angle 13.825 deg is just inside the limb) = -155.547 dBW.
  EXPECT_NEAR(received_power_dbw(spec, 20189e3, kGpsOrbit_m, 0.0), -155.547, 0.001);
}

TEST(LinkBudget, Cn0OfAProfile) {
  ReceiverProfile profile;
  profile.antenna.elevation_deg = {0.0, 90.0};
  profile.antenna.rhcp_gain_dbic = {{-4.5, 5.5}};
  profile.antenna.lhcp_gain_dbic = {{-20.0, -25.0}};
  profile.system_noise_temperature_k = 290.0;
  profile.implementation_loss_db = 1.5;
  const TrackedSignal g1c{Signal::parse("G1C").value(), 0.0};
  // Satellite straight overhead a receiver on the mean sphere.
  const Eigen::Vector3d receiver(kEarthRadiusMean_m, 0.0, 0.0);
  const Eigen::Vector3d satellite(kGpsOrbit_m, 0.0, 0.0);
  const LinkBudget b = link_budget(profile, g1c, satellite, receiver, 90.0, 0.0, 0.0);
  EXPECT_NEAR(b.received_power_dbw, -155.547, 0.001);
  EXPECT_DOUBLE_EQ(b.antenna_gain_dbic, 5.5);
  // -155.547 + 5.5 - 1.5 + 203.975 = 52.429 dB-Hz.
  EXPECT_NEAR(b.cn0_dbhz(), 52.429, 0.001);
  // Vegetation and a signal's extra loss come off one for one.
  const TrackedSignal lossy{g1c.signal, 7.0};
  EXPECT_NEAR(link_budget(profile, lossy, satellite, receiver, 90.0, 0.0, 3.0).cn0_dbhz(), 52.429 - 10.0, 0.001);
  // Half the antenna gain at 45 degrees (linear interpolation of the table).
  EXPECT_DOUBLE_EQ(link_budget(profile, g1c, satellite, receiver, 45.0, 0.0, 0.0).antenna_gain_dbic, 0.5);
}

// GPS L2C per block: the ICD's +1.5 dB of GPS III and the measured surplus of IIF and III over
// IIR-M; nothing for other signals or blocks. The offset adds to the received power one for one.
TEST(LinkBudget, GpsL2cPowerPerBlock) {
  const Signal l2l = Signal::parse("G2L").value();
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIRM, l2l), 0.0);
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIF, l2l), 2.9);
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIIA, l2l), 3.5);
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIIA, Signal::parse("G2S").value()), 3.5);
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIIA, Signal::parse("G2X").value()), 3.5);
  for (const char* other : {"G1C", "G1W", "G5Q", "J2L", "E5Q"}) {
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIF, Signal::parse(other).value()), 0.0) << other;
  }
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kUnknown, l2l), 0.0);

  ReceiverProfile profile;
  profile.antenna.elevation_deg = {0.0, 90.0};
  profile.antenna.rhcp_gain_dbic = {{0.0, 0.0}};
  profile.antenna.lhcp_gain_dbic = {{-20.0, -20.0}};
  const TrackedSignal tracked{l2l, 0.0};
  const Eigen::Vector3d receiver(kEarthRadiusMean_m, 0.0, 0.0);
  const Eigen::Vector3d satellite(kGpsOrbit_m, 0.0, 0.0);
  const double base = link_budget(profile, tracked, satellite, receiver, 90.0, 0.0, 0.0).cn0_dbhz();
  EXPECT_NEAR(link_budget(profile, tracked, satellite, receiver, 90.0, 0.0, 0.0, 2.9).cn0_dbhz(), base + 2.9, 1e-12);
}

// GPS L2 P(Y) per block (fitted on ESBC's G2W): IIR and III below the row's usual margin, the
// flex-power blocks IIR-M and IIF above it; every P(Y) code of band 2, not L1 P(Y) or L2C.
TEST(LinkBudget, GpsL2PyPowerPerBlock) {
  for (const char* code : {"G2W", "G2P", "G2Y", "G2D"}) {
    const Signal l2w = Signal::parse(code).value();
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIRA, l2w), -4.1) << code;
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIRB, l2w), -4.1) << code;
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIRM, l2w), 1.4) << code;
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIF, l2w), 3.4) << code;
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIIA, l2w), -2.8) << code;
    EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kUnknown, l2w), 0.0) << code;
  }
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIF, Signal::parse("G1W").value()), 0.0);
  EXPECT_DOUBLE_EQ(block_power_offset_db(SatelliteBlock::kGpsIIRM, Signal::parse("G2L").value()), 0.0);
}

}  // namespace
}  // namespace skytrace::receiver
