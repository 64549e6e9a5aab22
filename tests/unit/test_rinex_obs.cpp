// RINEX observation writer and reader: exact layout, round trips, overflow and the atomic file.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"
#include "time_boundaries.hpp"

namespace skytrace::io {
namespace {

std::string read_all(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  std::string line;
  while (std::getline(ss, line)) lines.push_back(line);
  return lines;
}

size_t count_entries(const std::filesystem::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

ObservationType type(const char* code) { return ObservationType{code, {}}; }

// A GPS + GLONASS header as the simulator would fill it.
ObservationHeader two_system_header(double version) {
  ObservationHeader h;
  h.version = version;
  h.program = "skytrace 0.1";
  h.run_by = "unit test";
  h.date = "20200625 000000 UTC";
  h.comments = {"simulated observations", "second comment line"};
  h.marker_name = "SIM1";
  h.marker_number = "00001";
  h.marker_type = "GROUND_CRAFT";
  h.observer = "robot";
  h.agency = "skytrace";
  h.receiver_number = "0001";
  h.receiver_type = "SKYTRACE SIM";
  h.receiver_version = "0.1";
  h.antenna_number = "A1";
  h.antenna_type = "SIMANT          NONE";
  h.approx_position_ecef_m = std::array<double, 3>{3582105.2910, 532589.7313, 5232754.8054};
  h.antenna_delta_hen_m = {0.2160, 0.0010, -0.0020};
  h.observation_types[GnssSystem::kGps] = {type("C1C"), type("L1C"), type("D1C"), type("S1C"),
                                           type("C2W"), type("L2W")};
  h.observation_types[GnssSystem::kGlonass] = {type("C1C"), type("L1C"), type("D1C"), type("S1C")};
  h.signal_strength_unit = "DBHZ";
  h.leap_seconds = 18;
  h.glonass_slots = {{1, 1}, {2, -4}, {3, 5}, {4, 6}, {5, 1}, {6, -4}, {7, 5}, {8, 6}, {9, -2}, {10, -7}};
  return h;
}

const GnssTime kT0 = GnssTime::from_calendar(CalendarTime{2020, 6, 25, 0, 0, 0.0}, TimeScale::kGpst);

ObservationValue val(double v, std::uint8_t lli = 0, std::uint8_t ssi = 0) { return ObservationValue{v, lli, ssi}; }

std::vector<ObservationEpoch> sample_epochs() {
  std::vector<ObservationEpoch> epochs;
  for (int k = 0; k < 3; ++k) {
    ObservationEpoch e;
    e.time = kT0 + 30.0 * k + (k == 2 ? 0.25 : 0.0);
    if (k == 1) e.receiver_clock_offset_s = -1.234567890123e-4;
    // Deliberately unsorted: the writer sorts.
    e.satellites.push_back({SatelliteId{GnssSystem::kGlonass, 10},
                            {val(19922497.560 + k, 0, 8), val(106310300.891 + k, 1, 8), val(2141.240, 0, 8),
                             val(51.750)}});
    e.satellites.push_back({SatelliteId{GnssSystem::kGps, 5},
                            {val(20947300.931 + k, 0, 8), val(110078924.573 - k, 5, 8), val(-1037.205),
                             val(48.25), val(20947301.155), val(85775775.123, 0, 7)}});
    // Missing entries: blank C2W/L2W (shorter vector) and a blank L1C value carrying an LLI.
    e.satellites.push_back({SatelliteId{GnssSystem::kGps, 2},
                            {val(25847357.745, 0, 3), ObservationValue{std::nullopt, 1, 0}, val(-3123.088, 0, 3),
                             val(20.5)}});
    e.satellites.push_back({SatelliteId{GnssSystem::kGlonass, 1},
                            {val(-0.0004), ObservationValue{}, val(-0.920, 0, 6), val(45.0, 0, 9)}});
    epochs.push_back(e);
  }
  return epochs;
}

// ------------------------------------------------------------------ number formatting
TEST(RinexObsFormat, F14_3MatchesPrintfAndNeverOverflows) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-4, 8);
  size_t compared = 0, mismatched = 0;
  char ours[15] = {};
  char theirs[64];
  for (int i = 0; i < 200000; ++i) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng)) * 9.99;
    if (std::fabs(v) < 0.0005) continue;  // printf writes "-0.000" there, we write "0.000"
    ASSERT_TRUE(detail::format_f14_3(v, ours)) << v;
    std::snprintf(theirs, sizeof theirs, "%14.3f", v);
    ++compared;
    if (std::string(ours, 14) != theirs) {
      ++mismatched;
      // Only a tie broken differently may differ: one unit in the last digit.
      EXPECT_NEAR(std::stod(std::string(ours, 14)), v, 0.0005 + 1e-9) << theirs;
    }
  }
  EXPECT_GT(compared, 150000u);
  EXPECT_LE(mismatched, compared / 10000) << "values rounded differently from printf";

  const auto f = [](double v) {
    char buf[15] = {};
    if (!detail::format_f14_3(v, buf)) return std::string("<none>");
    return std::string(buf, 14);
  };
  EXPECT_EQ(f(0.0), "         0.000");
  EXPECT_EQ(f(-0.0004), "         0.000");
  EXPECT_EQ(f(-0.92), "        -0.920");
  EXPECT_EQ(f(0.0005), "         0.001");
  EXPECT_EQ(f(40715949.461), "  40715949.461");
  EXPECT_EQ(f(999999999.999), " 999999999.999");
  EXPECT_EQ(f(-999999999.999), "-999999999.999");
  EXPECT_EQ(f(999999999.9996), "<none>");  // would round to 1e9: ten digits
  EXPECT_EQ(f(2.6e9), "<none>");
  EXPECT_EQ(f(std::nan("")), "<none>");
  EXPECT_EQ(f(INFINITY), "<none>");
}

// ------------------------------------------------------------------ writer layout
TEST(RinexObsWriter, Exact304Layout) {
  const auto dir = test::make_temp_dir("rinex_obs_layout");
  const auto path = dir / "SIM1.rnx";
  ASSERT_TRUE(write_rinex_obs(path, two_system_header(3.04), sample_epochs()).ok());
  const auto lines = split_lines(read_all(path));
  ASSERT_GT(lines.size(), 20u);
  EXPECT_EQ(lines[0], "     3.04           OBSERVATION DATA    M                   RINEX VERSION / TYPE");
  size_t end_of_header = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].find("END OF HEADER") != std::string::npos) {
      end_of_header = i;
      break;
    }
    EXPECT_LE(lines[i].size(), 80u) << lines[i];
    EXPECT_GT(lines[i].size(), 60u) << lines[i];  // every header line has its label at column 61
  }
  ASSERT_GT(end_of_header, 0u);
  const std::string header_text = read_all(path).substr(0, read_all(path).find("END OF HEADER"));
  EXPECT_NE(header_text.find("G    6 C1C L1C D1C S1C C2W L2W                              SYS / # / OBS TYPES"),
            std::string::npos);
  EXPECT_NE(header_text.find("R    4 C1C L1C D1C S1C                                      SYS / # / OBS TYPES"),
            std::string::npos);
  EXPECT_NE(header_text.find("  2020     6    25     0     0    0.0000000     GPS         TIME OF FIRST OBS"),
            std::string::npos);
  EXPECT_NE(header_text.find("  2020     6    25     0     1    0.2500000     GPS         TIME OF LAST OBS"),
            std::string::npos);
  EXPECT_NE(header_text.find("    30.000                                                  INTERVAL"),
            std::string::npos);
  EXPECT_NE(header_text.find("G L1C  0.00000                                              SYS / PHASE SHIFT"),
            std::string::npos);
  EXPECT_NE(header_text.find("G L2W  0.00000                                              SYS / PHASE SHIFT"),
            std::string::npos);
  EXPECT_NE(header_text.find("R L1C  0.00000                                              SYS / PHASE SHIFT"),
            std::string::npos);
  EXPECT_NE(header_text.find(" 10 R01  1 R02 -4 R03  5 R04  6 R05  1 R06 -4 R07  5 R08  6 GLONASS SLOT / FRQ #\n"
                             "    R09 -2 R10 -7                                           GLONASS SLOT / FRQ #"),
            std::string::npos);
  EXPECT_NE(header_text.find(" C1C          C1P          C2C          C2P                 GLONASS COD/PHS/BIS"),
            std::string::npos);
  EXPECT_NE(header_text.find("  3582105.2910   532589.7313  5232754.8054                  APPROX POSITION XYZ"),
            std::string::npos);

  // Body: epoch line and satellites sorted G02, G05, R01, R10; F14.3 + LLI + SSI per value.
  ASSERT_GE(lines.size(), end_of_header + 6);
  EXPECT_EQ(lines[end_of_header + 1], "> 2020 06 25 00 00  0.0000000  0  4");
  EXPECT_EQ(lines[end_of_header + 2],
            "G02  25847357.745 3              1      -3123.088 3        20.500");
  EXPECT_EQ(lines[end_of_header + 3],
            "G05  20947300.931 8 110078924.57358     -1037.205          48.250    20947301.155    85775775.123 7");
  EXPECT_EQ(lines[end_of_header + 4], "R01         0.000                          -0.920 6        45.000 9");
  EXPECT_EQ(lines[end_of_header + 5],
            "R10  19922497.560 8 106310300.89118      2141.240 8        51.750");
  EXPECT_EQ(lines[end_of_header + 6], "> 2020 06 25 00 00 30.0000000  0  4      -0.000123456789");
  EXPECT_EQ(lines[end_of_header + 11], "> 2020 06 25 00 01  0.2500000  0  4");
}

TEST(RinexObsWriter, Version400HeaderDropsDeprecatedRecords) {
  const auto dir = test::make_temp_dir("rinex_obs_v4");
  const auto path = dir / "SIM1_v4.rnx";
  ASSERT_TRUE(write_rinex_obs(path, two_system_header(4.00), sample_epochs()).ok());
  const std::string text = read_all(path);
  EXPECT_EQ(text.substr(0, 81), "     4.00           OBSERVATION DATA    M                   RINEX VERSION / TYPE\n");
  // RINEX 4.00 Table A2: SYS / PHASE SHIFT and GLONASS COD/PHS/BIS are deprecated.
  EXPECT_EQ(text.find("SYS / PHASE SHIFT"), std::string::npos);
  EXPECT_EQ(text.find("GLONASS COD/PHS/BIS"), std::string::npos);
  EXPECT_NE(text.find("GLONASS SLOT / FRQ #"), std::string::npos);
  EXPECT_NE(text.find("> 2020 06 25 00 00  0.0000000  0  4\n"), std::string::npos);
}

// ------------------------------------------------------------------ round trips
class RinexObsRoundTrip : public ::testing::TestWithParam<double> {};

TEST_P(RinexObsRoundTrip, EveryValueAndFlagAndHeaderField) {
  const double version = GetParam();
  const auto dir = test::make_temp_dir("rinex_obs_round_trip_" + std::to_string(static_cast<int>(version * 100)));
  const auto path = dir / "round.rnx";
  const ObservationHeader header = two_system_header(version);
  const auto epochs = sample_epochs();
  ASSERT_TRUE(write_rinex_obs(path, header, epochs).ok());

  auto read = read_rinex_obs(path);
  ASSERT_TRUE(read.ok()) << read.error().message;
  const ObservationHeader& h = read->header;
  EXPECT_NEAR(h.version, version, 1e-9);
  EXPECT_FALSE(h.file_system.has_value());  // mixed
  EXPECT_EQ(h.program, header.program);
  EXPECT_EQ(h.run_by, header.run_by);
  EXPECT_EQ(h.date, header.date);
  EXPECT_EQ(h.comments, header.comments);
  EXPECT_EQ(h.marker_name, header.marker_name);
  EXPECT_EQ(h.marker_number, header.marker_number);
  EXPECT_EQ(h.marker_type, header.marker_type);
  EXPECT_EQ(h.observer, header.observer);
  EXPECT_EQ(h.agency, header.agency);
  EXPECT_EQ(h.receiver_number, header.receiver_number);
  EXPECT_EQ(h.receiver_type, header.receiver_type);
  EXPECT_EQ(h.receiver_version, header.receiver_version);
  EXPECT_EQ(h.antenna_number, header.antenna_number);
  EXPECT_EQ(h.antenna_type, header.antenna_type);
  ASSERT_TRUE(h.approx_position_ecef_m.has_value());
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR((*h.approx_position_ecef_m)[k], (*header.approx_position_ecef_m)[k], 1e-4);
    EXPECT_NEAR(h.antenna_delta_hen_m[k], header.antenna_delta_hen_m[k], 1e-4);
  }
  EXPECT_EQ(h.observation_types, header.observation_types);
  EXPECT_EQ(h.signal_strength_unit, "DBHZ");
  ASSERT_TRUE(h.interval_s.has_value());
  EXPECT_DOUBLE_EQ(*h.interval_s, 30.0);
  EXPECT_EQ(h.time_system, TimeScale::kGpst);
  ASSERT_TRUE(h.time_of_first_obs && h.time_of_last_obs);
  EXPECT_NEAR(*h.time_of_first_obs - epochs.front().time, 0.0, 1e-9);
  EXPECT_NEAR(*h.time_of_last_obs - epochs.back().time, 0.0, 1e-9);
  EXPECT_EQ(h.leap_seconds, 18);
  EXPECT_EQ(h.glonass_slots, header.glonass_slots);
  if (version < 4.0) {
    EXPECT_EQ(h.phase_shifts.size(), 3u);  // G L1C, G L2W, R L1C
    for (const auto& p : h.phase_shifts) {
      EXPECT_EQ(p.code[0], 'L');
      EXPECT_EQ(p.shift_cycles, 0.0);
      EXPECT_TRUE(p.satellites.empty());
    }
    EXPECT_EQ(h.glonass_code_phase_biases.size(), 4u);
  } else {
    EXPECT_TRUE(h.phase_shifts.empty());
    EXPECT_TRUE(h.glonass_code_phase_biases.empty());
  }

  ASSERT_EQ(read->epochs.size(), epochs.size());
  for (size_t e = 0; e < epochs.size(); ++e) {
    const auto& got = read->epochs[e];
    const auto& want = epochs[e];
    EXPECT_NEAR(got.time - want.time, 0.0, 1e-9) << "epoch " << e;
    EXPECT_EQ(got.flag, EpochFlag::kOk);
    ASSERT_EQ(got.receiver_clock_offset_s.has_value(), want.receiver_clock_offset_s.has_value());
    if (want.receiver_clock_offset_s) {
      EXPECT_NEAR(*got.receiver_clock_offset_s, *want.receiver_clock_offset_s, 5e-13);
    }
    ASSERT_EQ(got.satellites.size(), want.satellites.size());
    for (size_t k = 1; k < got.satellites.size(); ++k) {
      EXPECT_LT(got.satellites[k - 1].satellite, got.satellites[k].satellite) << "satellites sorted";
    }
    for (const auto& w : want.satellites) {
      const auto* g = got.find(w.satellite);
      ASSERT_NE(g, nullptr) << w.satellite.to_string();
      const size_t ntypes = header.observation_types.at(w.satellite.system).size();
      ASSERT_EQ(g->values.size(), ntypes);
      for (size_t t = 0; t < ntypes; ++t) {
        const ObservationValue expected = t < w.values.size() ? w.values[t] : ObservationValue{};
        const ObservationValue& actual = g->values[t];
        SCOPED_TRACE(w.satellite.to_string() + " type " + std::to_string(t) + " epoch " + std::to_string(e));
        ASSERT_EQ(actual.value.has_value(), expected.value.has_value());
        if (expected.value) {
          EXPECT_NEAR(*actual.value, *expected.value, 0.5e-3 + 1e-9);
        }
        EXPECT_EQ(actual.lli, expected.lli);
        EXPECT_EQ(actual.ssi, expected.ssi);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Versions, RinexObsRoundTrip, ::testing::Values(3.04, 4.00));

// RINEX's GLO time system tags epochs in UTC(SU) (RINEX 3.04 Table A2: "GLO (=UTC time system)";
// GNSS-SDR and RTKLIB read and write it so), not in GLONASS system time.
TEST(RinexObsWriter, GlonassTimeSystemEpochsAreUtc) {
  const auto dir = test::make_temp_dir("rinex_obs_glo_time");
  const auto path = dir / "glo.rnx";
  ObservationHeader h = two_system_header(3.04);
  h.observation_types.erase(GnssSystem::kGps);
  h.time_system = TimeScale::kUtc;
  ObservationEpoch e;
  e.time = kT0;  // 2020-06-25 00:00:00 GPST = 2020-06-24 23:59:42 UTC (GPS-UTC = 18 s)
  e.satellites.push_back({SatelliteId{GnssSystem::kGlonass, 1}, {val(20000000.0)}});
  ASSERT_TRUE(write_rinex_obs(path, h, {e}).ok());
  const std::string text = read_all(path);
  EXPECT_NE(text.find("> 2020 06 24 23 59 42.0000000  0  1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("  2020     6    24    23    59   42.0000000     GLO         TIME OF FIRST OBS"),
            std::string::npos);
  EXPECT_NE(text.find("     3.04           OBSERVATION DATA    R"), std::string::npos);
  auto read = read_rinex_obs(path);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->header.time_system, TimeScale::kUtc);
  ASSERT_EQ(read->epochs.size(), 1u);
  EXPECT_NEAR(read->epochs[0].time - kT0, 0.0, 1e-9);
}

// ------------------------------------------------------------------ epochs at boundaries
// "YYYY-MM-DDThh:mm:ss" as the epoch line writes it ("> 2024 05 03 00 00  0.0000000").
std::string epoch_line_prefix(const std::string& iso) {
  return "> " + iso.substr(0, 4) + " " + iso.substr(5, 2) + " " + iso.substr(8, 2) + " " + iso.substr(11, 2) + " " +
         iso.substr(14, 2) + " " + (iso[17] == '0' ? std::string(" ") + iso[18] : iso.substr(17, 2)) + ".0000000  0  1";
}

// "YYYY-MM-DDThh:mm:ss" as TIME OF FIRST OBS writes it (5I6, F13.7).
std::string header_time(const std::string& iso) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%6d%6d%6d%6d%6d%13.7f", std::stoi(iso.substr(0, 4)), std::stoi(iso.substr(5, 2)),
                std::stoi(iso.substr(8, 2)), std::stoi(iso.substr(11, 2)), std::stoi(iso.substr(14, 2)),
                std::stod(iso.substr(17, 2)));
  return buf;
}

TEST(RinexObsWriter, EpochRoundedToF11_7CarriesIntoMinuteHourDayMonthYearAndWeek) {
  const auto dir = test::make_temp_dir("rinex_obs_boundaries");
  for (const TimeScale scale : {TimeScale::kGpst, TimeScale::kUtc}) {
    for (const double fraction : test::fractions_rounding_up(7)) {
      ObservationHeader h = two_system_header(3.04);
      if (scale == TimeScale::kUtc) h.observation_types.erase(GnssSystem::kGps);
      h.time_system = scale;
      std::vector<ObservationEpoch> epochs;
      for (const auto& b : test::time_boundaries()) {
        ObservationEpoch e;
        e.time = test::boundary_time(b, scale, fraction);
        e.satellites.push_back({SatelliteId{GnssSystem::kGlonass, 1}, {val(20000000.0)}});
        epochs.push_back(e);
      }
      const auto path = dir / "boundaries.rnx";
      ASSERT_TRUE(write_rinex_obs(path, h, epochs).ok());
      const std::string text = read_all(path);
      for (const auto& b : test::time_boundaries()) {
        EXPECT_NE(text.find(epoch_line_prefix(b.next) + "\n"), std::string::npos)
            << b.name << ", " << to_string(scale) << ", fraction 1 - " << 1.0 - fraction << ": expected "
            << epoch_line_prefix(b.next);
      }
      EXPECT_EQ(text.find(" 60.0000000"), std::string::npos) << text;
      const auto& boundaries = test::time_boundaries();
      EXPECT_NE(text.find(header_time(boundaries.front().next) + "     " + (scale == TimeScale::kGpst ? "GPS" : "GLO") +
                          "         TIME OF FIRST OBS"),
                std::string::npos);
      EXPECT_NE(text.find(header_time(boundaries.back().next) + "     " + (scale == TimeScale::kGpst ? "GPS" : "GLO") +
                          "         TIME OF LAST OBS"),
                std::string::npos);
    }
  }
}

TEST(RinexObsWriter, EpochInsideTheLeapSecondKeepsSecond60InGloTime) {
  // GLO time tags are UTC: 2016-12-31T23:59:60 is real; just before it rounds into it, just before
  // its end rounds into 2017-01-01 00:00:00.
  const auto dir = test::make_temp_dir("rinex_obs_leap");
  ObservationHeader h = two_system_header(3.04);
  h.observation_types.erase(GnssSystem::kGps);
  h.time_system = TimeScale::kUtc;
  const GnssTime leap = GnssTime::parse_iso8601("2016-12-31T23:59:60", TimeScale::kUtc).value();
  std::vector<ObservationEpoch> epochs(2);
  epochs[0].time = leap - 1.0 + (1.0 - 4e-8);
  epochs[1].time = leap + (1.0 - 4e-8);
  for (auto& e : epochs) e.satellites.push_back({SatelliteId{GnssSystem::kGlonass, 1}, {val(20000000.0)}});
  const auto path = dir / "leap.rnx";
  ASSERT_TRUE(write_rinex_obs(path, h, epochs).ok());
  const std::string text = read_all(path);
  EXPECT_NE(text.find("> 2016 12 31 23 59 60.0000000  0  1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("> 2017 01 01 00 00  0.0000000  0  1\n"), std::string::npos) << text;
}

// ------------------------------------------------------------------ overflow
TEST(RinexObsWriter, PhaseTooLargeForTheFieldIsAnErrorOrOmitted) {
  const auto dir = test::make_temp_dir("rinex_obs_overflow");
  ObservationEpoch bad;
  bad.time = kT0;
  bad.satellites.push_back({SatelliteId{GnssSystem::kGps, 7}, {val(21000000.0), val(1.2e9, 0, 7), val(100.0)}});
  ObservationEpoch good = bad;
  good.time = kT0 + 1.0;
  good.satellites[0].values[1] = val(1.2e8, 0, 7);

  {
    RinexObsWriter writer;
    ASSERT_TRUE(writer.open(dir / "strict.rnx", two_system_header(3.04)).ok());
    const Status s = writer.write_epoch(bad);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::kOutOfRange);
    EXPECT_NE(s.error().message.find("G07 L1C"), std::string::npos) << s.error().message;
    EXPECT_NE(s.error().message.find("2020-06-25T00:00:00"), std::string::npos) << s.error().message;
    // The failed epoch left nothing behind: the file holds only the good one.
    ASSERT_TRUE(writer.write_epoch(good).ok());
    ASSERT_TRUE(writer.finish().ok());
    auto read = read_rinex_obs(dir / "strict.rnx");
    ASSERT_TRUE(read.ok()) << read.error().message;
    ASSERT_EQ(read->epochs.size(), 1u);
    EXPECT_NEAR(*read->epochs[0].satellites[0].values[1].value, 1.2e8, 1e-3);
  }
  {
    RinexObsWriterOptions options;
    options.omit_unrepresentable_values = true;
    RinexObsWriter writer;
    ASSERT_TRUE(writer.open(dir / "lenient.rnx", two_system_header(3.04), options).ok());
    ASSERT_TRUE(writer.write_epoch(bad).ok());
    EXPECT_EQ(writer.omitted_value_count(), 1u);
    ASSERT_TRUE(writer.finish().ok());
    const auto lines = split_lines(read_all(dir / "lenient.rnx"));
    // The columns of the neighbours are intact: blank 16-column field between C1C and D1C.
    EXPECT_EQ(lines.back(), "G07  21000000.000                         100.000");
    auto read = read_rinex_obs(dir / "lenient.rnx");
    ASSERT_TRUE(read.ok()) << read.error().message;
    const auto& values = read->epochs[0].satellites[0].values;
    EXPECT_FALSE(values[1].value.has_value());
    EXPECT_NEAR(*values[2].value, 100.0, 1e-9);
  }
}

// ------------------------------------------------------------------ atomic output
TEST(RinexObsWriter, FileAppearsOnlyAtFinish) {
  const auto dir = test::make_temp_dir("rinex_obs_atomic");
  const auto path = dir / "out.rnx";
  RinexObsWriter writer;
  ASSERT_TRUE(writer.open(path, two_system_header(3.04)).ok());
  for (const auto& e : sample_epochs()) {
    ASSERT_TRUE(writer.write_epoch(e).ok());
    EXPECT_FALSE(std::filesystem::exists(path));
  }
  EXPECT_EQ(writer.epoch_count(), 3u);
  EXPECT_EQ(count_entries(dir), 1u);  // the body temporary
  ASSERT_TRUE(writer.finish().ok());
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_EQ(count_entries(dir), 1u);  // only the final file: temporaries removed
  EXPECT_FALSE(writer.is_open());
  EXPECT_FALSE(writer.write_epoch(sample_epochs()[0]).ok());
  EXPECT_FALSE(writer.finish().ok());
}

// A header written before the body from the expected span: the same bytes whether the epochs
// confirm it (the body file is renamed) or not (the final header replaces it), and no temporaries.
TEST(RinexObsWriter, ExpectedSpanGivesTheSameBytesConfirmedOrNot) {
  const auto dir = test::make_temp_dir("rinex_obs_expected");
  const auto write = [&](const std::string& name, RinexObsWriterOptions options) {
    RinexObsWriter writer;
    EXPECT_TRUE(writer.open(dir / name, two_system_header(3.04), options).ok());
    for (const auto& e : sample_epochs()) EXPECT_TRUE(writer.write_epoch(e).ok());
    EXPECT_TRUE(writer.finish().ok());
    return read_all(dir / name);
  };
  const std::vector<ObservationEpoch> epochs = sample_epochs();
  const std::string plain = write("plain.rnx", {});
  RinexObsWriterOptions confirmed;
  confirmed.expected_first_obs = epochs.front().time;
  confirmed.expected_last_obs = epochs.back().time;
  confirmed.expected_interval_s = epochs[1].time - epochs[0].time;
  EXPECT_EQ(write("confirmed.rnx", confirmed), plain);
  RinexObsWriterOptions wrong = confirmed;
  wrong.expected_last_obs = epochs.back().time + 3600.0;  // the run stopped early
  EXPECT_EQ(write("wrong_end.rnx", wrong), plain);
  RinexObsWriterOptions wrong_interval = confirmed;
  wrong_interval.expected_interval_s = 0.5;
  EXPECT_EQ(write("wrong_interval.rnx", wrong_interval), plain);
  EXPECT_EQ(count_entries(dir), 4u);  // the four files, no temporaries
}

TEST(RinexObsWriter, DestroyedWithoutFinishLeavesNothing) {
  const auto dir = test::make_temp_dir("rinex_obs_abandon");
  {
    RinexObsWriter writer;
    ASSERT_TRUE(writer.open(dir / "never.rnx", two_system_header(3.04)).ok());
    for (const auto& e : sample_epochs()) ASSERT_TRUE(writer.write_epoch(e).ok());
    EXPECT_GT(count_entries(dir), 0u);
  }
  EXPECT_EQ(count_entries(dir), 0u);
  {
    // Moved-from writers do not remove the moved temporaries twice; the new owner does.
    RinexObsWriter a;
    ASSERT_TRUE(a.open(dir / "moved.rnx", two_system_header(3.04)).ok());
    RinexObsWriter b = std::move(a);
    ASSERT_TRUE(b.write_epoch(sample_epochs()[0]).ok());
  }
  EXPECT_EQ(count_entries(dir), 0u);
}

TEST(RinexObsWriter, RejectsInvalidInput) {
  const auto dir = test::make_temp_dir("rinex_obs_invalid");
  {
    ObservationHeader h = two_system_header(3.05);
    RinexObsWriter writer;
    const Status s = writer.open(dir / "a.rnx", h);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::kUnsupported);
  }
  {
    ObservationHeader h = two_system_header(3.04);
    h.observation_types[GnssSystem::kGps].push_back(type("C1"));
    RinexObsWriter writer;
    EXPECT_FALSE(writer.open(dir / "b.rnx", h).ok());
  }
  {
    ObservationHeader h = two_system_header(3.04);
    h.time_system = TimeScale::kTai;  // no RINEX observation time system (GLO is UTC, GLONASST none)
    RinexObsWriter writer;
    EXPECT_FALSE(writer.open(dir / "c.rnx", h).ok());
    h.time_system = TimeScale::kGlonasst;
    EXPECT_FALSE(writer.open(dir / "c.rnx", h).ok());
  }
  RinexObsWriter writer;
  ASSERT_TRUE(writer.open(dir / "d.rnx", two_system_header(3.04)).ok());
  auto epochs = sample_epochs();
  ASSERT_TRUE(writer.write_epoch(epochs[1]).ok());
  EXPECT_FALSE(writer.write_epoch(epochs[0]).ok()) << "going back in time";
  ObservationEpoch galileo = epochs[2];
  galileo.satellites.push_back({SatelliteId{GnssSystem::kGalileo, 11}, {val(1.0)}});
  EXPECT_FALSE(writer.write_epoch(galileo).ok()) << "system without observation types";
  ObservationEpoch twice = epochs[2];
  twice.satellites.push_back(twice.satellites[0]);
  EXPECT_FALSE(writer.write_epoch(twice).ok()) << "duplicate satellite";
  ObservationEpoch too_many = epochs[2];
  too_many.satellites[0].values.resize(5);
  EXPECT_FALSE(writer.write_epoch(too_many).ok()) << "more values than types";
  ObservationEpoch bad_flag = epochs[2];
  bad_flag.satellites[0].values[0].lli = 8;
  EXPECT_FALSE(writer.write_epoch(bad_flag).ok()) << "LLI out of range";
  ASSERT_TRUE(writer.write_epoch(epochs[2]).ok());
  ASSERT_TRUE(writer.finish().ok());
  auto read = read_rinex_obs(dir / "d.rnx");
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->epochs.size(), 2u);
}

TEST(RinexObsWriter, EventRecordsRoundTrip) {
  const auto dir = test::make_temp_dir("rinex_obs_event");
  auto epochs = sample_epochs();
  ObservationEpoch event;
  event.time = epochs[0].time + 10.0;
  event.flag = EpochFlag::kHeaderInfo;
  event.event_records = {"antenna moved to the roof                                    COMMENT"};
  epochs.insert(epochs.begin() + 1, event);
  ASSERT_TRUE(write_rinex_obs(dir / "event.rnx", two_system_header(3.04), epochs).ok());
  auto read = read_rinex_obs(dir / "event.rnx");
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_EQ(read->epochs.size(), 4u);
  EXPECT_EQ(read->epochs[1].flag, EpochFlag::kHeaderInfo);
  EXPECT_EQ(read->epochs[1].event_records, event.event_records);
  EXPECT_TRUE(read->epochs[1].satellites.empty());
  // Events do not shorten the interval.
  EXPECT_DOUBLE_EQ(read->header.interval_s.value_or(0.0), 30.0);
}

// ------------------------------------------------------------------ RINEX 2 reader
// A RINEX 2.11 file with 14 satellites (satellite list continued) and 7 types (values continued),
// a blank system letter for GPS, an event and a power-failure flag.
constexpr const char* kRinex211 =
    "     2.11           OBSERVATION DATA    M (MIXED)           RINEX VERSION / TYPE\n"
    "teqc  2019Feb25     NGS                 20220704 07:18:43UTCPGM / RUN BY / DATE\n"
    "TEST                                                        MARKER NAME\n"
    "     7    L1    L2    C1    P2    P1    S1    D1            # / TYPES OF OBSERV\n"
    "    30.0000                                                 INTERVAL\n"
    "  2021     4    28    19     0    0.0000000     GPS         TIME OF FIRST OBS\n"
    "    18                                                      LEAP SECONDS\n"
    "                                                            END OF HEADER\n"
    " 21  4 28 19  0  0.0000000  0 14G15 19G01G17G02G12R15G30G13G28R19R18 0.000123456\n"
    "                                E07G06\n"
    " 122610995.213 7  95540973.904 6  23332073.875    23332083.105\n"
    "        42.200         -1234.5\n"
    " 105562626.468 8  82256563.65447  20087880.078    20087884.836\n"
    "        52.100\n"
    " 1\n"
    "\n"
    " 2\n"
    "\n"
    " 3\n"
    "\n"
    " 4\n"
    "\n"
    " 5\n"
    "\n"
    " 6\n"
    "\n"
    " 7\n"
    "\n"
    " 8\n"
    "\n"
    " 9\n"
    "\n"
    "10\n"
    "\n"
    " 126106956.825 5  98265263.438 5  23997373.680    23997385.781\n"
    "        35.200\n"
    "  11.000          12.000\n"
    "                          99.5\n"
    "                            4  1\n"
    "ROOF ANTENNA                                                COMMENT\n"
    " 21  4 28 19  0 30.0000000  1  1G15\n"
    " 122610995.213 7\n"
    "\n";

TEST(RinexObsReader, Rinex211ContinuationLinesAndCodeMapping) {
  auto read = parse_rinex_obs("test.11o", kRinex211);
  ASSERT_TRUE(read.ok()) << read.error().message;
  const auto& h = read->header;
  EXPECT_NEAR(h.version, 2.11, 1e-9);
  EXPECT_EQ(h.marker_name, "TEST");
  EXPECT_EQ(h.leap_seconds, 18);
  // Systems present: G, R, E; each lists the 7 types with the RINEX 3 equivalent and the original.
  ASSERT_EQ(h.observation_types.size(), 3u);
  const auto& g = h.observation_types.at(GnssSystem::kGps);
  ASSERT_EQ(g.size(), 7u);
  EXPECT_EQ(g[0], (ObservationType{"L1C", "L1"}));
  EXPECT_EQ(g[1], (ObservationType{"L2W", "L2"}));
  EXPECT_EQ(g[2], (ObservationType{"C1C", "C1"}));
  EXPECT_EQ(g[3], (ObservationType{"C2W", "P2"}));
  EXPECT_EQ(g[4], (ObservationType{"C1W", "P1"}));
  EXPECT_EQ(g[5], (ObservationType{"S1C", "S1"}));
  EXPECT_EQ(g[6], (ObservationType{"D1C", "D1"}));
  const auto& r = h.observation_types.at(GnssSystem::kGlonass);
  EXPECT_EQ(r[1], (ObservationType{"L2P", "L2"}));
  EXPECT_EQ(r[3], (ObservationType{"C2P", "P2"}));
  const auto& e = h.observation_types.at(GnssSystem::kGalileo);
  EXPECT_EQ(e[0], (ObservationType{"L1X", "L1"}));
  EXPECT_EQ(e[1], (ObservationType{"", "L2"})) << "Galileo has no L2";
  EXPECT_EQ(e[3], (ObservationType{"", "P2"}));
  EXPECT_EQ(h.type_index(GnssSystem::kGps, "P2"), 3u);
  EXPECT_EQ(h.type_index(GnssSystem::kGps, "C2W"), 3u);

  ASSERT_EQ(read->epochs.size(), 3u);
  const auto& e0 = read->epochs[0];
  ASSERT_EQ(e0.satellites.size(), 14u);
  EXPECT_EQ(e0.satellites[1].satellite, (SatelliteId{GnssSystem::kGps, 19}));  // blank letter = GPS
  EXPECT_EQ(e0.satellites[12].satellite, (SatelliteId{GnssSystem::kGalileo, 7}));
  EXPECT_EQ(e0.satellites[13].satellite, (SatelliteId{GnssSystem::kGps, 6}));
  ASSERT_TRUE(e0.receiver_clock_offset_s.has_value());
  EXPECT_NEAR(*e0.receiver_clock_offset_s, 0.000123456, 1e-15);
  const auto& g15 = e0.satellites[0].values;
  EXPECT_NEAR(*g15[0].value, 122610995.213, 1e-6);
  EXPECT_EQ(g15[0].ssi, 7);
  EXPECT_NEAR(*g15[3].value, 23332083.105, 1e-6);
  EXPECT_FALSE(g15[4].value.has_value());
  EXPECT_NEAR(*g15[5].value, 42.2, 1e-9);
  EXPECT_NEAR(*g15[6].value, -1234.5, 1e-9);  // second line, second field
  const auto& g19 = e0.satellites[1].values;
  EXPECT_NEAR(*g19[1].value, 82256563.654, 1e-6);
  EXPECT_EQ(g19[1].lli, 4);
  EXPECT_EQ(g19[1].ssi, 7);
  const auto& e07 = e0.satellites[12].values;
  EXPECT_NEAR(*e07[0].value, 126106956.825, 1e-6);
  const auto& g06 = e0.satellites[13].values;
  EXPECT_NEAR(*g06[0].value, 11.0, 1e-9);
  EXPECT_NEAR(*g06[1].value, 12.0, 1e-9);
  EXPECT_FALSE(g06[5].value.has_value());
  EXPECT_NEAR(*g06[6].value, 99.5, 1e-9);

  EXPECT_EQ(read->epochs[1].flag, EpochFlag::kHeaderInfo);
  ASSERT_EQ(read->epochs[1].event_records.size(), 1u);
  EXPECT_EQ(read->epochs[1].event_records[0].substr(0, 12), "ROOF ANTENNA");
  EXPECT_EQ(read->epochs[2].flag, EpochFlag::kPowerFailure);
  EXPECT_NEAR(read->epochs[2].time - read->epochs[0].time, 30.0, 1e-9);
  EXPECT_NEAR(read->epochs[0].time - GnssTime::from_calendar({2021, 4, 28, 19, 0, 0.0}, TimeScale::kGpst), 0.0, 1e-9);
}

TEST(RinexObsReader, ErrorsNameFileAndLine) {
  std::string text = kRinex211;
  const size_t at = text.find("95540973.904");
  text.replace(at, 12, "95540973.9x4");
  auto read = parse_rinex_obs("broken.11o", text);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.error().code, ErrorCode::kParse);
  EXPECT_NE(read.error().message.find("broken.11o:11:"), std::string::npos) << read.error().message;
  EXPECT_NE(read.error().message.find("G15"), std::string::npos) << read.error().message;

  auto nav = parse_rinex_obs("nav.rnx", "     3.04           N: GNSS NAV DATA    M                   RINEX VERSION / TYPE\n");
  ASSERT_FALSE(nav.ok());
  EXPECT_NE(nav.error().message.find("nav.rnx:1:"), std::string::npos) << nav.error().message;

  auto truncated = parse_rinex_obs("cut.rnx", std::string(kRinex211).substr(0, std::string(kRinex211).find(" 3\n")));
  ASSERT_FALSE(truncated.ok());
  EXPECT_NE(truncated.error().message.find("cut.rnx:9:"), std::string::npos) << truncated.error().message;
}

TEST(RinexObsReader, Rinex3ScaleFactorAndShortLines) {
  const std::string text =
      "     3.03           OBSERVATION DATA    G: GPS              RINEX VERSION / TYPE\n"
      "G    3 C1C L1C S1C                                          SYS / # / OBS TYPES\n"
      "G   10   1 S1C                                              SYS / SCALE FACTOR\n"
      "  2019     4    28    12    44   33.9970000     GPS         TIME OF FIRST OBS\n"
      "                                                            END OF HEADER\n"
      "> 2019  4 28 12 44 33.9970000  0  2\n"
      "G 2  21600712.022   113512506.8763           270\n"
      "G19  19761890.586                3\n";
  auto read = parse_rinex_obs("scale.rnx", text);
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_EQ(read->epochs.size(), 1u);
  const auto& e = read->epochs[0];
  EXPECT_NEAR(e.time - GnssTime::from_calendar({2019, 4, 28, 12, 44, 33.0}, TimeScale::kGpst), 0.997, 1e-12);
  ASSERT_EQ(e.satellites.size(), 2u);
  EXPECT_EQ(e.satellites[0].satellite, (SatelliteId{GnssSystem::kGps, 2}));
  EXPECT_NEAR(*e.satellites[0].values[2].value, 27.0, 1e-12);  // 270 / 10
  EXPECT_EQ(e.satellites[0].values[1].lli, 3);
  EXPECT_FALSE(e.satellites[1].values[1].value.has_value());
  EXPECT_EQ(e.satellites[1].values[1].lli, 3);
  EXPECT_FALSE(e.satellites[1].values[2].value.has_value());
  EXPECT_EQ(read->header.file_system, GnssSystem::kGps);
}

TEST(RinexObsReader, Rinex2CodeMappingTable) {
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGps, "C1"), "C1C");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGps, "P1"), "C1W");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGps, "C2"), "C2X");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGps, "L5"), "L5X");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGlonass, "C2"), "C2C");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGlonass, "D1"), "D1C");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGalileo, "C7"), "C7X");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGalileo, "S8"), "S8X");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kSbas, "L1"), "L1C");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kSbas, "P1"), "");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGps, "L6"), "");
  EXPECT_EQ(rinex2_to_rinex3_code(GnssSystem::kGps, "C1C"), "");
}

}  // namespace
}  // namespace skytrace::io
