// Every real navigation file under shared/data/real parses, with record counts per system and
// message checked against counts made independently on the text, e.g.
//   awk '/END OF HEADER/{h=1;next} h && /^[A-Z]/{c[substr($0,1,1)]++} END{for(k in c) print k,c[k]}' FILE
// (BeiDou D1/D2 split by PRN, Galileo I/NAV/F/NAV by the data-source field of line 6, RINEX 4 by
// the '> EPH' lines), and a few decoded records compared with the numbers written in the file.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

using Counts = std::map<std::string, int>;

Counts count_records(const NavigationData& nav) {
  Counts counts;
  for (const auto& e : nav.kepler) {
    ++counts[std::string(1, system_letter(e.satellite.system)) + ":" + std::string(to_string(e.message))];
  }
  if (!nav.glonass.empty()) counts["R:FDMA"] = static_cast<int>(nav.glonass.size());
  if (!nav.sbas.empty()) counts["S:SBAS"] = static_cast<int>(nav.sbas.size());
  return counts;
}

GnssTime gpst(int y, int mo, int d, int h, int mi, double s) {
  return GnssTime::from_calendar(CalendarTime{y, mo, d, h, mi, s}, TimeScale::kGpst);
}

// Properties every real file must show whatever its version:
// - toe within 2 h of toc (a wrong week or time scale moves it by weeks or by 14/18 s... or more);
//   the largest measured gap is 5400 s, in one 2016 Galileo record of the BRDC file;
// - GLONASS t_b on a quarter hour of UTC (an epoch read as GPST would show 18 s or 17 s);
// - SBAS GEO positions about 42164 km from the geocentre (metres, not kilometres);
// - a source "file:line" on every record.
void check_invariants(const NavigationData& nav) {
  for (const auto& e : nav.kepler) {
    EXPECT_LE(std::fabs(e.toe - e.toc), 7200.0) << e.source;
    EXPECT_FALSE(e.source.empty());
  }
  for (const auto& g : nav.glonass) {
    const CalendarTime utc = g.toe.to_calendar(TimeScale::kUtc);
    EXPECT_EQ(utc.minute % 15, 0) << g.source;
    EXPECT_DOUBLE_EQ(utc.second, 0.0) << g.source;
    EXPECT_GT(g.position_m.norm(), 25.0e6) << g.source;  // GLONASS orbit radius 25 510 km
    EXPECT_LT(g.position_m.norm(), 26.0e6) << g.source;
    EXPECT_FALSE(g.source.empty());
  }
  for (const auto& s : nav.sbas) {
    EXPECT_NEAR(s.position_m.norm(), 42.164e6, 0.2e6) << s.source;
    EXPECT_FALSE(s.source.empty());
  }
}

NavigationData read_ok(const std::filesystem::path& path) {
  auto nav = read_rinex_nav(path);
  if (!nav) {
    ADD_FAILURE() << nav.error().message;
    return {};
  }
  EXPECT_EQ(nav->source_files.size(), 1u);
  check_invariants(*nav);
  return std::move(*nav);
}

const KeplerEphemeris* find_source(const NavigationData& nav, const std::string& source) {
  for (const auto& e : nav.kepler) {
    if (e.source == source) return &e;
  }
  return nullptr;
}

TEST(RinexNavRealFiles, EsbcMixed305) {
  const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  const auto nav = read_ok(path);
  EXPECT_EQ(count_records(nav), (Counts{{"C:D1", 331}, {"C:D2", 26}, {"E:FNAV", 781}, {"E:INAV", 821},
                                        {"G:LNAV", 257}, {"J:LNAV", 15}, {"R:FDMA", 510}, {"S:SBAS", 2130}}));
  EXPECT_EQ(nav.leap_seconds, 18);
  ASSERT_TRUE(nav.ionosphere.gps);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[0], 4.6566e-09);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->beta[3], -5.2429e+05);
  ASSERT_TRUE(nav.ionosphere.galileo);
  EXPECT_DOUBLE_EQ(nav.ionosphere.galileo->ai0_sfu, 28.25);
  ASSERT_EQ(nav.time_corrections.size(), 3u);
  EXPECT_EQ(nav.time_corrections[0].type, "GAGP");
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a0_s, 2.3574102670e-09);
  EXPECT_EQ(nav.time_corrections[0].reference_time, gpst(2020, 6, 25, 0, 0, 0));  // 345600 s, week 2111

  // Line 15880: G01 2020 06 25 04 00 00.
  const auto* g01 = find_source(nav, "ESBC00DNK_R_20201770000_01D_MN.rnx:15880");
  ASSERT_NE(g01, nullptr);
  EXPECT_EQ(g01->satellite.to_string(), "G01");
  EXPECT_EQ(g01->toc, gpst(2020, 6, 25, 4, 0, 0));
  EXPECT_EQ(g01->toe, g01->toc);
  EXPECT_DOUBLE_EQ(g01->sqrt_a_sqrtm, 5.153707128525e+03);
  EXPECT_DOUBLE_EQ(g01->group_delays.tgd_s, 5.122274160385e-09);
  EXPECT_EQ(g01->iodc, 58);
  EXPECT_DOUBLE_EQ(g01->fit_interval_h, 4.0);

  // Line 208: C05 (GEO, D2) 2020 06 24 22 00 00 BDT, BDT week 755, toe 338400 s.
  const auto* c05 = find_source(nav, "ESBC00DNK_R_20201770000_01D_MN.rnx:208");
  ASSERT_NE(c05, nullptr);
  EXPECT_EQ(c05->message, NavMessage::kBeiDouD2);
  EXPECT_EQ(c05->toc, gpst(2020, 6, 24, 22, 0, 14));
  EXPECT_EQ(c05->toe, c05->toc);
  EXPECT_DOUBLE_EQ(c05->crs_m, -4.142968750000e+02);
  EXPECT_DOUBLE_EQ(c05->group_delays.tgd1_s, 1.0e-10);
  EXPECT_DOUBLE_EQ(c05->group_delays.tgd2_s, -9.3e-09);
  EXPECT_EQ(c05->iode, 1);
  EXPECT_EQ(c05->iodc, 0);

  // Line 3064: E01 2020 06 24 23 30 00, data sources 258 (F/NAV), toe 343800 s of week 2111.
  const auto* e01 = find_source(nav, "ESBC00DNK_R_20201770000_01D_MN.rnx:3064");
  ASSERT_NE(e01, nullptr);
  EXPECT_EQ(e01->message, NavMessage::kGalileoFnav);
  EXPECT_EQ(e01->toe, gpst(2020, 6, 24, 23, 30, 0));
  EXPECT_DOUBLE_EQ(e01->accuracy_m, 3.12);
  EXPECT_DOUBLE_EQ(e01->group_delays.bgd_e1e5a_s, -1.862645149231e-09);
  EXPECT_EQ(e01->iode, 61);

  // Line 18056: R01 2020 06 24 23 15 00 UTC, five lines, delta tau unknown (.999999999999e+09).
  const GlonassEphemeris* r01 = nullptr;
  for (const auto& g : nav.glonass) {
    if (g.source == "ESBC00DNK_R_20201770000_01D_MN.rnx:18056") r01 = &g;
  }
  ASSERT_NE(r01, nullptr);
  EXPECT_EQ(r01->toe, gpst(2020, 6, 24, 23, 15, 18));
  EXPECT_NEAR(r01->position_m.x(), 10908942.38281, 1e-6);
  EXPECT_NEAR(r01->velocity_mps.y(), 2795.855522156, 1e-9);
  EXPECT_EQ(r01->frequency_channel, 1);
  EXPECT_DOUBLE_EQ(r01->message_frame_time_s, 82800.0);  // 342000 s of the week
  EXPECT_FALSE(r01->delta_tau_n_s);
  EXPECT_EQ(r01->urai, 15);

  // Line 20606: S23 2020 06 25 00 00 16.
  ASSERT_FALSE(nav.sbas.empty());
  const auto& s23 = nav.sbas.front();
  EXPECT_EQ(s23.source, "ESBC00DNK_R_20201770000_01D_MN.rnx:20606");
  EXPECT_EQ(s23.toe, gpst(2020, 6, 25, 0, 0, 16));
  EXPECT_NEAR(s23.position_m.x(), 35944600.0, 1e-6);
  EXPECT_EQ(s23.iodn, 92);
}

TEST(RinexNavRealFiles, MojnMixed305) {
  const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/MOJN00DNK_R_20201770000_01D_MN.rnx");
  const auto nav = read_ok(path);
  EXPECT_EQ(count_records(nav), (Counts{{"C:D1", 318}, {"C:D2", 26}, {"E:FNAV", 841}, {"E:INAV", 821},
                                        {"G:LNAV", 240}, {"J:LNAV", 20}, {"R:FDMA", 464}, {"S:SBAS", 2168}}));
  EXPECT_EQ(nav.leap_seconds, 18);
}

TEST(RinexNavRealFiles, Nya1SingleSystem) {
  const auto gps_path = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_GN.rnx");
  const auto gal_path = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_EN.rnx");
  const auto bds_path = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_CN.rnx");

  const auto gps = read_ok(gps_path);
  EXPECT_EQ(count_records(gps), (Counts{{"G:LNAV", 215}}));
  ASSERT_TRUE(gps.ionosphere.gps);
  EXPECT_DOUBLE_EQ(gps.ionosphere.gps->alpha[0], 1.9558e-08);  // line ends with a time mark 'A'
  ASSERT_EQ(gps.time_corrections.size(), 1u);
  EXPECT_EQ(gps.time_corrections[0].reference_time, gpst(2024, 5, 5, 17, 4, 0));  // 61440 s, week 2313
  EXPECT_EQ(gps.leap_seconds, 18);
  const auto* g27 = find_source(gps, "NYA100NOR_S_20241240000_01D_GN.rnx:8");
  ASSERT_NE(g27, nullptr);
  EXPECT_EQ(g27->toc, gpst(2024, 5, 3, 2, 0, 0));
  EXPECT_EQ(g27->iode, 42);
  EXPECT_DOUBLE_EQ(g27->sqrt_a_sqrtm, 5.153678092957e+03);

  const auto gal = read_ok(gal_path);
  EXPECT_EQ(count_records(gal), (Counts{{"E:INAV", 711}}));  // data sources 513 everywhere
  ASSERT_TRUE(gal.ionosphere.galileo);
  EXPECT_DOUBLE_EQ(gal.ionosphere.galileo->ai0_sfu, 139.5);
  const auto* e08 = find_source(gal, "NYA100NOR_S_20241240000_01D_EN.rnx:8");
  ASSERT_NE(e08, nullptr);
  EXPECT_EQ(e08->data_source, 513u);
  EXPECT_EQ(e08->toe, gpst(2024, 5, 2, 23, 50, 0));  // 431400 s of week 2312
  EXPECT_DOUBLE_EQ(e08->group_delays.bgd_e1e5b_s, -4.423782229424e-09);

  const auto bds = read_ok(bds_path);
  EXPECT_EQ(count_records(bds), (Counts{{"C:D1", 194}}));
  const auto* c06 = find_source(bds, "NYA100NOR_S_20241240000_01D_CN.rnx:4");
  ASSERT_NE(c06, nullptr);
  EXPECT_EQ(c06->toc, gpst(2024, 5, 3, 0, 0, 14));
}

TEST(RinexNavRealFiles, SlacRinex2Gps) {
  const auto path = SKYTRACE_SHARED_FILE("real/slac_2021118/brdc1180.21n");
  const auto nav = read_ok(path);
  EXPECT_EQ(count_records(nav), (Counts{{"G:LNAV", 105}}));
  EXPECT_EQ(nav.leap_seconds, 18);
  ASSERT_TRUE(nav.ionosphere.gps);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[0], 0.9313e-08);
  const auto* g06 = find_source(nav, "brdc1180.21n:9");
  ASSERT_NE(g06, nullptr);
  EXPECT_EQ(g06->satellite.to_string(), "G06");
  EXPECT_EQ(g06->toc, gpst(2021, 4, 28, 17, 59, 44));
  EXPECT_DOUBLE_EQ(g06->af0_s, 0.109337270260e-04);
  EXPECT_EQ(g06->iode, 31);
}

TEST(RinexNavRealFiles, Kms3Rinex4) {
  const auto path = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_MN.rnx");
  const auto nav = read_ok(path);
  EXPECT_EQ(count_records(nav), (Counts{{"C:D1", 33}, {"C:D2", 3}, {"E:FNAV", 53}, {"E:INAV", 55}, {"G:LNAV", 30},
                                        {"J:LNAV", 1}, {"R:FDMA", 24}, {"S:SBAS", 158}}));
  EXPECT_EQ(nav.leap_seconds, 18);
  // "> ION G29 LNAV" (line 149), "> ION E01 IFNV" (732), "> ION C08 D1D2" (2395).
  ASSERT_TRUE(nav.ionosphere.gps);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[0], 1.024454832077e-08);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->beta[3], -5.898240000000e+05);
  ASSERT_TRUE(nav.ionosphere.galileo);
  EXPECT_DOUBLE_EQ(nav.ionosphere.galileo->ai1_sfu_per_deg, 5.390625e-01);
  ASSERT_TRUE(nav.ionosphere.beidou);
  EXPECT_DOUBLE_EQ(nav.ionosphere.beidou->alpha[2], -1.013278961182e-06);
  // "> STO" lines 234 (GPUT), 735 (GAUT), 738 (GAGP).
  ASSERT_EQ(nav.time_corrections.size(), 3u);
  EXPECT_EQ(nav.time_corrections[1].type, "GAUT");
  EXPECT_DOUBLE_EQ(nav.time_corrections[1].a0_s, -1.862645149231e-09);
  EXPECT_EQ(nav.time_corrections[1].reference_time, gpst(2022, 6, 8, 0, 0, 0));
  EXPECT_EQ(nav.time_corrections[1].source, "KMS300DNK_R_20221591000_01H_MN.rnx:735");
  for (const auto& g : nav.glonass) EXPECT_TRUE(g.delta_tau_n_s) << g.source;  // all carry line 4
}

TEST(RinexNavRealFiles, SmartlocBerlin) {
  const auto gps_path = SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/brdc1580.16n");
  const auto glo_path = SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/brdc1580.16g");
  const auto mixed_path =
      SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/BRDC00WRD_U_20161580000_01D_MN.rnx");
  const auto sbas_path =
      SKYTRACE_SHARED_FILE("real/smartloc_berlin_potsdamer_platz_2016158/REDU00BEL_R_20161580000_01D_SN.rnx");

  const auto gps = read_ok(gps_path);
  EXPECT_EQ(count_records(gps), (Counts{{"G:LNAV", 418}}));
  EXPECT_EQ(gps.leap_seconds, 17);

  const auto glo = read_ok(glo_path);
  EXPECT_EQ(count_records(glo), (Counts{{"R:FDMA", 1169}}));
  ASSERT_FALSE(glo.glonass.empty());
  const auto& r01 = glo.glonass.front();  // line 8: " 1 16  6  6  0 15  0.0"
  EXPECT_EQ(r01.source, "brdc1580.16g:8");
  EXPECT_EQ(r01.toe, gpst(2016, 6, 6, 0, 15, 17));  // UTC + 17 s
  EXPECT_NEAR(r01.position_m.x(), -6553426.26953, 1e-6);
  EXPECT_DOUBLE_EQ(r01.minus_tau_n_s, -0.142809003591e-03);
  ASSERT_EQ(glo.time_corrections.size(), 1u);
  EXPECT_EQ(glo.time_corrections[0].type, "GLUT");
  EXPECT_DOUBLE_EQ(glo.time_corrections[0].a0_s, 0.232830643654e-08);

  const auto mixed = read_ok(mixed_path);
  EXPECT_EQ(count_records(mixed), (Counts{{"C:D1", 21}, {"C:D2", 11}, {"E:FNAV", 50}, {"E:INAV", 76},
                                          {"G:LNAV", 295}, {"R:FDMA", 588}}));

  const auto sbas = read_ok(sbas_path);
  EXPECT_EQ(count_records(sbas), (Counts{{"S:SBAS", 1744}}));
  ASSERT_FALSE(sbas.sbas.empty());
  const auto& s25 = sbas.sbas.front();  // line 4
  EXPECT_EQ(s25.satellite.prn(), 125);
  EXPECT_EQ(s25.toe, gpst(2016, 6, 6, 6, 34, 8));
  EXPECT_NEAR(s25.position_m.x(), 40530769.76, 1e-6);
  EXPECT_NEAR(s25.position_m.y(), -11622011.20, 1e-6);
  EXPECT_EQ(s25.iodn, 106);
}

// hksc1180.19n and .19b carry RINEX 2 style names but are RINEX 3.02 files (LgsRinex, HKSC station):
// GPS and BeiDou navigation; the BeiDou one gives BDT - UTC (4 s) as LEAP SECONDS, CRLF endings.
TEST(RinexNavRealFiles, HongKongRinex302) {
  const auto gps_path = SKYTRACE_SHARED_FILE("real/hk_tst_ublox_m8t_2019118/hksc1180.19n");
  const auto bds_path = SKYTRACE_SHARED_FILE("real/hk_tst_ublox_m8t_2019118/hksc1180.19b");

  const auto gps = read_ok(gps_path);
  EXPECT_EQ(count_records(gps), (Counts{{"G:LNAV", 203}}));
  EXPECT_EQ(gps.leap_seconds, 18);
  for (const auto& e : gps.kepler) EXPECT_DOUBLE_EQ(e.fit_interval_h, 0.0) << e.source;  // field left blank

  const auto bds = read_ok(bds_path);
  EXPECT_EQ(count_records(bds), (Counts{{"C:D1", 229}, {"C:D2", 127}}));
  EXPECT_EQ(bds.leap_seconds, 18);  // 4 s BDT - UTC + 14 s
  ASSERT_TRUE(bds.ionosphere.beidou);
  EXPECT_DOUBLE_EQ(bds.ionosphere.beidou->alpha[0], 9.3132e-09);
  const auto* c01 = find_source(bds, "hksc1180.19b:8");  // C01 2019 04 27 23 00 00, week 694, toe 601200 s
  ASSERT_NE(c01, nullptr);
  EXPECT_EQ(c01->message, NavMessage::kBeiDouD2);
  EXPECT_EQ(c01->toc, gpst(2019, 4, 27, 23, 0, 14));
  EXPECT_EQ(c01->toe, c01->toc);
  EXPECT_DOUBLE_EQ(c01->group_delays.tgd1_s, 1.420000028673e-08);
  ASSERT_EQ(bds.time_corrections.size(), 1u);
  EXPECT_EQ(bds.time_corrections[0].type, "BDUT");
  EXPECT_EQ(bds.time_corrections[0].reference_time,
            GnssTime::from_week_tow(TimeScale::kBdt, 695, 85985.0));
}

}  // namespace
}  // namespace skytrace::orbits
