// SP3 and RINEX clock parsing on small inline files, and the interpolation of precise orbits and
// clocks on synthetic orbits whose exact positions are known.
#include <Eigen/Geometry>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/precise.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

using skytrace::test::make_temp_dir;

std::filesystem::path write_text(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
  const auto path = dir / name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string p_line(const char* satellite, double x_km, double y_km, double z_km, double clock_us,
                   const char* tail = "", char kind = 'P') {
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "%c%3s%14.6f%14.6f%14.6f%14.6f%s\n", kind, satellite, x_km, y_km, z_km,
                clock_us, tail);
  return buffer;
}

// An SP3-c file of 3 epochs, 15 min apart, with the time system given.
std::string small_sp3c(const std::string& time_system = "GPS") {
  std::string s;
  s += "#cV2020  6 25  0  0  0.00000000       3 ORBIT IGb14 FIT  TST\n";
  s += "## 2111 345600.00000000   900.00000000 59025 0.0000000000000\n";
  s += "+    4   G01G05R03L12  0  0  0  0  0  0  0  0  0  0  0  0  0\n";
  s += "+          0  0  0  0  0  0  0  0  0  0  0  0  0  0  0  0  0\n";
  s += "++         5  6  7  8  0  0  0  0  0  0  0  0  0  0  0  0  0\n";
  s += "%c M  cc " + time_system + " ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n";
  s += "%c cc cc ccc ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n";
  s += "%f  1.2500000  1.025000000  0.00000000000  0.000000000000000\n";
  s += "%i    0    0    0    0      0      0      0      0         0\n";
  s += "/* a comment line\n";
  s += "*  2020  6 25  0  0  0.00000000\n";
  s += p_line("G01", -11562.163582, 14053.114306, 23345.128269, -884.707516, " 10 11 12 113 E   MP");
  s += p_line("G01", 12345.678901, -2345.678901, 345.678901, 12.345678, "", 'V');
  s += "EP  G01     55     55     55    222 1234567 -1234567 5999999      -30      21 -1230000\n";
  s += p_line("G05", 0.0, 0.0, 0.0, 999999.999999);
  s += p_line("R03", 999999.999999, 999999.999999, 999999.999999, 12.5);
  s += p_line("L12", 1.0, 2.0, 3.0, 4.0);
  s += "*  2020  6 25  0 15  0.00000000\n";
  s += p_line("G01", -11000.0, 14000.0, 23000.0, -884.7);
  s += p_line("G05", 16577.017768, -4619.539763, 24092.494804, -368.776159);
  s += "*  2020  6 25  0 30  0.00000000\n";
  s += p_line("G01", -10000.0, 13000.0, 22000.0, -884.6);
  s += "EOF\n";
  return s;
}

TEST(Sp3Reader, ParsesHeaderValuesAndMissingMarkers) {
  const auto dir = make_temp_dir("sp3_parse");
  const auto path = write_text(dir, "small.sp3", small_sp3c());
  auto data = read_sp3(path);
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_EQ(data->header.version, 'c');
  EXPECT_TRUE(data->header.has_velocities);
  EXPECT_EQ(data->header.declared_epoch_count, 3);
  EXPECT_EQ(data->header.data_used, "ORBIT");
  EXPECT_EQ(data->header.coordinate_system, "IGb14");
  EXPECT_EQ(data->header.orbit_type, "FIT");
  EXPECT_EQ(data->header.agency, "TST");
  EXPECT_EQ(data->header.file_type, "M");
  EXPECT_EQ(data->header.time_system, "GPS");
  EXPECT_DOUBLE_EQ(data->header.interval_s, 900.0);
  // L12 (a LEO) is dropped; the others keep the header order.
  ASSERT_EQ(data->header.satellites.size(), 3u);
  EXPECT_EQ(data->header.satellites[2].to_string(), "R03");
  ASSERT_EQ(data->header.accuracy_exponents.size(), 3u);
  EXPECT_EQ(data->header.accuracy_exponents[1], 6);
  ASSERT_EQ(data->header.comments.size(), 1u);
  EXPECT_EQ(data->header.comments[0], "a comment line");

  ASSERT_EQ(data->epochs.size(), 3u);
  EXPECT_EQ(data->epochs[0], GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0));
  EXPECT_DOUBLE_EQ(data->epochs[2] - data->epochs[0], 1800.0);
  EXPECT_EQ(data->header.first_epoch, data->epochs[0]);

  const auto* g01 = data->series(SatelliteId::parse("G01").value());
  ASSERT_NE(g01, nullptr);
  const Sp3Record& r = (*g01)[0];
  ASSERT_TRUE(r.has_position && r.has_clock && r.has_velocity && r.has_clock_rate);
  EXPECT_NEAR(r.position_m.x(), -11562163.582, 1e-6);
  EXPECT_NEAR(r.position_m.z(), 23345128.269, 1e-6);
  EXPECT_NEAR(r.clock_s, -884.707516e-6, 1e-15);
  EXPECT_NEAR(r.velocity_mps.x(), 1234.5678901, 1e-9);   // dm/s -> m/s
  EXPECT_NEAR(r.velocity_mps.y(), -234.5678901, 1e-9);
  EXPECT_NEAR(r.clock_rate_s_per_s, 12.345678e-10, 1e-19);  // 1e-4 us/s -> s/s
  EXPECT_TRUE(r.clock_event);
  EXPECT_TRUE(r.maneuver);
  EXPECT_TRUE(r.orbit_predicted);
  EXPECT_FALSE(r.clock_predicted);

  const auto* g05 = data->series(SatelliteId::parse("G05").value());
  ASSERT_NE(g05, nullptr);
  EXPECT_FALSE((*g05)[0].has_position);  // 0.000000 position
  EXPECT_FALSE((*g05)[0].has_clock);     // 999999.999999 clock
  EXPECT_TRUE((*g05)[1].has_position);
  EXPECT_FALSE((*g05)[2].has_position);  // no record at all
  const auto* r03 = data->series(SatelliteId::parse("R03").value());
  ASSERT_NE(r03, nullptr);
  EXPECT_FALSE((*r03)[0].has_position);  // 999999.999999 position
  EXPECT_TRUE((*r03)[0].has_clock);
  EXPECT_NEAR((*r03)[0].clock_s, 12.5e-6, 1e-15);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGps), 2u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGlonass), 0u);  // no valid position
}

TEST(Sp3Reader, ReadsGzipCompressedFiles) {
  const auto dir = make_temp_dir("sp3_gzip");
  const std::string text = small_sp3c();
  const auto path = dir / "small.sp3.gz";
  gzFile file = gzopen(path.string().c_str(), "wb");
  ASSERT_NE(file, nullptr);
  ASSERT_EQ(gzwrite(file, text.data(), static_cast<unsigned>(text.size())), static_cast<int>(text.size()));
  gzclose(file);
  auto compressed = read_sp3(path);
  ASSERT_TRUE(compressed.ok()) << compressed.error().message;
  auto plain = read_sp3(write_text(dir, "small.sp3", text));
  ASSERT_TRUE(plain.ok());
  ASSERT_EQ(compressed->epochs.size(), plain->epochs.size());
  EXPECT_EQ(compressed->records[0][0].position_m, plain->records[0][0].position_m);
}

TEST(Sp3Reader, ConvertsEpochsFromTheFileTimeSystem) {
  const auto dir = make_temp_dir("sp3_time_systems");
  const GnssTime gps = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  // Expected GPST of the tabulated "2020-06-25 00:00:00" in each system (GPS - UTC = 18 s).
  const std::pair<const char*, double> cases[] = {
      {"GPS", 0.0}, {"GAL", 0.0}, {"QZS", 0.0}, {"BDT", 14.0}, {"TAI", -19.0}, {"UTC", 18.0}, {"GLO", 18.0},
      {"ccc", 0.0}};
  for (const auto& [name, offset_s] : cases) {
    auto data = read_sp3(write_text(dir, std::string(name) + ".sp3", small_sp3c(name)));
    ASSERT_TRUE(data.ok()) << name << ": " << data.error().message;
    EXPECT_DOUBLE_EQ(data->epochs[0] - gps, offset_s) << name;
  }
  auto bad = read_sp3(write_text(dir, "XYZ.sp3", small_sp3c("XYZ")));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("XYZ.sp3:6:"), std::string::npos) << bad.error().message;
}

// SP3-d with more than 85 satellites: any number of "+" and "++" lines and long comments, also
// between the %c/%f lines.
TEST(Sp3Reader, ReadsSp3dWithMoreThan85Satellites) {
  std::vector<std::string> ids;
  for (const auto& [letter, count] : {std::pair{'G', 32}, std::pair{'R', 24}, std::pair{'E', 36}, std::pair{'C', 8}}) {
    for (int k = 1; k <= count; ++k) {
      char id[16];
      std::snprintf(id, sizeof id, "%c%02d", letter, k);
      ids.emplace_back(id);
    }
  }
  ASSERT_EQ(ids.size(), 100u);
  std::string s = "#dP2021  4 28  0  0  0.00000000       1 d+D   IGb14 FIT AIUB\n";
  s += "## 2155 259200.00000000   300.00000000 59332 0.0000000000000\n";
  const size_t lines = (ids.size() + 16) / 17;
  for (size_t line = 0; line < lines; ++line) {
    s += line == 0 ? "+  100   " : "+        ";
    for (size_t k = 0; k < 17; ++k) {
      const size_t index = line * 17 + k;
      s += index < ids.size() ? ids[index] : "  0";
    }
    s += "\n";
  }
  for (size_t line = 0; line < lines; ++line) {
    s += "++       ";
    for (size_t k = 0; k < 17; ++k) s += line * 17 + k < ids.size() ? "  4" : "  0";
    s += "\n";
  }
  s += "%c M  cc GPS ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n";
  s += "/* A comment of the SP3-d kind, eighty characters long, placed inside the header.\n";
  s += "%c cc cc ccc ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n";
  s += "%f  1.2500000  1.025000000  0.00000000000  0.000000000000000\n";
  s += "%f  0.0000000  0.000000000  0.00000000000  0.000000000000000\n";
  s += "%i    0    0    0    0      0      0      0      0         0\n";
  s += "%i    0    0    0    0      0      0      0      0         0\n";
  for (int k = 0; k < 6; ++k) s += "/* comment " + std::to_string(k) + "\n";
  s += "*  2021  4 28  0  0  0.00000000\n";
  s += p_line("C08", -12345.0, 23456.0, 34567.0, 1.0);
  s += p_line("G01", 13287.682546, -15491.926575, 16545.690647, 703.963460);
  s += "EOF\n";
  const auto dir = make_temp_dir("sp3d");
  auto data = read_sp3(write_text(dir, "d.sp3", s));
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_EQ(data->header.version, 'd');
  ASSERT_EQ(data->header.satellites.size(), 100u);
  EXPECT_EQ(data->header.satellites.back().to_string(), "C08");
  EXPECT_EQ(data->header.accuracy_exponents.size(), 100u);
  EXPECT_EQ(data->header.comments.size(), 7u);
  EXPECT_EQ(data->satellites.size(), 100u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kBeiDou), 1u);
  const auto* c08 = data->series(SatelliteId::parse("C08").value());
  ASSERT_NE(c08, nullptr);
  EXPECT_NEAR((*c08)[0].position_m.y(), 23456000.0, 1e-6);
}

TEST(Sp3Reader, BadInputNamesFileLineAndField) {
  const auto dir = make_temp_dir("sp3_bad");
  struct Case {
    std::string from, to, where, what;
  };
  const Case cases[] = {
      {"-11000.0", "-11000.x", "bad1.sp3:19:", "G01 x"},
      {"-884.6", "-88A.6", "bad2.sp3:22:", "clock"},
      {"*  2020  6 25  0 30", "*  2020  6 25  0 10", "bad3.sp3:21:", "does not follow"},
      {"#cV2020", "#xV2020", "bad4.sp3:1:", "not an SP3 file"},
      {"## 2111 345600.00000000   900.00000000", "## 2111 345600.00000000   abc.00000000", "bad5.sp3:2:", "epoch interval"},
      {"*  2020  6 25  0 15", "*  2020 13 25  0 15", "bad6.sp3:18:", "epoch out of range"},
  };
  int index = 0;
  for (const auto& c : cases) {
    std::string text = small_sp3c();
    const auto at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    const std::string name = "bad" + std::to_string(++index) + ".sp3";
    auto data = read_sp3(write_text(dir, name, text));
    ASSERT_FALSE(data.ok()) << name;
    EXPECT_EQ(data.error().code, ErrorCode::kParse);
    EXPECT_NE(data.error().message.find(c.where), std::string::npos) << data.error().message;
    EXPECT_NE(data.error().message.find(c.what), std::string::npos) << data.error().message;
  }
  // A duplicated P record.
  std::string text = small_sp3c();
  text.insert(text.find("*  2020  6 25  0 30"), p_line("G05", 1.0, 2.0, 3.0, 4.0));
  auto duplicate = read_sp3(write_text(dir, "dup.sp3", text));
  ASSERT_FALSE(duplicate.ok());
  EXPECT_NE(duplicate.error().message.find("dup.sp3:21: second P record of G05"), std::string::npos)
      << duplicate.error().message;
  // A missing file.
  auto missing = read_sp3(dir / "absent.sp3");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
}

TEST(Sp3Reader, MergesFilesWithoutDuplicateEpochs) {
  const auto dir = make_temp_dir("sp3_merge");
  // Second file: starts at the last epoch of the first (00:30) and goes on to 00:45.
  std::string second = small_sp3c();
  const auto body = second.find("*  2020  6 25  0  0");
  second = second.substr(0, body);
  second += "*  2020  6 25  0 30  0.00000000\n";
  second += p_line("G01", -1.0, -1.0, -1.0, -1.0);  // loses to the first file's record
  second += p_line("G05", 1.0, 2.0, 3.0, 4.0);        // fills the first file's gap
  second += "*  2020  6 25  0 45  0.00000000\n";
  second += p_line("G01", -9000.0, 12000.0, 21000.0, -884.5);
  second += p_line("G07", 9000.0, 12000.0, 21000.0, 5.0);
  second += "EOF\n";
  auto merged = read_sp3({write_text(dir, "a.sp3", small_sp3c()), write_text(dir, "b.sp3", second)});
  ASSERT_TRUE(merged.ok()) << merged.error().message;
  ASSERT_EQ(merged->epochs.size(), 4u);
  for (size_t k = 1; k < merged->epochs.size(); ++k) EXPECT_DOUBLE_EQ(merged->epochs[k] - merged->epochs[k - 1], 900.0);
  EXPECT_EQ(merged->sources.size(), 2u);
  const auto* g01 = merged->series(SatelliteId::parse("G01").value());
  ASSERT_NE(g01, nullptr);
  EXPECT_NEAR((*g01)[2].position_m.x(), -10000000.0, 1e-6);
  EXPECT_NEAR((*g01)[3].position_m.x(), -9000000.0, 1e-6);
  const auto* g05 = merged->series(SatelliteId::parse("G05").value());
  ASSERT_NE(g05, nullptr);
  EXPECT_TRUE((*g05)[2].has_position);
  EXPECT_NEAR((*g05)[2].position_m.z(), 3000.0, 1e-6);
  ASSERT_NE(merged->series(SatelliteId::parse("G07").value()), nullptr);
  EXPECT_EQ(merged->satellites.size(), 4u);  // G01 G05 G07 R03, sorted
  EXPECT_EQ(merged->satellites[2].to_string(), "G07");
}

// --- RINEX clock -------------------------------------------------------------------------------

std::string header_line(const std::string& content, const std::string& label, size_t label_column) {
  std::string line = content;
  line.resize(label_column, ' ');
  return line + label + "\n";
}

TEST(RinexClockReader, ReadsVersion300) {
  std::string s;
  s += header_line("     3.00           CLOCK DATA          G", "RINEX VERSION / TYPE", 60);
  s += header_line("   GPS", "TIME SYSTEM ID", 60);
  s += header_line("     2    AR    AS", "# OF TYPES OF DATA", 60);
  s += header_line("GRG  CNES/CLS TOULOUSE,FRANCE", "ANALYSIS CENTER", 60);
  s += header_line("     2", "# OF SOLN SATS", 60);
  s += header_line("G05 E01", "PRN LIST", 60);
  s += header_line("", "END OF HEADER", 60);
  s += "AR BRUX 2020  6 25  0  0  0.000000  2   -0.123456789012E-06  0.123456789012E-10\n";
  s += "AS E01  2020  6 25  0  0  0.000000  2   -0.884707516318E-03  0.337986288247E-10\n";
  s += "AS G05  2020  6 25  0  0  0.000000  2   -0.153202221931E-04  0.530778487457E-11\n";
  s += "AS G05  2020  6 25  0  0 30.000000  4   -0.153201916405E-04  0.537564763307E-11\n";
  s += "   0.100000000000E-11 -0.200000000000E-12\n";
  s += "AR BRUX 2020  6 25  0  0 30.000000  6   -0.123456789012E-06  0.123456789012E-10\n";
  s += "   0.100000000000E-11 -0.200000000000E-12  0.100000000000E-11 -0.200000000000E-12\n";
  s += "AS G05  2020  6 25  0  1  0.000000  1   -0.153202368705E-04\n";
  const auto dir = make_temp_dir("clk300");
  auto data = read_rinex_clock(write_text(dir, "grg.clk", s));
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_DOUBLE_EQ(data->version, 3.0);
  EXPECT_EQ(data->time_system, "GPS");
  EXPECT_EQ(data->analysis_center, "GRG  CNES/CLS TOULOUSE,FRANCE");
  ASSERT_EQ(data->listed_satellites.size(), 2u);
  EXPECT_EQ(data->satellite_clocks.size(), 2u);
  const auto* g05 = data->series(SatelliteId::parse("G05").value());
  ASSERT_NE(g05, nullptr);
  ASSERT_EQ(g05->size(), 3u);
  const GnssTime t0 = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  EXPECT_EQ((*g05)[0].time, t0);
  EXPECT_DOUBLE_EQ((*g05)[1].time - t0, 30.0);
  EXPECT_DOUBLE_EQ((*g05)[2].time - t0, 60.0);
  EXPECT_DOUBLE_EQ((*g05)[1].bias_s, -0.153201916405E-04);
  EXPECT_DOUBLE_EQ((*g05)[1].sigma_s, 0.537564763307E-11);
  EXPECT_LT((*g05)[2].sigma_s, 0.0);  // not given
}

TEST(RinexClockReader, ReadsVersion304WithNineCharacterNamesAndTimeSystem) {
  std::string s;
  s += header_line("3.04                 C                    M", "RINEX VERSION / TYPE", 65);
  s += header_line("   UTC", "TIME SYSTEM ID", 65);
  s += header_line("     2    AR    AS", "# / TYPES OF DATA", 65);
  s += header_line("ASCG00SHN 30602M004            6121151562 -1563978954  -872615294", "SOLN STA NAME / NUM", 65);
  s += header_line("C06 G05 R24 J01", "PRN LIST", 65);
  s += header_line("", "END OF HEADER", 65);
  s += "AR WAB200CHE 2021 04 28 19 30  0.000000  2    0.217267716775E-06  0.458032568265E-10          \n";
  s += "AS G05       2021 04 28 19 30  0.000000  2   -0.404037984480E-04  0.188192149578E-10          \n";
  s += "AS G05       2021 04 28 19 30 30.000000  1   -0.404037740176E-04                              \n";
  s += "AS J01       2021 04 28 19 30  0.000000  2   -0.100000000000E-03 -0.100000000000E-10\n";
  const auto dir = make_temp_dir("clk304");
  auto data = read_rinex_clock(write_text(dir, "cod.clk", s));
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_DOUBLE_EQ(data->version, 3.04);
  EXPECT_EQ(data->time_system, "UTC");
  EXPECT_EQ(data->listed_satellites.size(), 4u);
  const auto* g05 = data->series(SatelliteId::parse("G05").value());
  ASSERT_NE(g05, nullptr);
  ASSERT_EQ(g05->size(), 2u);
  // 19:30 UTC = 19:30:18 GPST in 2021.
  const GnssTime expected = GnssTime::from_calendar({2021, 4, 28, 19, 30, 18.0}, TimeScale::kGpst);
  EXPECT_EQ((*g05)[0].time, expected);
  EXPECT_DOUBLE_EQ((*g05)[1].bias_s, -0.404037740176E-04);
  const auto* j01 = data->series(SatelliteId::parse("J01").value());
  ASSERT_NE(j01, nullptr);
  EXPECT_DOUBLE_EQ((*j01)[0].bias_s, -1e-4);
}

TEST(RinexClockReader, ReadsVersion200WithoutTimeSystem) {
  std::string s;
  s += header_line("     2.00           C", "RINEX VERSION / TYPE", 60);
  s += header_line("     1    AS", "# / TYPES OF DATA", 60);
  s += header_line("", "END OF HEADER", 60);
  s += "AS G16  1994 07 14 20 59  0.000000  2   -0.123456789012E+00 -0.123456789012E+01\n";
  const auto dir = make_temp_dir("clk200");
  auto data = read_rinex_clock(write_text(dir, "old.clk", s));
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_EQ(data->time_scale, TimeScale::kGpst);
  const auto* g16 = data->series(SatelliteId::parse("G16").value());
  ASSERT_NE(g16, nullptr);
  EXPECT_DOUBLE_EQ((*g16)[0].bias_s, -0.123456789012);
  EXPECT_DOUBLE_EQ((*g16)[0].sigma_s, -1.23456789012);
  EXPECT_EQ((*g16)[0].time, GnssTime::from_calendar({1994, 7, 14, 20, 59, 0.0}, TimeScale::kGpst));
}

TEST(RinexClockReader, BadInputNamesFileLineAndField) {
  const auto dir = make_temp_dir("clk_bad");
  const std::string head = header_line("     3.00           C", "RINEX VERSION / TYPE", 60) +
                           header_line("", "END OF HEADER", 60);
  auto bias = read_rinex_clock(write_text(dir, "b1.clk", head + "AS G05  2020  6 25  0  0  0.000000  2   -0.15320x221931E-04  0.53E-11\n"));
  ASSERT_FALSE(bias.ok());
  EXPECT_NE(bias.error().message.find("b1.clk:3: AS G05 clock bias"), std::string::npos) << bias.error().message;
  auto month = read_rinex_clock(write_text(dir, "b2.clk", head + "AS G05  2020 13 25  0  0  0.000000  1   -0.153202221931E-04\n"));
  ASSERT_FALSE(month.ok());
  EXPECT_NE(month.error().message.find("b2.clk:3:"), std::string::npos) << month.error().message;
  auto satellite = read_rinex_clock(write_text(dir, "b3.clk", head + "AS X05  2020  6 25  0  0  0.000000  1   -0.153202221931E-04\n"));
  ASSERT_FALSE(satellite.ok());
  EXPECT_NE(satellite.error().message.find("b3.clk:3: AS satellite"), std::string::npos) << satellite.error().message;
  auto truncated = read_rinex_clock(write_text(dir, "b4.clk", head + "AS G05  2020  6 25  0  0  0.000000  4   -0.153202221931E-04  0.1E-10\n"));
  ASSERT_FALSE(truncated.ok());
  EXPECT_NE(truncated.error().message.find("b4.clk:3: record truncated"), std::string::npos) << truncated.error().message;
  auto no_end = read_rinex_clock(write_text(dir, "b5.clk", header_line("     3.00           C", "RINEX VERSION / TYPE", 60)));
  ASSERT_FALSE(no_end.ok());
  EXPECT_NE(no_end.error().message.find("END OF HEADER"), std::string::npos);
  auto not_clock = read_rinex_clock(write_text(dir, "b6.clk", header_line("     3.04           N", "RINEX VERSION / TYPE", 60)));
  ASSERT_FALSE(not_clock.ok());
  EXPECT_NE(not_clock.error().message.find("b6.clk:1:"), std::string::npos);
}

// --- Interpolation ----------------------------------------------------------------------------

constexpr double kOmega_radps = constants::kEarthRotationRateGps_radps;
constexpr double kGm_m3ps2 = constants::kGmGps_m3ps2;

struct TruthState {
  Eigen::Vector3d position_m, velocity_mps;
};

// A Keplerian orbit (GPS-like: a = 26560 km, i = 55 deg) in the Earth-fixed frame at t_s seconds
// after its reference epoch, the Earth turning at the WGS84 rate. `perturbed` adds a smooth
// non-Keplerian motion of 5 km at two and three times the orbital frequency (J2-like in size).
TruthState kepler_truth(double t_s, double eccentricity, bool perturbed = false) {
  const double a_m = 26560e3, inclination_rad = 55.0 * std::numbers::pi / 180.0, raan_rad = 0.7, perigee_rad = 0.3;
  const double n_radps = std::sqrt(kGm_m3ps2 / (a_m * a_m * a_m));
  const double mean_rad = 0.2 + n_radps * t_s;
  double e_rad = mean_rad;
  for (int k = 0; k < 30; ++k) e_rad = mean_rad + eccentricity * std::sin(e_rad);
  const double cos_e = std::cos(e_rad), sin_e = std::sin(e_rad);
  const double root = std::sqrt(1.0 - eccentricity * eccentricity);
  // Perifocal position and velocity.
  const Eigen::Vector3d p(a_m * (cos_e - eccentricity), a_m * root * sin_e, 0.0);
  const double e_dot = n_radps / (1.0 - eccentricity * cos_e);
  const Eigen::Vector3d v(-a_m * sin_e * e_dot, a_m * root * cos_e * e_dot, 0.0);
  const Eigen::Matrix3d to_inertial =
      (Eigen::AngleAxisd(raan_rad, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(inclination_rad, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(perigee_rad, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  Eigen::Vector3d r_i = to_inertial * p, v_i = to_inertial * v;
  if (perturbed) {
    const double amplitude_m = 5000.0, w2 = 2.0 * n_radps, w3 = 3.0 * n_radps;
    r_i += amplitude_m * Eigen::Vector3d(std::sin(w2 * t_s), std::cos(w2 * t_s), std::sin(w3 * t_s));
    v_i += amplitude_m * Eigen::Vector3d(w2 * std::cos(w2 * t_s), -w2 * std::sin(w2 * t_s), w3 * std::cos(w3 * t_s));
  }
  // Earth-fixed: rotate by -omega t about z; the velocity loses omega x r.
  const Eigen::Matrix3d to_fixed = Eigen::AngleAxisd(-kOmega_radps * t_s, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  TruthState s;
  s.position_m = to_fixed * r_i;
  s.velocity_mps = to_fixed * v_i - Eigen::Vector3d::UnitZ().cross(s.position_m) * kOmega_radps;
  return s;
}

// SP3 data for G01 sampled every interval_s from t0, exact (no rounding), clock 1e-4 s + 1e-11 t.
Sp3Data synthetic_sp3(const GnssTime& t0, int epochs, double interval_s, double eccentricity, bool velocities = false,
                      bool perturbed = false) {
  Sp3Data data;
  data.interval_s = interval_s;
  data.header.interval_s = interval_s;
  data.satellites = {SatelliteId{GnssSystem::kGps, 1}};
  data.records.resize(1);
  for (int k = 0; k < epochs; ++k) {
    const double t_s = k * interval_s;
    data.epochs.push_back(t0 + t_s);
    const TruthState truth = kepler_truth(t_s, eccentricity, perturbed);
    Sp3Record r;
    r.position_m = truth.position_m;
    r.has_position = true;
    r.clock_s = 1e-4 + 1e-11 * t_s;
    r.has_clock = true;
    if (velocities) {
      r.velocity_mps = truth.velocity_mps;
      r.has_velocity = true;
    }
    data.records[0].push_back(r);
  }
  return data;
}

const GnssTime kT0 = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
const SatelliteId kG01{GnssSystem::kGps, 1};

struct Errors {
  double position_m = 0.0, velocity_mps = 0.0;
};

// Largest errors at the midpoints of the intervals [first, last) of the synthetic data.
Errors midpoint_errors(const PreciseEphemerides& source, int first, int last, double interval_s, double eccentricity,
                       bool perturbed = false) {
  Errors worst;
  for (int k = first; k < last; ++k) {
    for (double fraction : {0.25, 0.5, 0.75}) {
      const double t_s = (k + fraction) * interval_s;
      auto orbit = source.orbit(kG01, kT0 + t_s);
      EXPECT_TRUE(orbit.ok()) << (orbit.ok() ? "" : orbit.error().message);
      if (!orbit.ok()) continue;
      const TruthState truth = kepler_truth(t_s, eccentricity, perturbed);
      worst.position_m = std::max(worst.position_m, (orbit->position_m - truth.position_m).norm());
      worst.velocity_mps = std::max(worst.velocity_mps, (orbit->velocity_mps - truth.velocity_mps).norm());
    }
  }
  return worst;
}

struct Variant {
  const char* name;
  InterpolationFrame frame;
  bool two_body;
};
constexpr Variant kVariants[] = {{"inertial + two-body", InterpolationFrame::kInertial, true},
                                 {"inertial", InterpolationFrame::kInertial, false},
                                 {"earth-fixed", InterpolationFrame::kEarthFixed, false}};

TEST(PreciseInterpolation, RecoversCircularOrbitBetween900sSamples) {
  const double interval_s = 900.0;
  for (const auto& variant : kVariants) {
    PreciseOptions options;
    options.frame = variant.frame;
    options.two_body_reference = variant.two_body;
    auto source = PreciseEphemerides::create(synthetic_sp3(kT0, 33, interval_s, 0.0), std::nullopt, options);
    ASSERT_TRUE(source.ok()) << source.error().message;
    // Intervals where the 10-point window is centred (4 samples on each side to spare).
    const Errors centred = midpoint_errors(*source, 4, 28, interval_s, 0.0);
    // The first and last intervals, where the window is one-sided.
    const Errors edges = std::max(midpoint_errors(*source, 0, 1, interval_s, 0.0),
                                  midpoint_errors(*source, 31, 32, interval_s, 0.0),
                                  [](const Errors& a, const Errors& b) { return a.position_m < b.position_m; });
    std::printf("[ measured ] circular orbit, 900 s, 10 points, %s: centred %.3g m %.3g m/s, edge intervals %.3g m %.3g m/s\n",
                variant.name, centred.position_m, centred.velocity_mps, edges.position_m, edges.velocity_mps);
    EXPECT_LT(centred.position_m, 1e-3) << variant.name;
    EXPECT_LT(centred.velocity_mps, 1e-4) << variant.name;
    EXPECT_LT(edges.position_m, 0.05) << variant.name;
  }
}

// Galileo E14/E18-like orbit (e = 0.16) with non-Keplerian perturbations: plain polynomials lose
// centimetres near perigee even at 900 s; the two-body reference removes the eccentricity from
// what is interpolated, leaving the perturbations.
TEST(PreciseInterpolation, RecoversEccentricOrbitWithTwoBodyReference) {
  const double interval_s = 900.0, eccentricity = 0.16;
  Errors plain_centred;
  for (const auto& variant : kVariants) {
    PreciseOptions options;
    options.frame = variant.frame;
    options.two_body_reference = variant.two_body;
    auto source = PreciseEphemerides::create(synthetic_sp3(kT0, 60, interval_s, eccentricity, false, true),
                                             std::nullopt, options);
    ASSERT_TRUE(source.ok());
    const Errors centred = midpoint_errors(*source, 4, 55, interval_s, eccentricity, true);
    const Errors edges = midpoint_errors(*source, 0, 1, interval_s, eccentricity, true);
    std::printf("[ measured ] e = 0.16 orbit, 900 s, 10 points, %s: centred %.3g m %.3g m/s, first interval %.3g m\n",
                variant.name, centred.position_m, centred.velocity_mps, edges.position_m);
    if (variant.two_body) {
      // Measured 0.9 mm and 15 mm (against 79 mm and 1.5 m without the reference).
      EXPECT_LT(centred.position_m, 2e-3);
      EXPECT_LT(centred.velocity_mps, 1e-5);
      EXPECT_LT(edges.position_m, 0.05);
    } else if (variant.frame == InterpolationFrame::kInertial) {
      plain_centred = centred;
    }
  }
  EXPECT_GT(plain_centred.position_m, 1e-3);  // the problem the reference solves is real
}

TEST(PreciseInterpolation, OnSampleEpochsReturnsTheSamples) {
  const Sp3Data data = synthetic_sp3(kT0, 20, 900.0, 0.01);
  auto source = PreciseEphemerides::create(data);
  ASSERT_TRUE(source.ok());
  for (int k : {0, 7, 19}) {
    auto orbit = source->orbit(kG01, kT0 + k * 900.0);
    ASSERT_TRUE(orbit.ok()) << orbit.error().message;
    EXPECT_LT((orbit->position_m - data.records[0][static_cast<size_t>(k)].position_m).norm(), 1e-6) << k;
  }
}

TEST(PreciseInterpolation, VelocityRecordsAreInterpolatedWhenPresent) {
  const double interval_s = 900.0, eccentricity = 0.01;
  for (const auto frame : {InterpolationFrame::kInertial, InterpolationFrame::kEarthFixed}) {
    PreciseOptions options;
    options.frame = frame;
    Sp3Data data = synthetic_sp3(kT0, 24, interval_s, eccentricity, true);
    // Spoil the positions' own derivative information by rounding them to 1 mm (as SP3 does):
    // the velocity must come from the V records, not from differentiating positions.
    for (auto& r : data.records[0]) r.position_m = (r.position_m * 1000.0).array().round() / 1000.0;
    auto source = PreciseEphemerides::create(data, std::nullopt, options);
    ASSERT_TRUE(source.ok());
    const Errors centred = midpoint_errors(*source, 5, 18, interval_s, eccentricity);
    EXPECT_LT(centred.position_m, 2e-3);
    EXPECT_LT(centred.velocity_mps, 1e-5);
  }
}

TEST(PreciseInterpolation, RefusesExtrapolationGapsAndMissingSamples) {
  const double interval_s = 900.0;
  Sp3Data data = synthetic_sp3(kT0, 30, interval_s, 0.0);
  data.records[0][15].has_position = false;  // one missing sample
  auto source = PreciseEphemerides::create(data);
  ASSERT_TRUE(source.ok());
  // Up to one interval beyond the data is allowed, more is refused with the coverage in the text.
  EXPECT_TRUE(source->orbit(kG01, kT0 - 899.0).ok());
  EXPECT_TRUE(source->orbit(kG01, kT0 + 29 * interval_s + 900.0).ok());
  auto late = source->orbit(kG01, kT0 + 29 * interval_s + 901.0);
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().code, ErrorCode::kOutOfRange);
  EXPECT_EQ(late.error().message,
            "no precise orbit for G01 at 2020-06-25T07:30:01 GPST (the SP3 data cover 2020-06-25T00:00:00 to "
            "2020-06-25T07:15:00 GPST)");
  // Around the missing sample: the neighbouring intervals are refused, farther ones work with a
  // window that stays on one side.
  auto at_gap = source->orbit(kG01, kT0 + 14.5 * interval_s);
  ASSERT_FALSE(at_gap.ok());
  EXPECT_NE(at_gap.error().message.find("position missing at 2020-06-25T03:45:00"), std::string::npos)
      << at_gap.error().message;
  auto near_gap = source->orbit(kG01, kT0 + 13.5 * interval_s);
  ASSERT_TRUE(near_gap.ok()) << near_gap.error().message;
  EXPECT_LT((near_gap->position_m - kepler_truth(13.5 * interval_s, 0.0).position_m).norm(), 0.05);
  // A satellite unknown to the data.
  auto unknown = source->orbit(SatelliteId{GnssSystem::kGalileo, 11}, kT0 + 100.0);
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::kNotFound);
  // A gap in the epoch grid (a missing file in a merge).
  Sp3Data split = synthetic_sp3(kT0, 30, interval_s, 0.0);
  split.epochs.erase(split.epochs.begin() + 12, split.epochs.begin() + 14);
  split.records[0].erase(split.records[0].begin() + 12, split.records[0].begin() + 14);
  auto split_source = PreciseEphemerides::create(split);
  ASSERT_TRUE(split_source.ok());
  auto across = split_source->orbit(kG01, kT0 + 12.5 * interval_s);
  ASSERT_FALSE(across.ok());
  EXPECT_NE(across.error().message.find("gap in the SP3 epochs"), std::string::npos) << across.error().message;
  // Too few samples for the window.
  PreciseOptions options;
  options.interpolation_points = 25;
  EXPECT_FALSE(PreciseEphemerides::create(synthetic_sp3(kT0, 30, interval_s, 0.0), std::nullopt, options).ok());
  options.interpolation_points = 12;
  auto short_source = PreciseEphemerides::create(synthetic_sp3(kT0, 10, interval_s, 0.0), std::nullopt, options);
  ASSERT_TRUE(short_source.ok());
  auto too_few = short_source->orbit(kG01, kT0 + 4.5 * interval_s);
  ASSERT_FALSE(too_few.ok());
  EXPECT_NE(too_few.error().message.find("only 10 consecutive samples"), std::string::npos) << too_few.error().message;
}

TEST(PreciseInterpolation, ClocksFromSp3AndFromClockFile) {
  const double interval_s = 900.0;
  Sp3Data data = synthetic_sp3(kT0, 30, interval_s, 0.0);
  data.records[0][10].has_clock = false;  // one missing clock: bridged (neighbours 2 intervals apart)
  data.records[0][20].has_clock = false;  // two missing clocks: refused
  data.records[0][21].has_clock = false;
  auto source = PreciseEphemerides::create(data);
  ASSERT_TRUE(source.ok());
  auto clock = source->clock(kG01, kT0 + 10 * interval_s + 100.0);
  ASSERT_TRUE(clock.ok()) << clock.error().message;
  EXPECT_NEAR(clock->bias_s, 1e-4 + 1e-11 * (10 * interval_s + 100.0), 1e-16);
  EXPECT_NEAR(clock->drift_s_per_s, 1e-11, 1e-18);
  auto refused = source->clock(kG01, kT0 + 20.5 * interval_s);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("no precise clock for G01 at 2020-06-25T05:07:30 GPST"), std::string::npos)
      << refused.error().message;

  // A clock file takes precedence: a different clock line every 30 s.
  RinexClockData clocks;
  auto& samples = clocks.satellite_clocks[kG01];
  for (int k = 0; k <= 200; ++k) {
    if (k == 50 || k == 100 || k == 101) continue;  // one gap bridged, one two-sample gap refused
    samples.push_back({kT0 + 30.0 * k, 2e-4 - 3e-12 * 30.0 * k, 1e-11});
  }
  auto with_file = PreciseEphemerides::create(data, clocks);
  ASSERT_TRUE(with_file.ok());
  auto from_file = with_file->clock(kG01, kT0 + 1500.0 + 7.5);
  ASSERT_TRUE(from_file.ok()) << from_file.error().message;
  EXPECT_NEAR(from_file->bias_s, 2e-4 - 3e-12 * 1507.5, 1e-16);
  EXPECT_NEAR(from_file->drift_s_per_s, -3e-12, 1e-18);
  EXPECT_FALSE(with_file->clock(kG01, kT0 + 3015.0).ok());
  // Beyond the clock file: one interval is extrapolated, more is refused (no SP3 fallback).
  EXPECT_TRUE(with_file->clock(kG01, kT0 + 6000.0 + 30.0).ok());
  auto beyond = with_file->clock(kG01, kT0 + 6000.0 + 31.0);
  ASSERT_FALSE(beyond.ok());
  EXPECT_NE(beyond.error().message.find("clock file"), std::string::npos) << beyond.error().message;
  // With the fallback the SP3 clock is used there.
  PreciseOptions options;
  options.sp3_clock_fallback = true;
  auto fallback = PreciseEphemerides::create(data, clocks, options);
  ASSERT_TRUE(fallback.ok());
  auto sp3_value = fallback->clock(kG01, kT0 + 6000.0 + 31.0);
  ASSERT_TRUE(sp3_value.ok()) << sp3_value.error().message;
  EXPECT_NEAR(sp3_value->bias_s, 1e-4 + 1e-11 * 6031.0, 1e-16);
  // A satellite absent from the clock file is not offered without the fallback.
  RinexClockData other;
  other.satellite_clocks[SatelliteId{GnssSystem::kGps, 2}] = samples;
  auto without = PreciseEphemerides::create(data, other);
  ASSERT_TRUE(without.ok());
  EXPECT_TRUE(without->satellites().empty());
  EXPECT_EQ(without->clock(kG01, kT0 + 100.0).error().code, ErrorCode::kNotFound);
}

TEST(PreciseInterpolation, CoverageFindsWhereOrbitsAndClocksCannotBeFormed) {
  const double interval_s = 900.0;
  Sp3Data data = synthetic_sp3(kT0, 30, interval_s, 0.0);
  data.records[0][15].has_position = false;
  RinexClockData clocks;
  auto& samples = clocks.satellite_clocks[kG01];
  for (int k = 0; k <= 200; ++k) {
    if (k == 50 || k == 100 || k == 101) continue;  // one sample bridged, two not
    samples.push_back({kT0 + 30.0 * k, 2e-4, -1.0});
  }
  auto source = PreciseEphemerides::create(data, clocks);
  ASSERT_TRUE(source.ok());
  EXPECT_EQ(source->orbit_span().first, kT0);
  EXPECT_DOUBLE_EQ(source->orbit_span().last - kT0, 29 * interval_s);
  ASSERT_TRUE(source->clock_file_span().has_value());
  EXPECT_DOUBLE_EQ(source->clock_file_span()->last - kT0, 6000.0);

  // From a fraction of a second before the data (extrapolated) to 100 s past the clock file's end.
  const auto c = source->coverage(kG01, kT0 - 0.2, kT0 + 6100.0);
  EXPECT_TRUE(c.in_orbits);
  EXPECT_TRUE(c.in_clocks);
  EXPECT_FALSE(c.complete());
  EXPECT_TRUE(c.orbit_gaps.empty());
  // Clock: the two missing samples, and beyond one interval after the file's last sample, each
  // between the last and the first times that work.
  ASSERT_EQ(c.clock_gaps.size(), 2u);
  EXPECT_DOUBLE_EQ(c.clock_gaps[0].first - kT0, 99 * 30.0);
  EXPECT_DOUBLE_EQ(c.clock_gaps[0].last - kT0, 102 * 30.0);
  EXPECT_DOUBLE_EQ(c.clock_gaps[1].first - kT0, 6000.0);
  EXPECT_DOUBLE_EQ(c.clock_gaps[1].last - kT0, 6100.0);
  // Orbit: the intervals next to the missing sample (beyond the clock file, the clock fails throughout).
  const auto later = source->coverage(kG01, kT0 + 10 * interval_s, kT0 + 20 * interval_s);
  ASSERT_EQ(later.orbit_gaps.size(), 1u);
  EXPECT_DOUBLE_EQ(later.orbit_gaps[0].first - kT0, 14 * interval_s);
  EXPECT_DOUBLE_EQ(later.orbit_gaps[0].last - kT0, 16 * interval_s);
  ASSERT_EQ(later.clock_gaps.size(), 1u);
  EXPECT_DOUBLE_EQ(later.clock_gaps[0].last - later.clock_gaps[0].first, 10 * interval_s);
  // A span the products serve entirely, and a satellite they lack.
  EXPECT_TRUE(source->coverage(kG01, kT0 - 0.2, kT0 + 2000.0).complete());
  const auto other = source->coverage(SatelliteId{GnssSystem::kGps, 2}, kT0, kT0 + 600.0);
  EXPECT_FALSE(other.in_orbits);
  EXPECT_FALSE(other.in_clocks);
  ASSERT_EQ(other.orbit_gaps.size(), 1u);
  EXPECT_DOUBLE_EQ(other.orbit_gaps[0].last - other.orbit_gaps[0].first, 600.0);
}

TEST(PreciseInterpolation, RelativisticTermAndItsRate) {
  // Eccentric orbit: -2 r.v / c^2 swings by +-2 e sqrt(GM a) / c^2 = +-45.8 ns at e = 0.02.
  const double interval_s = 900.0, eccentricity = 0.02;
  auto source = PreciseEphemerides::create(synthetic_sp3(kT0, 40, interval_s, eccentricity));
  ASSERT_TRUE(source.ok());
  const double c2 = constants::kSpeedOfLight_mps * constants::kSpeedOfLight_mps;
  double largest_s = 0.0;
  for (double t_s = 5 * interval_s; t_s < 34 * interval_s; t_s += 1234.5) {
    auto state = source->state(kG01, kT0 + t_s);
    ASSERT_TRUE(state.ok()) << state.error().message;
    const TruthState truth = kepler_truth(t_s, eccentricity);
    EXPECT_NEAR(state->relativistic_s, -2.0 * truth.position_m.dot(truth.velocity_mps) / c2, 1e-13);
    // The rate against a central difference of the term itself over +-1 s.
    auto before = source->state(kG01, kT0 + t_s - 1.0);
    auto after = source->state(kG01, kT0 + t_s + 1.0);
    ASSERT_TRUE(before.ok() && after.ok());
    const double numeric_rate = (after->relativistic_s - before->relativistic_s) / 2.0;
    EXPECT_NEAR(state->relativistic_drift_s_per_s, numeric_rate, 1e-14) << t_s;
    EXPECT_NEAR(state->clock_bias_s, 1e-4 + 1e-11 * t_s, 1e-16);
    EXPECT_NEAR(state->clock_drift_s_per_s, 1e-11, 1e-18);
    largest_s = std::max(largest_s, std::abs(state->relativistic_s));
  }
  EXPECT_GT(largest_s, 3e-8);
  EXPECT_LT(largest_s, 4.6e-8);
  EXPECT_EQ(source->name(), "precise");
  ASSERT_EQ(source->satellites().size(), 1u);
}

TEST(PreciseInterpolation, RejectsBadOptions) {
  PreciseOptions options;
  options.interpolation_points = 1;
  auto bad = PreciseEphemerides::create(synthetic_sp3(kT0, 30, 900.0, 0.0), std::nullopt, options);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_FALSE(PreciseEphemerides::create(Sp3Data{}).ok());
  // Hand-built data must keep the readers' layout.
  Sp3Data unsorted = synthetic_sp3(kT0, 30, 900.0, 0.0);
  std::swap(unsorted.epochs[3], unsorted.epochs[4]);
  EXPECT_FALSE(PreciseEphemerides::create(unsorted).ok());
  Sp3Data short_records = synthetic_sp3(kT0, 30, 900.0, 0.0);
  short_records.records[0].pop_back();
  EXPECT_FALSE(PreciseEphemerides::create(short_records).ok());
  RinexClockData clocks;
  clocks.satellite_clocks[kG01] = {{kT0 + 30.0, 1e-4, -1.0}, {kT0, 1e-4, -1.0}};
  EXPECT_FALSE(PreciseEphemerides::create(synthetic_sp3(kT0, 30, 900.0, 0.0), clocks).ok());
}

}  // namespace
}  // namespace skytrace::orbits
