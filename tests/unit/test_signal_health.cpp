// Per-signal health of broadcast records against the ICD bit layouts (orbits/signal_health.hpp),
// and ephemeris selection by the signals a receiver wants.
#include <gtest/gtest.h>

#include <vector>

#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/signal_health.hpp"

namespace skytrace::orbits {
namespace {

Signal sig(std::string_view text) { return Signal::parse(text).value(); }

KeplerEphemeris kepler(std::string_view satellite, NavMessage message, int health) {
  KeplerEphemeris e;
  e.satellite = SatelliteId::parse(satellite).value();
  e.message = message;
  e.health = health;
  return e;
}

bool healthy(const KeplerEphemeris& e, std::string_view signal) { return signal_healthy(e, sig(signal)); }

TEST(SignalHealth, GpsLnavSummaryBitAndSignalCodes) {
  // IS-GPS-200 20.3.3.3.1.4: MSB = NAV data summary, 5 LSBs = Table 20-VIII.
  EXPECT_EQ(decode_gps_lnav_health(0x37).signal_code, 23);
  EXPECT_TRUE(decode_gps_lnav_health(0x37).nav_data_bad);
  for (const char* s : {"G1C", "G1W", "G2W", "G2L", "G5Q", "G1L"}) {
    EXPECT_TRUE(healthy(kepler("G01", NavMessage::kGpsLnav, 0), s)) << s;
    EXPECT_FALSE(healthy(kepler("G01", NavMessage::kGpsLnav, 0x20), s)) << s;  // NAV data bad
    EXPECT_FALSE(healthy(kepler("G01", NavMessage::kGpsLnav, 63), s)) << s;    // the usual "unhealthy"
    EXPECT_FALSE(healthy(kepler("G01", NavMessage::kGpsLnav, 2), s)) << s;     // all signals dead
    EXPECT_FALSE(healthy(kepler("G01", NavMessage::kGpsLnav, 28), s)) << s;    // temporarily out
    EXPECT_TRUE(healthy(kepler("G01", NavMessage::kGpsLnav, 1), s)) << s;      // all weak: still ranging
    EXPECT_TRUE(healthy(kepler("G01", NavMessage::kGpsLnav, 3), s)) << s;      // no data modulation
  }
  const auto l1_dead = kepler("G01", NavMessage::kGpsLnav, 23);
  EXPECT_FALSE(healthy(l1_dead, "G1C"));
  EXPECT_FALSE(healthy(l1_dead, "G1W"));
  EXPECT_FALSE(healthy(l1_dead, "G1L"));
  EXPECT_TRUE(healthy(l1_dead, "G2W"));
  EXPECT_TRUE(healthy(l1_dead, "G5Q"));
  const auto l1_ca_dead = kepler("G01", NavMessage::kGpsLnav, 11);
  EXPECT_FALSE(healthy(l1_ca_dead, "G1C"));
  EXPECT_TRUE(healthy(l1_ca_dead, "G1W"));
  const auto l2c_dead = kepler("G01", NavMessage::kGpsLnav, 14);
  EXPECT_FALSE(healthy(l2c_dead, "G2L"));
  EXPECT_FALSE(healthy(l2c_dead, "G2X"));
  EXPECT_TRUE(healthy(l2c_dead, "G2W"));
  EXPECT_TRUE(healthy(l2c_dead, "G1C"));
  const auto l2p_dead = kepler("G01", NavMessage::kGpsLnav, 8);
  EXPECT_FALSE(healthy(l2p_dead, "G2W"));
  EXPECT_TRUE(healthy(l2p_dead, "G2L"));
  const auto l1_l2_p_dead = kepler("G01", NavMessage::kGpsLnav, 17);
  EXPECT_FALSE(healthy(l1_l2_p_dead, "G1W"));
  EXPECT_FALSE(healthy(l1_l2_p_dead, "G2W"));
  EXPECT_TRUE(healthy(l1_l2_p_dead, "G1C"));
  const auto l2_dead = kepler("G01", NavMessage::kGpsLnav, 26);
  EXPECT_FALSE(healthy(l2_dead, "G2L"));
  EXPECT_FALSE(healthy(l2_dead, "G2W"));
  EXPECT_TRUE(healthy(l2_dead, "G1C"));
  EXPECT_TRUE(healthy(l2_dead, "G5X"));
}

TEST(SignalHealth, QzssLnavOneBitPerSignal) {
  // IS-QZSS-PNT: bit 5 L1 (transmitted C/A or C/B), 4 L1C/A, 3 L2C, 2 L5, 1 L1C, 0 L1C/B.
  const auto l1cb_off = kepler("J01", NavMessage::kQzssLnav, 1);  // what QZS-1/2/3/4 broadcast
  for (const char* s : {"J1C", "J2L", "J2X", "J5Q", "J5I", "J1L", "J1X", "J6L"}) EXPECT_TRUE(healthy(l1cb_off, s)) << s;
  EXPECT_FALSE(healthy(l1cb_off, "J1E"));
  const auto l1ca = kepler("J01", NavMessage::kQzssLnav, 0x10);
  EXPECT_FALSE(healthy(l1ca, "J1C"));
  EXPECT_TRUE(healthy(l1ca, "J2L"));
  const auto l1 = kepler("J01", NavMessage::kQzssLnav, 0x20);
  EXPECT_FALSE(healthy(l1, "J1C"));
  EXPECT_FALSE(healthy(l1, "J1E"));
  EXPECT_TRUE(healthy(l1, "J1L"));  // L1C has its own bit
  EXPECT_FALSE(healthy(kepler("J01", NavMessage::kQzssLnav, 0x08), "J2L"));
  EXPECT_TRUE(healthy(kepler("J01", NavMessage::kQzssLnav, 0x08), "J5Q"));
  EXPECT_FALSE(healthy(kepler("J01", NavMessage::kQzssLnav, 0x04), "J5Q"));
  EXPECT_FALSE(healthy(kepler("J01", NavMessage::kQzssLnav, 0x02), "J1L"));
  EXPECT_TRUE(healthy(kepler("J01", NavMessage::kQzssLnav, 0x3F), "J6L"));  // L6 is not in the word
  // The record serves orbit and clock when a wanted signal is healthy.
  const std::vector<Signal> l1ca_only{sig("J1C")};
  const std::vector<Signal> l1ca_and_l5{sig("J1C"), sig("J5Q")};
  EXPECT_TRUE(record_usable(l1cb_off, l1ca_only));
  EXPECT_FALSE(record_usable(l1ca, l1ca_only));
  EXPECT_TRUE(record_usable(l1ca, l1ca_and_l5));
  EXPECT_TRUE(record_usable(l1ca));  // no signal in mind: any of the system
}

TEST(SignalHealth, CnavCarrierBits) {
  // RINEX 4 CNAV/CNAV-2: bit 0 L1, bit 1 L2, bit 2 L5.
  for (NavMessage m : {NavMessage::kGpsCnav, NavMessage::kGpsCnav2}) {
    EXPECT_FALSE(healthy(kepler("G01", m, 1), "G1L"));
    EXPECT_TRUE(healthy(kepler("G01", m, 1), "G2L"));
    EXPECT_FALSE(healthy(kepler("G01", m, 2), "G2L"));
    EXPECT_TRUE(healthy(kepler("G01", m, 2), "G5Q"));
    EXPECT_FALSE(healthy(kepler("G01", m, 4), "G5Q"));
    EXPECT_TRUE(healthy(kepler("G01", m, 4), "G1C"));
  }
  EXPECT_FALSE(healthy(kepler("J01", NavMessage::kQzssCnav, 4), "J5Q"));
  EXPECT_TRUE(healthy(kepler("J01", NavMessage::kQzssCnav, 4), "J2L"));
}

TEST(SignalHealth, GalileoHealthAndDataValidityPerComponent) {
  // bit 0 E1-B DVS, bits 1-2 E1-B HS, bit 3 E5a DVS, bits 4-5 E5a HS, bit 6 E5b DVS, bits 7-8 E5b HS.
  const auto e1_dvs = kepler("E11", NavMessage::kGalileoInav, 1 << 0);
  EXPECT_FALSE(healthy(e1_dvs, "E1C"));
  EXPECT_TRUE(healthy(e1_dvs, "E7Q"));
  const auto e1_hs = kepler("E11", NavMessage::kGalileoInav, 1 << 1);
  EXPECT_FALSE(healthy(e1_hs, "E1B"));
  const auto e5a_test = kepler("E11", NavMessage::kGalileoFnav, 3 << 4);
  EXPECT_FALSE(healthy(e5a_test, "E5Q"));
  EXPECT_FALSE(healthy(e5a_test, "E8Q"));  // AltBOC needs both sidebands
  const auto e5a_in_inav = kepler("E11", NavMessage::kGalileoInav, (3 << 4) | (1 << 6));  // E5b DVS
  EXPECT_TRUE(healthy(e5a_in_inav, "E1C"));
  EXPECT_FALSE(healthy(e5a_in_inav, "E7Q"));
  EXPECT_FALSE(healthy(e5a_in_inav, "E8Q"));
  EXPECT_FALSE(healthy(kepler("E11", NavMessage::kGalileoFnav, 1 << 3), "E5I"));
  // I/NAV does not carry E5a, but a set E5a bit (filled from F/NAV) still counts.
  EXPECT_FALSE(healthy(kepler("E11", NavMessage::kGalileoInav, 3 << 4), "E5Q"));
  EXPECT_TRUE(healthy(kepler("E11", NavMessage::kGalileoInav, 3 << 4), "E1C"));
  const auto e5b = kepler("E11", NavMessage::kGalileoInav, (1 << 6) | (2 << 7));
  EXPECT_FALSE(healthy(e5b, "E7I"));
  EXPECT_TRUE(healthy(e5b, "E1B"));
  EXPECT_FALSE(healthy(kepler("E11", NavMessage::kGalileoInav, 0x1FF), "E6C"));  // E6: judged by E1-B, E5b
  EXPECT_TRUE(healthy(kepler("E11", NavMessage::kGalileoInav, 0), "E6C"));
  // What ESBC's file has for E14 and E18: I/NAV 390 (E1-B and E5b HS 3), F/NAV 48 (E5a HS 3). An
  // F/NAV record does not carry E1-B: its E1 is judged by its E5a, an I/NAV record's E5a by E1-B/E5b.
  EXPECT_FALSE(healthy(kepler("E14", NavMessage::kGalileoInav, 390), "E1C"));
  EXPECT_FALSE(healthy(kepler("E14", NavMessage::kGalileoInav, 390), "E5Q"));
  EXPECT_FALSE(healthy(kepler("E14", NavMessage::kGalileoFnav, 48), "E1C"));
  EXPECT_FALSE(healthy(kepler("E14", NavMessage::kGalileoFnav, 48), "E7Q"));
  EXPECT_TRUE(healthy(kepler("E11", NavMessage::kGalileoFnav, 0), "E1C"));
  EXPECT_TRUE(healthy(kepler("E11", NavMessage::kGalileoInav, 48), "E1C"));  // bits I/NAV does not carry
}

TEST(SignalHealth, BeiDouNavicGlonassSbas) {
  EXPECT_FALSE(healthy(kepler("C07", NavMessage::kBeiDouD1, 1), "C2I"));
  EXPECT_FALSE(healthy(kepler("C07", NavMessage::kBeiDouD1, 1), "C6I"));
  EXPECT_TRUE(healthy(kepler("C07", NavMessage::kBeiDouD1, 0), "C2I"));
  EXPECT_FALSE(healthy(kepler("C30", NavMessage::kBeiDouCnav1, 1), "C1P"));
  EXPECT_FALSE(healthy(kepler("I05", NavMessage::kNavicLnav, 1), "I5A"));

  GlonassEphemeris g;
  g.satellite = SatelliteId::parse("R07").value();
  EXPECT_TRUE(signal_healthy(g, sig("R1C")));
  g.health = 1;  // B_n
  EXPECT_FALSE(signal_healthy(g, sig("R1C")));
  g.health = 0;
  g.health_flags = 3;  // almanac health and its availability: not the ephemeris
  EXPECT_TRUE(signal_healthy(g, sig("R2C")));
  g.health_flags = 4;  // l_n
  EXPECT_FALSE(signal_healthy(g, sig("R2C")));

  SbasEphemeris s;
  s.satellite = SatelliteId::parse("S23").value();
  s.health = 0x01;  // MT17: ranging off
  EXPECT_FALSE(signal_healthy(s, sig("S1C")));
  s.health = 0x11;  // MT17 health unavailable: bits 0-3 say nothing
  EXPECT_TRUE(signal_healthy(s, sig("S1C")));
}

TEST(SignalHealth, SelectionTakesTheRecordHealthyForTheWantedSignals) {
  NavigationData data;
  KeplerEphemeris e = kepler("G01", NavMessage::kGpsLnav, 23);  // L1 signals dead
  e.toc = e.toe = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  e.sqrt_a_sqrtm = 5153.7;
  data.kepler.push_back(e);
  const BroadcastEphemerides ephemerides(std::move(data));
  const SatelliteId g01 = SatelliteId::parse("G01").value();
  const GnssTime t = e.toe + 60.0;
  const std::vector<Signal> l1{sig("G1C")};
  const std::vector<Signal> l1_l5{sig("G1C"), sig("G5Q")};
  EXPECT_EQ(ephemerides.find_kepler(g01, t, std::nullopt, l1), nullptr);
  EXPECT_NE(ephemerides.find_kepler(g01, t, std::nullopt, l1_l5), nullptr);
  EXPECT_NE(ephemerides.find_kepler(g01, t), nullptr);  // some signal is usable
  EXPECT_FALSE(ephemerides.state_for_signal(g01, sig("G1C"), t).ok());
  EXPECT_TRUE(ephemerides.state_for_signal(g01, sig("G5Q"), t).ok());
  EXPECT_FALSE(ephemerides.has_usable_record(g01, t, l1));
  EXPECT_NE(health_description(e).find("L1 signals dead"), std::string::npos) << health_description(e);
}

}  // namespace
}  // namespace skytrace::orbits
