// The readers accept every code and record the RINEX versions define (observation types X and I,
// RINEX 2 bands 5-8 and BeiDou, RINEX 4.0x navigation records and messages), note the ones
// skytrace does not use once per file, and refuse only malformed input, naming file and line.
#include <gtest/gtest.h>

#include <string>

#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/rinex_nav.hpp"

namespace skytrace {
namespace {

// RINEX 3.04 as sbf2rin writes it: channel numbers X1 last, GPS also ionosphere delay I1; three
// epochs, so that a note per line would show.
constexpr const char* kObs304WithChannels =
    "     3.04           OBSERVATION DATA    M                   RINEX VERSION / TYPE\n"
    "G    4 C1C L1C S1C X1                                       SYS / # / OBS TYPES\n"
    "E    3 C1C C6A X1                                           SYS / # / OBS TYPES\n"
    "R    2 C4A X1                                               SYS / # / OBS TYPES\n"
    "  2020     6    25     0     0    0.0000000     GPS         TIME OF FIRST OBS\n"
    "                                                            END OF HEADER\n"
    "> 2020 06 25 00 00  0.0000000  0  3\n"
    "G05  21600712.022   113512506.876 7        44.000           3.000\n"
    "E11  25600712.022    25600713.022          12.000\n"
    "R07  20600712.022           5.000\n"
    "> 2020 06 25 00 00 30.0000000  0  1\n"
    "G05  21600812.022   113513506.876 7        44.000           3.000\n"
    "> 2020 06 25 00 01  0.0000000  0  1\n"
    "G05  21600912.022   113514506.876 7        44.000           3.000\n";

TEST(RinexDefinedCodes, ChannelNumbersAreReadAndNotedOncePerFile) {
  auto read = io::parse_rinex_obs("sbf2rin.rnx", kObs304WithChannels);
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_EQ(read->epochs.size(), 3u);
  const auto x1 = read->header.type_index(GnssSystem::kGps, "X1");
  ASSERT_TRUE(x1.has_value());
  EXPECT_EQ(read->header.observation_types.at(GnssSystem::kGps)[*x1].kind(), 'X');
  EXPECT_EQ(read->epochs[0].satellites[0].values[*x1].value, 3.0);
  EXPECT_EQ(read->epochs[0].satellites[0].values[0].value, 21600712.022);
  ASSERT_EQ(read->warnings.size(), 1u);
  const std::string& note = read->warnings[0];
  EXPECT_NE(note.find("sbf2rin.rnx"), std::string::npos) << note;
  EXPECT_NE(note.find("G: X1"), std::string::npos) << note;
  EXPECT_NE(note.find("R: X1"), std::string::npos) << note;
  EXPECT_EQ(note.find("C6A"), std::string::npos) << note;  // Galileo E6 PRS is catalogued
  EXPECT_EQ(note.find("C4A"), std::string::npos) << note;  // GLONASS L1OC is catalogued
}

TEST(RinexDefinedCodes, ChannelNumbersInEveryVersionFromThreeOhTwo) {
  for (const char* version : {"3.02", "3.03", "3.05", "4.00", "4.01", "4.02"}) {
    std::string text = kObs304WithChannels;
    text.replace(5, 4, version);
    auto read = io::parse_rinex_obs("v.rnx", text);
    ASSERT_TRUE(read.ok()) << version << ": " << read.error().message;
    EXPECT_EQ(read->epochs.size(), 3u) << version;
    EXPECT_EQ(read->warnings.size(), 1u) << version;
  }
}

TEST(RinexDefinedCodes, IonosphereAndUnknownSignalsAreNotedNotRefused) {
  std::string text = kObs304WithChannels;
  text.replace(text.find("G    4 C1C L1C S1C X1 "), 22, "G    4 C1C L1C S1C I1 ");
  text.replace(text.find("E    3 C1C C6A X1 "), 18, "E    3 C1C C6A C9Z ");  // a band Galileo has not (yet)
  auto read = io::parse_rinex_obs("future.rnx", text);
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_EQ(read->warnings.size(), 1u);
  EXPECT_NE(read->warnings[0].find("G: I1"), std::string::npos) << read->warnings[0];
  EXPECT_NE(read->warnings[0].find("E: C9Z"), std::string::npos) << read->warnings[0];
}

TEST(RinexDefinedCodes, MalformedCodesAreRefusedWithFileLineAndExpectation) {
  for (const char* bad : {"C1 ", "Q1C", "CAC", "C1c"}) {
    std::string text = kObs304WithChannels;
    text.replace(text.find("C1C L1C S1C X1"), 3, bad);
    auto read = io::parse_rinex_obs("bad.rnx", text);
    ASSERT_FALSE(read.ok()) << bad;
    EXPECT_NE(read.error().message.find("bad.rnx:2"), std::string::npos) << read.error().message;
    EXPECT_NE(read.error().message.find("expected"), std::string::npos) << read.error().message;
  }
}

TEST(RinexDefinedCodes, BeiDouB1InBandOneOfEarlyVersionsIsB1I) {
  const std::string text =
      "     3.02           OBSERVATION DATA    C                   RINEX VERSION / TYPE\n"
      "C    2 C1I L1I                                              SYS / # / OBS TYPES\n"
      "  2016     6     6     0     0    0.0000000     BDT         TIME OF FIRST OBS\n"
      "                                                            END OF HEADER\n"
      "> 2016 06 06 00 00  0.0000000  0  1\n"
      "C07  38600712.022   201000000.123\n";
  auto read = io::parse_rinex_obs("bds302.rnx", text);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_TRUE(read->header.type_index(GnssSystem::kBeiDou, "C2I").has_value());
  EXPECT_TRUE(read->warnings.empty());
}

// RINEX 2.11 with the band-5/7/8 types and Transit Doppler, GPS, GLONASS, Galileo and BeiDou.
constexpr const char* kObs211 =
    "     2.11           OBSERVATION DATA    M (MIXED)           RINEX VERSION / TYPE\n"
    "     8    C1    P1    L1    D1    C5    L7    S8    T1      # / TYPES OF OBSERV\n"
    "  2021     4    28    19     0    0.0000000     GPS         TIME OF FIRST OBS\n"
    "                                                            END OF HEADER\n"
    " 21  4 28 19  0  0.0000000  0  3G15R07C07\n"
    "  23332073.875    23332074.105   122610995.213       -1234.500    23332075.000\n"
    "\n"
    "  22332073.875\n"
    "\n"
    "  33332073.875\n"
    "                        42.000\n";

TEST(RinexDefinedCodes, Rinex2TypesOfAllBandsAndSystems) {
  auto read = io::parse_rinex_obs("mixed.21o", kObs211);
  ASSERT_TRUE(read.ok()) << read.error().message;
  const auto& h = read->header;
  EXPECT_TRUE(h.type_index(GnssSystem::kGps, "C5X").has_value());
  EXPECT_TRUE(h.type_index(GnssSystem::kGps, "C1W").has_value());  // P1
  EXPECT_TRUE(h.type_index(GnssSystem::kBeiDou, "C2I").has_value());
  EXPECT_TRUE(h.type_index(GnssSystem::kBeiDou, "L7I").has_value());
  ASSERT_EQ(read->epochs.size(), 1u);
  EXPECT_EQ(read->epochs[0].satellites[0].values[4].value, 23332075.0);  // G15 C5
  ASSERT_EQ(read->warnings.size(), 1u);
  const std::string& note = read->warnings[0];
  EXPECT_NE(note.find("T1"), std::string::npos) << note;  // Transit Doppler: no RINEX 3 code
  EXPECT_NE(note.find("R: "), std::string::npos) << note;  // GLONASS has no band 5, 7 or 8
}

TEST(RinexDefinedCodes, Rinex2MalformedTypeIsRefused) {
  std::string text = kObs211;
  text.replace(text.find("    T1"), 6, "    Q1");
  auto read = io::parse_rinex_obs("mixed.21o", text);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().message.find("mixed.21o:2"), std::string::npos) << read.error().message;
  EXPECT_NE(read.error().message.find("'Q1'"), std::string::npos) << read.error().message;
}

// RINEX 4.02: a GPS LNAV record, then records of kinds skytrace does not use.
constexpr const char* kNav402 =
    "     4.02           N: GNSS NAV DATA    M: MIXED            RINEX VERSION / TYPE\n"
    "    18                                                      LEAP SECONDS\n"
    "                                                            END OF HEADER\n"
    "> EPH G05 LNAV\n"
    "G05 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
    "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01\n"
    "    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03\n"
    "     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07\n"
    "     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09\n"
    "    -5.714523747137E-11 1.000000000000E+00 2.111000000000E+03 0.000000000000E+00\n"
    "     2.000000000000E+00 0.000000000000E+00 5.122274160385E-09 5.800000000000E+01\n"
    "     3.561060000000E+05 4.000000000000E+00\n"
    "> EPH R01 L1OC\n"
    "R01 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
    "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01\n"
    "> EPH R02 L1OC\n"
    "R02 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
    "> EPH I02 L1NV\n"
    "I02 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
    "> EOP G05 CNVX\n"
    "    2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
    "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09\n"
    "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09\n"
    "> ION C01 CNVX\n"
    "    2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n";

TEST(RinexDefinedRecords, Rinex4UnusedRecordsAreSkippedWithOneNote) {
  auto read = orbits::parse_rinex_nav("BRD400DLR.rnx", kNav402);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->kepler.size(), 1u);
  ASSERT_EQ(read->warnings.size(), 1u);
  const std::string& note = read->warnings[0];
  EXPECT_NE(note.find("BRD400DLR.rnx"), std::string::npos) << note;
  EXPECT_NE(note.find("EPH GLONASS L1OC (2)"), std::string::npos) << note;
  EXPECT_NE(note.find("EPH NavIC L1NV (1)"), std::string::npos) << note;
  EXPECT_NE(note.find("EOP records (1)"), std::string::npos) << note;
  EXPECT_NE(note.find("ION BeiDou CNVX (1)"), std::string::npos) << note;
}

TEST(RinexDefinedRecords, Rinex4MalformedRecordNamesFileAndLine) {
  std::string text = kNav402;
  text.replace(text.find("     3.600000000000E+05-1.508742570877E-07"), 23, "     3.6000000000x0E+05");
  auto read = orbits::parse_rinex_nav("BRD400DLR.rnx", text);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().message.find("BRD400DLR.rnx:8"), std::string::npos) << read.error().message;
  EXPECT_NE(read.error().message.find("Toe"), std::string::npos) << read.error().message;
  const std::string full = kNav402;
  const std::string eop = "> EOP G05 CNVX";
  const size_t at = full.find(eop);
  const std::string without_type = full.substr(0, at) + '>' + full.substr(at + eop.size());
  auto no_type = orbits::parse_rinex_nav("BRD400DLR.rnx", without_type);
  ASSERT_FALSE(no_type.ok());
  EXPECT_NE(no_type.error().message.find("BRD400DLR.rnx:"), std::string::npos) << no_type.error().message;
}

}  // namespace
}  // namespace skytrace
