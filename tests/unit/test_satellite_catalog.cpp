// Satellite catalogue: PRN assignments by date and the signals each block broadcasts. The expected
// values are published facts (launch/commissioning dates, block signal plans), not table echoes.
#include <gtest/gtest.h>

#include "skytrace/core/satellite_catalog.hpp"

namespace skytrace {
namespace {

GnssTime gpst_day(int year, int month, int day, int hour = 12) {
  return GnssTime::from_calendar(CalendarTime{year, month, day, hour, 0, 0.0}, TimeScale::kGpst);
}

SatelliteId sat(const char* text) { return SatelliteId::parse(text).value(); }
Signal sig(const char* text) { return Signal::parse(text).value(); }

TEST(SatelliteCatalog, GpsBlocksIn2020) {
  const GnssTime t = gpst_day(2020, 6, 25);
  // G01 = SVN 63, Block IIF (launched 2011-07-16): L2C and L5, no L1C.
  const auto g01 = satellite_info(sat("G01"), t);
  ASSERT_TRUE(g01.has_value());
  EXPECT_EQ(g01->svn, 63);
  EXPECT_EQ(g01->block, "GPS-IIF");
  EXPECT_FALSE(g01->open_ended);  // SVN 63 left PRN 01 in 2024
  EXPECT_TRUE(transmits(sat("G01"), sig("G5Q"), t));
  EXPECT_TRUE(transmits(sat("G01"), sig("G2L"), t));
  EXPECT_FALSE(transmits(sat("G01"), sig("G1L"), t));
  // G05 = SVN 50, the last IIR-M (launched 2009-08-17): L2C and M code, no L5.
  const auto g05 = satellite_info(sat("G05"), t);
  ASSERT_TRUE(g05.has_value());
  EXPECT_EQ(g05->svn, 50);
  EXPECT_EQ(g05->block_id, SatelliteBlock::kGpsIIRM);
  EXPECT_TRUE(transmits(sat("G05"), sig("G2S"), t));
  EXPECT_TRUE(transmits(sat("G05"), sig("G2X"), t));
  EXPECT_TRUE(transmits(sat("G05"), sig("G1M"), t));
  EXPECT_FALSE(transmits(sat("G05"), sig("G5Q"), t));
  EXPECT_EQ(signal_availability(sat("G05"), sig("G5I"), t), SignalAvailability::kNo);
  // G13 = SVN 43, IIR-A (1997): legacy signals only.
  EXPECT_TRUE(transmits(sat("G13"), sig("G1C"), t));
  EXPECT_TRUE(transmits(sat("G13"), sig("G2W"), t));
  EXPECT_FALSE(transmits(sat("G13"), sig("G2L"), t));
  EXPECT_FALSE(transmits(sat("G13"), sig("G1M"), t));
  // L2 C/A is not broadcast in normal operations, whatever the block.
  EXPECT_FALSE(transmits(sat("G01"), sig("G2C"), t));
}

TEST(SatelliteCatalog, GpsIIIUnderPrn04) {
  // GPS III SV01 (SVN 74, launched 2018-12-23) first set as PRN 04 on 2019-01-09 (day 009);
  // before that PRN 04 was flown by the IIA SVN 36. (The often-quoted "G04 is GPS III from
  // 2018-11" is off: the satellite was still on its way to orbit.)
  const auto before = satellite_info(sat("G04"), gpst_day(2018, 11, 15));
  ASSERT_TRUE(before.has_value());
  EXPECT_EQ(before->svn, 36);
  EXPECT_EQ(before->block, "GPS-IIA");
  EXPECT_FALSE(transmits(sat("G04"), sig("G2L"), gpst_day(2018, 11, 15)));

  const GnssTime t = gpst_day(2020, 6, 25);
  const auto g04 = satellite_info(sat("G04"), t);
  ASSERT_TRUE(g04.has_value());
  EXPECT_EQ(g04->svn, 74);
  EXPECT_EQ(g04->block, "GPS-IIIA");
  EXPECT_TRUE(g04->open_ended);
  for (const char* code : {"G1C", "G1L", "G1S", "G1X", "G2L", "G5I", "G5Q", "G1M"}) {
    EXPECT_TRUE(transmits(sat("G04"), sig(code), t)) << code;
  }
}

TEST(SatelliteCatalog, PrnReassignmentG18) {
  // PRN 18: IIA SVN 34 until 2020 day 069, then GPS III SV02 (SVN 75) from day 073.
  const auto old_sat = satellite_info(sat("G18"), gpst_day(2020, 3, 9));  // day 069
  ASSERT_TRUE(old_sat.has_value());
  EXPECT_EQ(old_sat->svn, 34);
  EXPECT_FALSE(transmits(sat("G18"), sig("G5Q"), gpst_day(2020, 3, 9)));
  EXPECT_EQ(old_sat->valid_until, GnssTime::from_calendar(CalendarTime{2020, 3, 10, 0, 0, 0.0}, TimeScale::kGpst));

  // In the gap between the two assignments the table knows nothing: conservative default.
  EXPECT_FALSE(satellite_info(sat("G18"), gpst_day(2020, 3, 11)).has_value());
  EXPECT_TRUE(transmits(sat("G18"), sig("G1C"), gpst_day(2020, 3, 11)));
  EXPECT_EQ(signal_availability(sat("G18"), sig("G5Q"), gpst_day(2020, 3, 11)), SignalAvailability::kUncertain);

  const auto new_sat = satellite_info(sat("G18"), gpst_day(2020, 3, 14));  // day 074
  ASSERT_TRUE(new_sat.has_value());
  EXPECT_EQ(new_sat->svn, 75);
  EXPECT_TRUE(transmits(sat("G18"), sig("G5Q"), gpst_day(2020, 3, 14)));
  EXPECT_TRUE(transmits(sat("G18"), sig("G1L"), gpst_day(2020, 3, 14)));
}

TEST(SatelliteCatalog, BoundaryToTheSecond) {
  // BeiDou C01: BDS-2 GEO SVN C003 until 2020 day 091 13499 s, SVN C020 from 13500 s.
  const GnssTime day91 = GnssTime::from_calendar(CalendarTime{2020, 3, 31, 0, 0, 0.0}, TimeScale::kGpst);
  EXPECT_EQ(satellite_info(sat("C01"), day91 + 13499.0)->svn, 3);
  EXPECT_EQ(satellite_info(sat("C01"), day91 + 13500.0)->svn, 20);
}

TEST(SatelliteCatalog, SvnMovesBetweenPrns) {
  // SVN 49 (the IIR-M with the L5 demonstration payload) filled in for several PRNs.
  EXPECT_EQ(satellite_info(sat("G27"), gpst_day(2013, 1, 1))->svn, 49);
  EXPECT_EQ(satellite_info(sat("G30"), gpst_day(2013, 6, 1))->svn, 49);
  EXPECT_EQ(signal_availability(sat("G27"), sig("G5I"), gpst_day(2013, 1, 1)), SignalAvailability::kUncertain);
  // ... and in 2024 it flew as PRN 01 between SVN 63 and GPS III SV07 (SVN 80).
  EXPECT_EQ(satellite_info(sat("G01"), gpst_day(2024, 6, 1))->svn, 49);
  EXPECT_EQ(satellite_info(sat("G01"), gpst_day(2025, 3, 1))->svn, 80);
  EXPECT_EQ(satellite_info(sat("G01"), gpst_day(2025, 3, 1))->block_id, SatelliteBlock::kGpsIIIA);
}

TEST(SatelliteCatalog, GpsIIIReplacementsAfter2024) {
  // PRN 21: IIR-A SVN 45 still on 2024-11-25, GPS III SV08 by 2025-11-14; in between unknown.
  EXPECT_EQ(satellite_info(sat("G21"), gpst_day(2024, 11, 1))->svn, 45);
  EXPECT_FALSE(satellite_info(sat("G21"), gpst_day(2025, 6, 1)).has_value());
  EXPECT_EQ(satellite_info(sat("G21"), gpst_day(2026, 1, 1))->block_id, SatelliteBlock::kGpsIIIA);
  EXPECT_TRUE(transmits(sat("G21"), sig("G1L"), gpst_day(2026, 1, 1)));
  // PRN 13: IIR-A SVN 43 until at least 2026-04-06.
  EXPECT_EQ(satellite_info(sat("G13"), gpst_day(2026, 4, 1))->svn, 43);
  EXPECT_EQ(satellite_info(sat("G13"), gpst_day(2026, 8, 1))->block_id, SatelliteBlock::kGpsIIIA);
  EXPECT_TRUE(satellite_info(sat("G13"), gpst_day(2026, 8, 1))->open_ended);
}

TEST(SatelliteCatalog, BeiDouGenerations) {
  const GnssTime t = gpst_day(2021, 1, 1);
  // C02: BDS-2 GEO. B1I, B2I, B3I; no B1C, B2a, B2b.
  const auto c02 = satellite_info(sat("C02"), t);
  ASSERT_TRUE(c02.has_value());
  EXPECT_EQ(c02->block, "BDS-2G");
  EXPECT_TRUE(transmits(sat("C02"), sig("C2I"), t));
  EXPECT_TRUE(transmits(sat("C02"), sig("C7I"), t));
  EXPECT_TRUE(transmits(sat("C02"), sig("C6I"), t));
  for (const char* code : {"C1P", "C1D", "C1X", "C5P", "C5X", "C7D", "C8X"}) {
    EXPECT_FALSE(transmits(sat("C02"), sig(code), t)) << code;
  }
  // C19..C46: BDS-3 MEO (C38-C40 IGSO). B1I, B3I, B1C, B2a, B2b; no B2I. C31 is the exception:
  // it still carries the experimental BDS-3S IGSO SVN C101, whose new signals are test signals.
  EXPECT_EQ(satellite_info(sat("C31"), t)->block_id, SatelliteBlock::kBds3SIgso);
  EXPECT_EQ(signal_availability(sat("C31"), sig("C1P"), t), SignalAvailability::kUncertain);
  for (int prn = 19; prn <= 46; ++prn) {
    if (prn == 31) continue;
    const SatelliteId id{GnssSystem::kBeiDou, static_cast<std::uint8_t>(prn)};
    const auto info = satellite_info(id, t);
    ASSERT_TRUE(info.has_value()) << id.to_string();
    const bool igso = prn >= 38 && prn <= 40;
    EXPECT_EQ(info->block_id, igso ? SatelliteBlock::kBds3Igso : SatelliteBlock::kBds3Meo) << id.to_string();
    for (const char* code : {"C2I", "C6I", "C1P", "C1D", "C5P", "C5D", "C7D", "C7Z", "C8X"}) {
      EXPECT_TRUE(transmits(id, sig(code), t)) << id.to_string() << " " << code;
    }
    EXPECT_FALSE(transmits(id, sig("C7I"), t)) << id.to_string();
  }
  // C60: BDS-3 GEO. B1I, B3I, PPP-B2b; B1C and B2a are not broadcast by GEOs.
  EXPECT_EQ(satellite_info(sat("C60"), t)->block, "BDS-3G");
  EXPECT_TRUE(transmits(sat("C60"), sig("C2I"), t));
  EXPECT_TRUE(transmits(sat("C60"), sig("C7D"), t));
  EXPECT_FALSE(transmits(sat("C60"), sig("C1P"), t));
  EXPECT_FALSE(transmits(sat("C60"), sig("C5P"), t));
  EXPECT_FALSE(transmits(sat("C60"), sig("C7I"), t));
}

TEST(SatelliteCatalog, BeiDouDefaultsByPrnRange) {
  // A PRN the table does not know at that date falls back on its PRN range.
  const GnssTime t = gpst_day(2015, 1, 1);
  EXPECT_FALSE(satellite_info(sat("C45"), t).has_value());
  EXPECT_TRUE(transmits(sat("C45"), sig("C1P"), t));
  EXPECT_FALSE(transmits(sat("C45"), sig("C7I"), t));
  EXPECT_FALSE(satellite_info(sat("C63"), t).has_value());
  EXPECT_FALSE(transmits(sat("C63"), sig("C1P"), t));
  EXPECT_FALSE(satellite_info(sat("C15"), t).has_value());
  EXPECT_TRUE(transmits(sat("C15"), sig("C7I"), t));
  EXPECT_FALSE(transmits(sat("C15"), sig("C5P"), t));
}

TEST(SatelliteCatalog, GlonassCdmaOnlyOnNewerBlocks) {
  const GnssTime t = gpst_day(2020, 6, 25);
  // R09: GLONASS-K1 SVN 802 (launched 2014-11-30): L3 CDMA payload.
  EXPECT_EQ(satellite_info(sat("R09"), t)->block, "GLO-K1");
  EXPECT_NE(signal_availability(sat("R09"), sig("R3Q"), t), SignalAvailability::kNo);
  // R21: GLONASS-M serial 755, the first M with L3 (launched 2014-06-14).
  EXPECT_EQ(satellite_info(sat("R21"), t)->block, "GLO-M+");
  EXPECT_NE(signal_availability(sat("R21"), sig("R3Q"), t), SignalAvailability::kNo);
  // R01: plain GLONASS-M, FDMA only.
  EXPECT_EQ(satellite_info(sat("R01"), t)->block, "GLO-M");
  EXPECT_EQ(signal_availability(sat("R01"), sig("R3Q"), t), SignalAvailability::kNo);
  EXPECT_TRUE(transmits(sat("R01"), sig("R1C"), t));
  EXPECT_TRUE(transmits(sat("R01"), sig("R2C"), t));
  EXPECT_TRUE(transmits(sat("R01"), sig("R2P"), t));
  // L3OC is a yes where public recordings show it: R09 (K1 802) and R21 (M+ 855); R12 (M+ 858)
  // stays uncertain (on in 2020, off in 2022).
  EXPECT_TRUE(transmits(sat("R09"), sig("R3Q"), t));
  EXPECT_TRUE(transmits(sat("R21"), sig("R3Q"), t));
  EXPECT_EQ(signal_availability(sat("R12"), sig("R3Q"), t), SignalAvailability::kUncertain);
  EXPECT_FALSE(transmits(sat("R01"), sig("R3Q"), t));
  // R26 in 2024: the first GLONASS-K2 (SVN 803, launched 2023-08-07).
  EXPECT_EQ(satellite_info(sat("R26"), gpst_day(2024, 5, 3))->block_id, SatelliteBlock::kGlonassK2);
}

TEST(SatelliteCatalog, GalileoAndTheE20Anomaly) {
  const GnssTime t = gpst_day(2020, 6, 25);
  EXPECT_EQ(satellite_info(sat("E11"), t)->block, "GAL-1");
  EXPECT_EQ(satellite_info(sat("E24"), t)->block, "GAL-2");
  for (const char* code : {"E1C", "E5Q", "E7Q", "E8Q", "E6C"}) EXPECT_TRUE(transmits(sat("E24"), sig(code), t)) << code;
  // E20 (GSAT0104) lost E5 and E6 on 2014-05-27.
  EXPECT_TRUE(transmits(sat("E20"), sig("E5Q"), gpst_day(2013, 6, 1)));
  EXPECT_FALSE(transmits(sat("E20"), sig("E5Q"), t));
  EXPECT_FALSE(transmits(sat("E20"), sig("E6C"), t));
}

TEST(SatelliteCatalog, QzssPerSatellite) {
  // QZS-1 (J01) until QZS-1R (J04) took over on 2022-03-24.
  EXPECT_EQ(satellite_info(sat("J01"), gpst_day(2020, 6, 25))->block, "QZS-1");
  EXPECT_FALSE(satellite_info(sat("J01"), gpst_day(2022, 6, 8)).has_value());
  EXPECT_EQ(satellite_info(sat("J04"), gpst_day(2022, 6, 8))->block, "QZS-2A");
  EXPECT_EQ(satellite_info(sat("J07"), gpst_day(2022, 6, 8))->block, "QZS-2G");
  const GnssTime t = gpst_day(2020, 6, 25);
  EXPECT_TRUE(transmits(sat("J01"), sig("J1C"), t));
  EXPECT_TRUE(transmits(sat("J01"), sig("J2L"), t));
  EXPECT_TRUE(transmits(sat("J01"), sig("J5Q"), t));
  EXPECT_FALSE(transmits(sat("J01"), sig("J6E"), t));   // L6E came with the QZS-2 series
  EXPECT_EQ(signal_availability(sat("J01"), sig("J5P"), t), SignalAvailability::kNo);          // no L5S
  EXPECT_EQ(signal_availability(sat("J02"), sig("J5P"), t), SignalAvailability::kUncertain);   // L5S demo
  EXPECT_TRUE(transmits(sat("J02"), sig("J6E"), t));
  EXPECT_FALSE(transmits(sat("J02"), sig("J1E"), t));   // L1C/B only from QZS-5 on
}

TEST(SatelliteCatalog, NavicSbasAndForeignSignals) {
  const GnssTime t = gpst_day(2022, 6, 8);
  EXPECT_FALSE(satellite_info(sat("I03"), t).has_value());
  EXPECT_TRUE(transmits(sat("I03"), sig("I5A"), t));
  EXPECT_TRUE(transmits(sat("I03"), sig("I9A"), t));
  EXPECT_FALSE(transmits(sat("I03"), sig("I1D"), t));
  EXPECT_TRUE(transmits(sat("S23"), sig("S1C"), t));
  EXPECT_EQ(signal_availability(sat("S23"), sig("S5I"), t), SignalAvailability::kUncertain);
  EXPECT_EQ(satellite_info(sat("S23"), t)->block, "SBAS-GEO");
  // A signal of another system is never transmitted.
  EXPECT_EQ(signal_availability(sat("G01"), sig("E1C"), t), SignalAvailability::kNo);
}

TEST(SatelliteCatalog, ConstellationSnapshot) {
  // On 2020-06-25 PRN 23 was vacant: SVN 60 was decommissioned on day 161 and GPS III SV03
  // (SVN 76), launched on 2020-06-30, was set as PRN 23 on day 196. All other 31 PRNs flew.
  const auto gps = catalogued_satellites(GnssSystem::kGps, gpst_day(2020, 6, 25));
  EXPECT_EQ(gps.size(), 31U);
  for (const auto& info : gps) EXPECT_NE(info.id.number, 23) << "G23 should be vacant on 2020-06-25";
  const auto bds = catalogued_satellites(GnssSystem::kBeiDou, gpst_day(2020, 6, 25));
  EXPECT_GE(bds.size(), 44U);
  EXPECT_EQ(block_name(SatelliteBlock::kGpsIIRM), "GPS-IIR-M");
}

}  // namespace
}  // namespace skytrace
