// RINEX 3.04 navigation writer: hand-made records of every system against the expected text.
// The expected lines of G, R, E, C, J and S records are the lines of the real ESBC00DNK
// 2020-06-25 mixed file (RINEX 3.05, sbf2rin) with 'e' exponents written 'E' and trailing blanks
// removed; the GLONASS fourth line (3.05 only) is not expected. The NavIC record and the header
// lines follow the RINEX 3.04 column layout (tables A5-A21).
#include <sstream>
#include <string>
#include <vector>

#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"
#include "time_boundaries.hpp"

namespace skytrace::orbits {
namespace {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) out.push_back(line);
  return out;
}

std::string rtrim(std::string s) {
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// The lines of the first record whose epoch line starts with `id` ("G01 2020 06 25 04").
std::vector<std::string> record(const std::string& text, const std::string& id, size_t count) {
  const auto lines = split_lines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind(id, 0) == 0) {
      std::vector<std::string> out;
      for (size_t j = i; j < lines.size() && j < i + count; ++j) out.push_back(rtrim(lines[j]));
      return out;
    }
  }
  return {};
}

GnssTime gpst(int y, int mo, int d, int h, int mi, double s) {
  return GnssTime::from_calendar(CalendarTime{y, mo, d, h, mi, s}, TimeScale::kGpst);
}

KeplerEphemeris gps_g01() {
  KeplerEphemeris e;
  e.satellite = {GnssSystem::kGps, 1};
  e.message = NavMessage::kGpsLnav;
  e.toc = gpst(2020, 6, 25, 4, 0, 0);
  e.toe = e.toc;
  e.week = 2111;
  e.toe_sow = 3.6e5;
  e.af0_s = 1.604342833161e-05;
  e.af1_s_per_s = 7.048583938740e-12;
  e.iode = 58;
  e.crs_m = -3.968750000000e+01;
  e.delta_n_rad_per_s = 4.304822170265e-09;
  e.m0_rad = 6.342094507864e-01;
  e.cuc_rad = -2.177432179451e-06;
  e.eccentricity = 1.000394229777e-02;
  e.cus_rad = 1.937150955200e-06;
  e.sqrt_a_sqrtm = 5.153707128525e+03;
  e.cic_rad = -1.508742570877e-07;
  e.omega0_rad = 2.572838528869e+00;
  e.cis_rad = 1.359730958939e-07;
  e.i0_rad = 9.806518601091e-01;
  e.crc_m = 3.539687500000e+02;
  e.omega_rad = 7.941703015008e-01;
  e.omega_dot_rad_per_s = -8.384634967987e-09;
  e.idot_rad_per_s = -5.714523747137e-11;
  e.codes_on_l2 = 1;
  e.accuracy_m = 2.0;
  e.group_delays.tgd_s = 5.122274160385e-09;
  e.iodc = 58;
  e.transmission_time_sow = 3.561060000000e+05;
  e.fit_interval_h = 4.0;
  return e;
}

KeplerEphemeris galileo_e01(bool inav) {
  KeplerEphemeris e;
  e.satellite = {GnssSystem::kGalileo, 1};
  e.message = inav ? NavMessage::kGalileoInav : NavMessage::kGalileoFnav;
  e.toc = gpst(2020, 6, 24, 23, 30, 0);
  e.toe = e.toc;
  e.week = 2111;
  e.toe_sow = 3.438e5;
  e.af0_s = inav ? -8.846933487803e-04 : -8.846927667037e-04;
  e.af1_s_per_s = -7.972289495228e-12;
  e.iode = e.iodc = 61;
  e.crs_m = 1.865625000000e+01;
  e.delta_n_rad_per_s = 2.656539226950e-09;
  e.m0_rad = -1.832282909549e+00;
  e.cuc_rad = 8.568167686462e-07;
  e.eccentricity = 9.650341235101e-05;
  e.cus_rad = 1.049041748047e-05;
  e.sqrt_a_sqrtm = 5.440602037430e+03;
  e.cic_rad = 1.862645149231e-09;
  e.omega0_rad = 2.123282284601e-01;
  e.cis_rad = -1.452863216400e-07;
  e.i0_rad = 9.828296477370e-01;
  e.crc_m = 1.298750000000e+02;
  e.omega_rad = -2.778709093141e+00;
  e.omega_dot_rad_per_s = -5.216288707934e-09;
  e.idot_rad_per_s = -6.996720012901e-10;
  e.data_source = inav ? 517 : 258;
  e.accuracy_m = 3.12;
  e.group_delays.bgd_e1e5a_s = -1.862645149231e-09;
  e.group_delays.bgd_e1e5b_s = inav ? -2.095475792885e-09 : 0.0;
  e.transmission_time_sow = inav ? 3.444650000000e+05 : 3.445400000000e+05;
  return e;
}

KeplerEphemeris beidou_c05() {
  KeplerEphemeris e;
  e.satellite = {GnssSystem::kBeiDou, 5};
  e.message = NavMessage::kBeiDouD2;
  e.toc = GnssTime::from_calendar(CalendarTime{2020, 6, 24, 22, 0, 0.0}, TimeScale::kBdt);
  e.toe = e.toc;
  e.week = 755;
  e.toe_sow = 3.384e5;
  e.af0_s = -5.154609680176e-04;
  e.af1_s_per_s = -6.708145150469e-11;
  e.iode = 1;
  e.crs_m = -4.142968750000e+02;
  e.delta_n_rad_per_s = -3.141559429989e-09;
  e.m0_rad = -1.101749161212e+00;
  e.cuc_rad = -1.366203650832e-05;
  e.eccentricity = 3.830116475001e-04;
  e.cus_rad = -1.177610829473e-05;
  e.sqrt_a_sqrtm = 6.493378950119e+03;
  e.cic_rad = -6.146728992462e-08;
  e.omega0_rad = 2.697580724014e+00;
  e.cis_rad = 6.146728992462e-08;
  e.i0_rad = 1.136268367853e-01;
  e.crc_m = 3.549843750000e+02;
  e.omega_rad = -1.027125663175e+00;
  e.omega_dot_rad_per_s = 4.100527946305e-09;
  e.idot_rad_per_s = 3.321566928024e-10;
  e.accuracy_m = 2.0;
  e.group_delays.tgd1_s = 1.0e-10;
  e.group_delays.tgd2_s = -9.3e-09;
  e.transmission_time_sow = 3.384276000000e+05;
  e.iodc = 0;
  return e;
}

KeplerEphemeris qzss_j01() {
  KeplerEphemeris e;
  e.satellite = {GnssSystem::kQzss, 1};
  e.message = NavMessage::kQzssLnav;
  e.toc = gpst(2020, 6, 25, 11, 0, 0);
  e.toe = e.toc;
  e.week = 2111;
  e.toe_sow = 3.852e5;
  e.af0_s = -2.819551154971e-04;
  e.af1_s_per_s = 5.684341886081e-12;
  e.iode = 201;
  e.crs_m = -3.591562500000e+02;
  e.delta_n_rad_per_s = 1.487561962927e-09;
  e.m0_rad = 2.868171997688e+00;
  e.cuc_rad = -1.077167689800e-05;
  e.eccentricity = 7.578011264559e-02;
  e.cus_rad = 3.583729267120e-05;
  e.sqrt_a_sqrtm = 6.493466983795e+03;
  e.cic_rad = 1.190230250359e-06;
  e.omega0_rad = -2.201465120842e+00;
  e.cis_rad = 1.600012183189e-06;
  e.i0_rad = 7.264422575902e-01;
  e.crc_m = -1.024000000000e+03;
  e.omega_rad = -1.556061202938e+00;
  e.omega_dot_rad_per_s = -2.021155617816e-09;
  e.idot_rad_per_s = 1.379343169465e-09;
  e.codes_on_l2 = 2;
  e.l2p_data_flag = 1;
  e.accuracy_m = 2.8;
  e.group_delays.tgd_s = -5.587935447693e-09;
  e.iodc = 969;
  e.transmission_time_sow = 3.837780000000e+05;
  e.fit_interval_h = 2.0;  // written as the QZSS flag 0
  return e;
}

GlonassEphemeris glonass_r01() {
  GlonassEphemeris g;
  g.satellite = {GnssSystem::kGlonass, 1};
  g.toe = GnssTime::from_calendar(CalendarTime{2020, 6, 24, 23, 15, 0.0}, TimeScale::kUtc);
  g.minus_tau_n_s = 6.355904042721e-05;
  g.gamma_n = 0.0;
  g.message_frame_time_s =
      82800.0;  // 23:00:00 of the UTC day: 342000 s of the UTC week (Wednesday)
  g.position_m = {1.090894238281e+07, -2.885726074219e+06, 2.288353955078e+07};
  g.velocity_mps = {1.407806396484e+03, 2.795855522156e+03, -3.169984817505e+02};
  g.acceleration_mps2 = {-1.862645149231e-06, -0.0, -2.793967723846e-06};
  g.health = 0;
  g.frequency_channel = 1;
  g.age_days = 0.0;
  g.delta_tau_n_s = 1e-9;  // RINEX 3.05 only: not written
  return g;
}

SbasEphemeris sbas_s23() {
  SbasEphemeris s;
  s.satellite = {GnssSystem::kSbas, 23};
  s.toe = gpst(2020, 6, 25, 0, 0, 16);
  s.transmission_time_sow = 3.456300000000e+05;
  s.position_m = {3.594460000000e+07, 2.204414000000e+07, 0.0};
  s.health = 63;
  s.accuracy_m = 32767.0;
  s.iodn = 92;
  return s;
}

KeplerEphemeris navic_i05() {
  KeplerEphemeris e;
  e.satellite = {GnssSystem::kNavic, 5};
  e.message = NavMessage::kNavicLnav;
  e.toc = gpst(2020, 6, 25, 0, 0, 0);
  e.toe = e.toc;
  e.week = 2111;
  e.toe_sow = 345600.0;
  e.af0_s = 1.25e-4;
  e.af1_s_per_s = -2.5e-12;
  e.iode = 12;
  e.crs_m = 100.5;
  e.delta_n_rad_per_s = 1e-9;
  e.m0_rad = -1.5;
  e.cuc_rad = 2e-6;
  e.eccentricity = 2e-3;
  e.cus_rad = -3e-6;
  e.sqrt_a_sqrtm = 6493.5;
  e.cic_rad = 4e-8;
  e.omega0_rad = 1.25;
  e.cis_rad = -5e-8;
  e.i0_rad = 0.5;
  e.crc_m = -250.25;
  e.omega_rad = 3.0;
  e.omega_dot_rad_per_s = -3e-9;
  e.idot_rad_per_s = 6e-11;
  e.accuracy_m = 2.0;
  e.health = 0;
  e.group_delays.tgd_s = -4.5e-9;
  e.transmission_time_sow = 343800.0;
  return e;
}

NavigationData all_systems() {
  NavigationData data;
  // Deliberately out of order: the writer sorts by system, satellite, message and toe.
  data.kepler = {navic_i05(),  galileo_e01(false), qzss_j01(),
                 beidou_c05(), galileo_e01(true),  gps_g01()};
  data.glonass = {glonass_r01()};
  data.sbas = {sbas_s23()};
  data.ionosphere.galileo = NequickGCoefficients{2.8250e+01, 7.8125e-03, 1.0071e-02};
  data.ionosphere.gps = KlobucharCoefficients{{4.6566e-09, 1.4901e-08, -5.9605e-08, -1.1921e-07},
                                              {8.1920e+04, 9.8304e+04, -6.5536e+04, -5.2429e+05}};
  data.ionosphere.beidou =
      KlobucharCoefficients{{1.1176e-08, 2.9802e-08, -4.1723e-07, 6.5565e-07},
                            {1.4131e+05, -5.2429e+05, 1.6384e+06, -4.5875e+05}};
  data.time_corrections.push_back({"GAGP", 2.3574102670e-09, 3.996802889e-15,
                                   GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600), ""});
  data.time_corrections.push_back(
      {"BDUT", -2.793967723846e-09, 0.0, GnssTime::from_week_tow(TimeScale::kBdt, 755, 14), ""});
  data.time_corrections.push_back({"GLUT", 1.8626451492e-09, 0.0, GnssTime{}, ""});
  data.leap_seconds = 18;
  return data;
}

RinexNavWriteOptions fixed_options() {
  RinexNavWriteOptions options;
  options.program = "skytrace";
  options.run_by = "test";
  options.creation_date = "20200625 000000 UTC";
  return options;
}

TEST(RinexNavWriter, HeaderLinesInColumns) {
  const auto lines = split_lines(format_rinex3_nav(all_systems(), fixed_options()));
  const std::vector<std::string> expected = {
      "     3.04           N: GNSS NAV DATA    M: MIXED            RINEX VERSION / TYPE",
      "skytrace            test                20200625 000000 UTC PGM / RUN BY / DATE",
      "GAL    2.8250E+01  7.8125E-03  1.0071E-02  0.0000E+00       IONOSPHERIC CORR",
      "GPSA   4.6566E-09  1.4901E-08 -5.9605E-08 -1.1921E-07       IONOSPHERIC CORR",
      "GPSB   8.1920E+04  9.8304E+04 -6.5536E+04 -5.2429E+05       IONOSPHERIC CORR",
      "BDSA   1.1176E-08  2.9802E-08 -4.1723E-07  6.5565E-07       IONOSPHERIC CORR",
      "BDSB   1.4131E+05 -5.2429E+05  1.6384E+06 -4.5875E+05       IONOSPHERIC CORR",
      "GAGP  2.3574102670E-09 3.996802889E-15 345600 2111          TIME SYSTEM CORR",
      "BDUT -2.7939677238E-09 0.000000000E+00     14  755          TIME SYSTEM CORR",
      "GLUT  1.8626451492E-09 0.000000000E+00      0    0          TIME SYSTEM CORR",
      "    18                                                      LEAP SECONDS",
      "                                                            END OF HEADER",
  };
  ASSERT_GE(lines.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i)
    EXPECT_EQ(lines[i], expected[i]) << "header line " << i + 1;
}

TEST(RinexNavWriter, GpsRecordMatchesRealFile) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  const std::vector<std::string> expected = {
      "G01 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00",
      "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01",
      "    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03",
      "     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07",
      "     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09",
      "    -5.714523747137E-11 1.000000000000E+00 2.111000000000E+03 0.000000000000E+00",
      "     2.000000000000E+00 0.000000000000E+00 5.122274160385E-09 5.800000000000E+01",
      "     3.561060000000E+05 4.000000000000E+00",
  };
  EXPECT_EQ(record(text, "G01 ", 8), expected);
}

TEST(RinexNavWriter, GalileoInavBeforeFnavMatchesRealFile) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  const std::vector<std::string> inav = {
      "E01 2020 06 24 23 30 00-8.846933487803E-04-7.972289495228E-12 0.000000000000E+00",
      "     6.100000000000E+01 1.865625000000E+01 2.656539226950E-09-1.832282909549E+00",
      "     8.568167686462E-07 9.650341235101E-05 1.049041748047E-05 5.440602037430E+03",
      "     3.438000000000E+05 1.862645149231E-09 2.123282284601E-01-1.452863216400E-07",
      "     9.828296477370E-01 1.298750000000E+02-2.778709093141E+00-5.216288707934E-09",
      "    -6.996720012901E-10 5.170000000000E+02 2.111000000000E+03",
      "     3.120000000000E+00 0.000000000000E+00-1.862645149231E-09-2.095475792885E-09",
      "     3.444650000000E+05",
  };
  const std::vector<std::string> fnav_changes = {
      "E01 2020 06 24 23 30 00-8.846927667037E-04-7.972289495228E-12 0.000000000000E+00",
      "    -6.996720012901E-10 2.580000000000E+02 2.111000000000E+03",
      "     3.120000000000E+00 0.000000000000E+00-1.862645149231E-09 0.000000000000E+00",
      "     3.445400000000E+05",
  };
  const auto both = record(text, "E01 ", 16);
  ASSERT_EQ(both.size(), 16u);
  // The I/NAV record is first although the input lists the F/NAV record first.
  EXPECT_EQ(std::vector<std::string>(both.begin(), both.begin() + 8), inav);
  EXPECT_EQ(both[8], fnav_changes[0]);
  EXPECT_EQ(both[13], fnav_changes[1]);
  EXPECT_EQ(both[14], fnav_changes[2]);
  EXPECT_EQ(both[15], fnav_changes[3]);
}

TEST(RinexNavWriter, BeiDouRecordInBdtMatchesRealFile) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  const std::vector<std::string> expected = {
      "C05 2020 06 24 22 00 00-5.154609680176E-04-6.708145150469E-11 0.000000000000E+00",
      "     1.000000000000E+00-4.142968750000E+02-3.141559429989E-09-1.101749161212E+00",
      "    -1.366203650832E-05 3.830116475001E-04-1.177610829473E-05 6.493378950119E+03",
      "     3.384000000000E+05-6.146728992462E-08 2.697580724014E+00 6.146728992462E-08",
      "     1.136268367853E-01 3.549843750000E+02-1.027125663175E+00 4.100527946305E-09",
      "     3.321566928024E-10 0.000000000000E+00 7.550000000000E+02",
      "     2.000000000000E+00 0.000000000000E+00 1.000000000000E-10-9.300000000000E-09",
      "     3.384276000000E+05 0.000000000000E+00",
  };
  EXPECT_EQ(record(text, "C05 ", 8), expected);
}

TEST(RinexNavWriter, QzssRecordWritesFitFlagMatchesRealFile) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  const std::vector<std::string> expected = {
      "J01 2020 06 25 11 00 00-2.819551154971E-04 5.684341886081E-12 0.000000000000E+00",
      "     2.010000000000E+02-3.591562500000E+02 1.487561962927E-09 2.868171997688E+00",
      "    -1.077167689800E-05 7.578011264559E-02 3.583729267120E-05 6.493466983795E+03",
      "     3.852000000000E+05 1.190230250359E-06-2.201465120842E+00 1.600012183189E-06",
      "     7.264422575902E-01-1.024000000000E+03-1.556061202938E+00-2.021155617816E-09",
      "     1.379343169465E-09 2.000000000000E+00 2.111000000000E+03 1.000000000000E+00",
      "     2.800000000000E+00 0.000000000000E+00-5.587935447693E-09 9.690000000000E+02",
      "     3.837780000000E+05 0.000000000000E+00",
  };
  EXPECT_EQ(record(text, "J01 ", 8), expected);
}

TEST(RinexNavWriter, GlonassRecordInKmWithoutFourthLine) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  const std::vector<std::string> expected = {
      "R01 2020 06 24 23 15 00 6.355904042721E-05 0.000000000000E+00 3.420000000000E+05",
      "     1.090894238281E+04 1.407806396484E+00-1.862645149231E-09 0.000000000000E+00",
      "    -2.885726074219E+03 2.795855522156E+00-0.000000000000E+00 1.000000000000E+00",
      "     2.288353955078E+04-3.169984817505E-01-2.793967723846E-09 0.000000000000E+00",
  };
  const auto lines = record(text, "R01 ", 5);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(std::vector<std::string>(lines.begin(), lines.begin() + 4), expected);
  // The next line starts the next record (RINEX 3.04 has no fourth GLONASS orbit line).
  EXPECT_EQ(lines[4].substr(0, 1), "E");
}

TEST(RinexNavWriter, SbasRecordMatchesRealFile) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  const std::vector<std::string> expected = {
      "S23 2020 06 25 00 00 16 0.000000000000E+00 0.000000000000E+00 3.456300000000E+05",
      "     3.594460000000E+04 0.000000000000E+00 0.000000000000E+00 6.300000000000E+01",
      "     2.204414000000E+04 0.000000000000E+00 0.000000000000E+00 3.276700000000E+04",
      "     0.000000000000E+00 0.000000000000E+00 0.000000000000E+00 9.200000000000E+01",
  };
  EXPECT_EQ(record(text, "S23 ", 4), expected);
}

TEST(RinexNavWriter, NavicRecordLayout) {
  const auto text = format_rinex3_nav(all_systems(), fixed_options());
  // RINEX 3.04 table A19: IODEC; Crs, Delta n, M0 ... line 5 IDOT, blank, IRN week (GPS-aligned);
  // line 6 URA, health, TGD; line 7 transmission time.
  const std::vector<std::string> expected = {
      "I05 2020 06 25 00 00 00 1.250000000000E-04-2.500000000000E-12 0.000000000000E+00",
      "     1.200000000000E+01 1.005000000000E+02 1.000000000000E-09-1.500000000000E+00",
      "     2.000000000000E-06 2.000000000000E-03-3.000000000000E-06 6.493500000000E+03",
      "     3.456000000000E+05 4.000000000000E-08 1.250000000000E+00-5.000000000000E-08",
      "     5.000000000000E-01-2.502500000000E+02 3.000000000000E+00-3.000000000000E-09",
      "     6.000000000000E-11 0.000000000000E+00 2.111000000000E+03",
      "     2.000000000000E+00 0.000000000000E+00-4.500000000000E-09",
      "     3.438000000000E+05",
  };
  EXPECT_EQ(record(text, "I05 ", 8), expected);
}

TEST(RinexNavWriter, RecordsOrderedBySystemThenSatellite) {
  const auto lines = split_lines(format_rinex3_nav(all_systems(), fixed_options()));
  std::string order;
  bool body = false;
  for (const auto& line : lines) {
    if (line.find("END OF HEADER") != std::string::npos) {
      body = true;
      continue;
    }
    if (body && !line.empty() && line[0] != ' ') order += line.substr(0, 3) + " ";
  }
  EXPECT_EQ(order, "G01 R01 E01 E01 C05 J01 I05 S23 ");
}

TEST(RinexNavWriter, FillsWeekAndDataSourceOfHandMadeRecords) {
  NavigationData data;
  KeplerEphemeris e = galileo_e01(false);
  e.week = 0;  // not given: from toe
  e.toe_sow = 0.0;
  e.data_source = 0;  // not given: F/NAV -> 258
  data.kepler.push_back(e);
  KeplerEphemeris c = beidou_c05();
  c.week = 0;
  c.toe_sow = 0.0;
  data.kepler.push_back(c);
  const auto text = format_rinex3_nav(data, fixed_options());
  const auto galileo = record(text, "E01 ", 8);
  ASSERT_EQ(galileo.size(), 8u);
  EXPECT_EQ(galileo[3].substr(0, 23), "     3.438000000000E+05");
  EXPECT_EQ(galileo[5], "    -6.996720012901E-10 2.580000000000E+02 2.111000000000E+03");
  const auto beidou = record(text, "C05 ", 8);
  ASSERT_EQ(beidou.size(), 8u);
  EXPECT_EQ(beidou[3].substr(0, 23), "     3.384000000000E+05");  // BDT seconds of week
  EXPECT_EQ(beidou[5].substr(42, 19), " 7.550000000000E+02");     // BDT week
}

TEST(RinexNavWriter, LeavesOutCnavRecordsWithAComment) {
  NavigationData data;
  KeplerEphemeris cnav = gps_g01();
  cnav.message = NavMessage::kGpsCnav;
  data.kepler = {gps_g01(), cnav};
  const auto text = format_rinex3_nav(data, fixed_options());
  EXPECT_NE(text.find("1 CNAV/CNAV-2/B-CNAV records left out"), std::string::npos);
  size_t epochs = 0;
  for (const auto& line : split_lines(text)) epochs += line.rfind("G01 ", 0) == 0 ? 1 : 0;
  EXPECT_EQ(epochs, 1u);
}

TEST(RinexNavWriter, EveryLineFitsEightyColumns) {
  const auto text = format_rinex3_nav(all_systems(), RinexNavWriteOptions{});
  for (const auto& line : split_lines(text)) EXPECT_LE(line.size(), 80u) << line;
  // Default creation date: "YYYYMMDD HHMMSS UTC" in columns 41-59.
  const auto second = split_lines(text).at(1);
  EXPECT_EQ(second.substr(56, 3), "UTC");
  EXPECT_EQ(second.substr(48, 1), " ");
}

// "YYYY-MM-DDThh:mm:ss" as a record epoch writes it after the satellite ("2024 05 05 00 00 00").
std::string record_epoch(const std::string& iso) {
  return iso.substr(0, 4) + " " + iso.substr(5, 2) + " " + iso.substr(8, 2) + " " + iso.substr(11, 2) + " " +
         iso.substr(14, 2) + " " + iso.substr(17, 2);
}

TEST(RinexNavWriter, RecordEpochRoundedToTheSecondCarriesIntoMinuteHourDayMonthYearAndWeek) {
  for (const auto& b : test::time_boundaries()) {
    for (const double fraction : test::fractions_rounding_up(0)) {
      NavigationData data;
      KeplerEphemeris g = gps_g01();
      g.toc = test::boundary_time(b, TimeScale::kGpst, fraction);  // GPS epochs in GPST
      KeplerEphemeris c = beidou_c05();
      c.toc = test::boundary_time(b, TimeScale::kBdt, fraction);  // BeiDou epochs in BDT
      GlonassEphemeris r = glonass_r01();
      r.toe = test::boundary_time(b, TimeScale::kUtc, fraction);  // GLONASS epochs in UTC
      data.kepler = {g, c};
      data.glonass = {r};
      const auto text = format_rinex3_nav(data, fixed_options());
      const std::string expected = record_epoch(b.next);
      for (const char* id : {"G01 ", "C05 ", "R01 "}) {
        const auto lines = record(text, id, 1);
        ASSERT_EQ(lines.size(), 1u) << id << b.name;
        EXPECT_EQ(lines[0].substr(4, 19), expected) << id << b.name << ", fraction " << fraction;
      }
    }
  }
}

TEST(RinexNavWriter, GlonassRecordEpochKeepsARealLeapSecond) {
  NavigationData data;
  GlonassEphemeris r = glonass_r01();
  r.toe = GnssTime::parse_iso8601("2016-12-31T23:59:59.7", TimeScale::kUtc).value();
  data.glonass = {r};
  auto lines = record(format_rinex3_nav(data, fixed_options()), "R01 ", 1);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].substr(4, 19), "2016 12 31 23 59 60");
  data.glonass[0].toe = GnssTime::parse_iso8601("2016-12-31T23:59:60.7", TimeScale::kUtc).value();
  lines = record(format_rinex3_nav(data, fixed_options()), "R01 ", 1);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].substr(4, 19), "2017 01 01 00 00 00");
}

TEST(RinexNavWriter, TimeSystemCorrectionReferenceRoundedAtTheWeekEnd) {
  // The reference time is written as whole seconds of week and week: rounding 604799.6 s up must
  // give second 0 of the next week, never second 604800 of this one.
  for (const double fraction : test::fractions_rounding_up(0)) {
    NavigationData data;
    data.kepler = {gps_g01()};
    data.time_corrections.push_back(
        {"GAGP", 2.3574102670e-09, 0.0, GnssTime::from_week_tow(TimeScale::kGpst, 2312, 604799.0) + fraction, ""});
    data.time_corrections.push_back(
        {"BDUT", -2.793967723846e-09, 0.0, GnssTime::from_week_tow(TimeScale::kBdt, 956, 604799.0) + fraction, ""});
    data.time_corrections.push_back(
        {"GPUT", 1e-9, 0.0, GnssTime::from_week_tow(TimeScale::kGpst, 2312, 345599.0) + fraction, ""});
    std::vector<std::string> found;
    for (const auto& line : split_lines(format_rinex3_nav(data, fixed_options()))) {
      if (line.find("TIME SYSTEM CORR") != std::string::npos) found.push_back(line.substr(0, 4) + line.substr(38, 12));
    }
    EXPECT_EQ(found, (std::vector<std::string>{"GAGP      0 2313", "BDUT      0  957", "GPUT 345600 2312"}))
        << "fraction " << fraction;
  }
}

}  // namespace
}  // namespace skytrace::orbits
