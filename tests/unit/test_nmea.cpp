// NMEA 0183 v4.11 sentences: the checksum against the textbook GGA example, and every sentence of
// hand-made fixes against text written out by hand (checksums computed separately with Python).
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "skytrace/io/nmea.hpp"
#include "time_boundaries.hpp"

namespace skytrace::io {
namespace {

positioning::SatelliteUse sat(const char* id, const char* signal, double az, double el, double cn0, bool used,
                              double residual_m) {
  positioning::SatelliteUse s;
  s.satellite = SatelliteId::parse(id).value();
  s.signal = Signal::parse(signal).value();
  s.direction = {az, el};
  s.cn0_dbhz = cn0;
  s.used = used;
  s.residual_m = residual_m;
  return s;
}

GnssTime gpst(const char* iso) { return GnssTime::parse_iso8601(iso, TimeScale::kGpst).value(); }

positioning::PositionFix esbc_like_fix() {
  positioning::PositionFix fix;
  fix.receiver_time = fix.time = gpst("2020-06-25T12:35:14.5");  // UTC 12:34:56.5 (GPS - UTC = 18 s)
  fix.type = positioning::FixType::kFix3D;
  fix.position = {55.46123456, 8.4575, 58.1234};
  fix.velocity_valid = true;
  fix.velocity_enu_mps = {1.0, 1.0, 0.1};
  fix.hdop = 0.83;
  fix.pdop = 1.52;
  fix.vdop = 1.27;
  fix.satellites_used = 3;
  fix.covariance_enu_m2 = Eigen::Vector3d(4.0, 1.0, 9.0).asDiagonal();
  fix.satellites = {sat("G05", "G1C", 45.4, 30.6, 44.6, true, 0.3), sat("G13", "G1C", 359.7, 5.2, 35.2, true, -0.4),
                    sat("R07", "R1C", 120.0, 60.0, 48.0, true, 0.0), sat("E11", "E1C", 200.5, 12.4, 38.9, false, 0.0)};
  return fix;
}

// Heights as a receiver without a geoid model gives them: ellipsoidal, separation 0.
NmeaSettings ellipsoidal() {
  NmeaSettings s;
  s.geoid = nullptr;
  return s;
}

TEST(Nmea, ChecksumOfTheTextbookGga) {
  EXPECT_EQ(nmea_checksum("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), "47");
  EXPECT_TRUE(nmea_checksum_valid("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"));
  EXPECT_FALSE(nmea_checksum_valid("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*48"));
  EXPECT_FALSE(nmea_checksum_valid("GPGGA,123519*47"));
  EXPECT_EQ(nmea_sentence("GPZDA,1"), "$GPZDA,1*" + nmea_checksum("GPZDA,1") + "\r\n");
}

TEST(Nmea, EverySentenceOfAMultiConstellationFix) {
  const std::vector<std::string> expected = {
      "$GNGGA,123456.50,5527.6740736,N,00827.4500000,E,1,03,0.83,58.123,M,0.000,M,,*4B\r\n",
      "$GNGSA,A,3,05,13,,,,,,,,,,,1.52,0.83,1.27,1*0F\r\n",
      "$GNGSA,A,3,71,,,,,,,,,,,,1.52,0.83,1.27,2*0D\r\n",
      "$GNGSA,A,3,,,,,,,,,,,,,1.52,0.83,1.27,3*0A\r\n",
      "$GPGSV,1,1,02,05,31,045,45,13,05,000,35,1*60\r\n",
      "$GLGSV,1,1,01,71,60,120,48,1*46\r\n",
      "$GAGSV,1,1,01,11,12,201,39,7*48\r\n",
      "$GNRMC,123456.50,A,5527.6740736,N,00827.4500000,E,2.749,45.00,250620,,,A,V*3C\r\n",
      "$GNVTG,45.00,T,,M,2.749,N,5.091,K,A*17\r\n",
      "$GNZDA,123456.50,25,06,2020,00,00*7B\r\n",
      "$GNGST,123456.50,0.289,2.000,1.000,90.00,1.000,2.000,3.000*42\r\n",
  };
  const auto sentences = nmea_epoch(esbc_like_fix(), ellipsoidal());
  ASSERT_EQ(sentences.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(sentences[i], expected[i]) << i;
}

TEST(Nmea, SingleSystemTalkerAndSouthWestHemisphere) {
  auto fix = esbc_like_fix();
  fix.position = {-33.8568, -151.2153, -12.5};
  fix.hdop = 1.0;
  fix.satellites_used = 1;
  fix.satellites = {sat("G05", "G1C", 45.4, 30.6, 44.6, true, 0.3)};
  NmeaSettings only_gga = ellipsoidal();
  only_gga.gsa = only_gga.gsv = only_gga.rmc = only_gga.vtg = only_gga.zda = only_gga.gst = false;
  const auto sentences = nmea_epoch(fix, only_gga);
  ASSERT_EQ(sentences.size(), 1U);
  EXPECT_EQ(sentences[0], "$GPGGA,123456.50,3351.4080000,S,15112.9180000,W,1,01,1.00,-12.500,M,0.000,M,,*74\r\n");
}

TEST(Nmea, NoFixSentences) {
  auto fix = esbc_like_fix();
  fix.type = positioning::FixType::kNone;
  const auto sentences = nmea_epoch(fix);
  EXPECT_EQ(sentences.front(), "$GNGGA,123456.50,,,,,0,00,,,M,,M,,*54\r\n");
  bool rmc_seen = false;
  for (const auto& s : sentences) {
    EXPECT_TRUE(nmea_checksum_valid(s)) << s;
    if (s.rfind("$GNRMC", 0) == 0) {
      EXPECT_EQ(s, "$GNRMC,123456.50,V,,,,,,,250620,,,N,V*18\r\n");
      rmc_seen = true;
    }
    if (s.rfind("$GNGSA", 0) == 0) {
      EXPECT_EQ(s.substr(0, 12), "$GNGSA,A,1,,") << s;
    }
  }
  EXPECT_TRUE(rmc_seen);
}

TEST(Nmea, TimeRoundsIntoTheNextDayAcrossTheLeapSecondOffset) {
  auto fix = esbc_like_fix();
  fix.time = fix.receiver_time = gpst("2020-06-25T00:00:17.996");  // UTC 2020-06-24T23:59:59.996
  NmeaSettings only_zda;
  only_zda.gga = only_zda.gsa = only_zda.gsv = only_zda.rmc = only_zda.vtg = only_zda.gst = false;
  EXPECT_EQ(nmea_epoch(fix, only_zda).at(0), "$GNZDA,000000.00,25,06,2020,00,00*79\r\n");
}

TEST(Nmea, SatelliteAndSignalNumberingOfNmea411) {
  const auto id = [](const char* text) { return nmea_satellite_id(SatelliteId::parse(text).value()); };
  EXPECT_EQ(id("G32"), 32);
  EXPECT_EQ(id("R01"), 65);
  EXPECT_EQ(id("R24"), 88);
  EXPECT_EQ(id("E36"), 36);
  EXPECT_EQ(id("C63"), 63);
  EXPECT_EQ(id("J01"), 1);
  EXPECT_EQ(id("S20"), 33);  // PRN 120
  EXPECT_EQ(id("I14"), 14);
  const auto signal = [](const char* text) { return nmea_signal_id(Signal::parse(text).value()); };
  EXPECT_EQ(signal("G1C"), 1);
  EXPECT_EQ(signal("G2W"), 4);
  EXPECT_EQ(signal("G2L"), 6);
  EXPECT_EQ(signal("G5Q"), 8);
  EXPECT_EQ(signal("R2C"), 3);
  EXPECT_EQ(signal("E5Q"), 1);
  EXPECT_EQ(signal("E7Q"), 2);
  EXPECT_EQ(signal("E1C"), 7);
  EXPECT_EQ(signal("C2I"), 1);
  EXPECT_EQ(signal("C7I"), 0xB);
  EXPECT_EQ(signal("J1C"), 1);
  EXPECT_EQ(nmea_system_id(GnssSystem::kBeiDou), 4);
  EXPECT_EQ(nmea_talker(GnssSystem::kBeiDou), "GB");
  EXPECT_EQ(nmea_talker(GnssSystem::kQzss), "GQ");
  EXPECT_EQ(nmea_talker(GnssSystem::kNavic), "GI");
}

TEST(Nmea, GsvSplitsIntoSentencesOfFourSatellites) {
  positioning::PositionFix fix = esbc_like_fix();
  fix.satellites.clear();
  for (int prn = 1; prn <= 9; ++prn) {
    fix.satellites.push_back(sat(("G" + std::to_string(prn)).c_str(), "G1C", 10.0 * prn, 20.0, 40.0, true, 0.0));
  }
  NmeaSettings only_gsv;
  only_gsv.gga = only_gsv.gsa = only_gsv.rmc = only_gsv.vtg = only_gsv.zda = only_gsv.gst = false;
  const auto sentences = nmea_epoch(fix, only_gsv);
  ASSERT_EQ(sentences.size(), 3U);
  EXPECT_EQ(sentences[0].substr(0, 17), "$GPGSV,3,1,09,01,");
  EXPECT_EQ(sentences[2].substr(0, 17), "$GPGSV,3,3,09,09,");
}

// Comma-separated fields of a sentence without '$' and the checksum.
std::vector<std::string> fields_of(const std::string& sentence) {
  const std::string body = sentence.substr(1, sentence.find('*') - 1);
  std::vector<std::string> fields;
  size_t start = 0;
  for (size_t comma = body.find(','); comma != std::string::npos; comma = body.find(',', start)) {
    fields.push_back(body.substr(start, comma - start));
    start = comma + 1;
  }
  fields.push_back(body.substr(start));
  return fields;
}

// Time (hhmmss.ss) and date of GGA, RMC (ddmmyy) and ZDA (dd, mm, yyyy) of a fix at `t`.
struct NmeaTimes {
  std::string gga_time, rmc_time, rmc_date, zda_time, zda_date;
};

NmeaTimes nmea_times(const GnssTime& t) {
  auto fix = esbc_like_fix();
  fix.time = fix.receiver_time = t;
  NmeaTimes out;
  for (const auto& s : nmea_epoch(fix)) {
    const auto f = fields_of(s);
    if (f[0] == "GNGGA") out.gga_time = f[1];
    if (f[0] == "GNRMC") {
      out.rmc_time = f[1];
      out.rmc_date = f[9];
    }
    if (f[0] == "GNZDA") {
      out.zda_time = f[1];
      out.zda_date = f[4] + "-" + f[3] + "-" + f[2];
    }
  }
  return out;
}

TEST(Nmea, TimeRoundedToHundredthsCarriesIntoMinuteHourDayMonthAndYear) {
  for (const auto& b : test::time_boundaries()) {
    const std::string next(b.next);  // UTC
    const std::string hhmmss = next.substr(11, 2) + next.substr(14, 2) + next.substr(17, 2) + ".00";
    const std::string ddmmyy = next.substr(8, 2) + next.substr(5, 2) + next.substr(2, 2);
    auto fractions = test::fractions_rounding_up(2);
    fractions.push_back(0.995);  // 59.995 s: never "60.00"
    for (const double fraction : fractions) {
      const NmeaTimes got = nmea_times(test::boundary_time(b, TimeScale::kUtc, fraction));
      EXPECT_EQ(got.gga_time, hhmmss) << b.name << ", fraction " << fraction;
      EXPECT_EQ(got.rmc_time, hhmmss) << b.name << ", fraction " << fraction;
      EXPECT_EQ(got.rmc_date, ddmmyy) << b.name << ", fraction " << fraction;
      EXPECT_EQ(got.zda_time, hhmmss) << b.name << ", fraction " << fraction;
      EXPECT_EQ(got.zda_date, next.substr(0, 10)) << b.name << ", fraction " << fraction;
    }
    const NmeaTimes below = nmea_times(test::boundary_time(b, TimeScale::kUtc, 0.994));
    EXPECT_EQ(below.gga_time.substr(4), "59.99") << b.name;
    EXPECT_EQ(below.zda_date, std::string(b.last_second).substr(0, 10)) << b.name;
  }
}

TEST(Nmea, TimeShowsSecond60OnlyInsideARealLeapSecond) {
  const GnssTime before_leap = GnssTime::parse_iso8601("2016-12-31T23:59:59", TimeScale::kUtc).value();
  NmeaTimes got = nmea_times(before_leap + 0.996);
  EXPECT_EQ(got.zda_time, "235960.00");
  EXPECT_EQ(got.zda_date, "2016-12-31");
  got = nmea_times(before_leap + 1.996);  // the end of the leap second 23:59:60
  EXPECT_EQ(got.zda_time, "000000.00");
  EXPECT_EQ(got.zda_date, "2017-01-01");
  EXPECT_EQ(got.rmc_date, "010117");
}

}  // namespace
}  // namespace skytrace::io

namespace skytrace::io {
namespace {

// RTK solutions: GGA quality 4 (fixed) or 5 (float) with the age of the corrections, RMC and VTG
// mode R or F; DGNSS quality 2 and mode D (NMEA 0183 4.11).
TEST(Nmea, RtkFixesReportTheirQualityModeAndCorrectionAge) {
  auto fix = esbc_like_fix();
  fix.relative = positioning::PositionFix::Relative{};
  fix.relative->age_s = 1.25;
  auto sentence = [&](std::string_view type) {
    std::string found;
    for (const auto& s : nmea_epoch(fix, ellipsoidal())) {
      if (s.compare(3, type.size(), type) == 0) found = s;
    }
    return found;
  };
  fix.type = positioning::FixType::kRtkFixed;
  EXPECT_NE(sentence("GGA").find(",E,4,03,0.83,58.123,M,0.000,M,1.2,*"), std::string::npos) << sentence("GGA");
  EXPECT_NE(sentence("RMC").find(",R,V*"), std::string::npos) << sentence("RMC");
  EXPECT_NE(sentence("VTG").find(",K,R*"), std::string::npos) << sentence("VTG");
  fix.type = positioning::FixType::kRtkFloat;
  EXPECT_NE(sentence("GGA").find(",E,5,03,"), std::string::npos) << sentence("GGA");
  EXPECT_NE(sentence("RMC").find(",F,V*"), std::string::npos);
  fix.type = positioning::FixType::kDgnss;
  EXPECT_NE(sentence("GGA").find(",E,2,03,"), std::string::npos);
  EXPECT_NE(sentence("VTG").find(",K,D*"), std::string::npos);
  for (const auto& s : nmea_epoch(fix)) EXPECT_TRUE(nmea_checksum_valid(s)) << s;
}

// GGA with a geoid model: altitude above mean sea level = ellipsoidal height - N, and N in the
// separation field, so that their sum (what gpsd adds up) is still the ellipsoidal height. The grid
// is EGM96 from Debian's proj-data (scripts/setup installs it).
TEST(Nmea, GgaGivesTheAltitudeAboveTheGeoidAndItsSeparation) {
  auto grid = GeoidGrid::load_gtx("/usr/share/proj/egm96_15.gtx");
  if (!grid) GTEST_SKIP() << "proj-data's EGM96 grid not installed (scripts/setup)";
  NmeaSettings with_geoid;
  with_geoid.geoid = &grid.value();
  with_geoid.gsa = with_geoid.gsv = with_geoid.rmc = with_geoid.vtg = with_geoid.zda = with_geoid.gst = false;
  const auto fix = esbc_like_fix();  // 55.46 N 8.46 E, 58.123 m above the ellipsoid
  const std::string gga = nmea_epoch(fix, with_geoid).at(0);
  std::vector<std::string> f;
  for (std::stringstream fields(gga); std::getline(fields, f.emplace_back(), ',');) {}
  const double n_m = grid.value().undulation_m(fix.position.latitude_deg, fix.position.longitude_deg);
  EXPECT_GT(n_m, 38.0);  // EGM96 in western Denmark: about 40 m
  EXPECT_LT(n_m, 43.0);
  EXPECT_EQ(f[10], "M");
  EXPECT_NEAR(std::stod(f[11]), n_m, 0.0005) << gga;
  EXPECT_NEAR(std::stod(f[9]), 58.123 - n_m, 0.0011) << gga;
  EXPECT_NEAR(std::stod(f[9]) + std::stod(f[11]), 58.123, 0.0011) << gga;
  EXPECT_TRUE(nmea_checksum_valid(gga)) << gga;
}

}  // namespace
}  // namespace skytrace::io
