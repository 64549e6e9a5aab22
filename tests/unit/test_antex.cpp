// The ANTEX 1.4 reader on small files written here: type-mean receiver antennas, NOAZI and azimuth
// grids with their interpolation, the radome NONE fallback, satellite antennas skipped, malformed
// records refused with file and line; and the phase centre term of the observation model (a pure
// up-offset on L1 shortens the L1 range by the offset times sin(elevation), L2 unchanged).
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "skytrace/orbits/nominal.hpp"
#include "skytrace/receiver/antex.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/receiver/stages/geometry.hpp"

namespace skytrace::receiver {
namespace {

// A record: content padded to column 60, then the label.
std::string record(const std::string& content, const std::string& label) {
  std::string line = content;
  line.resize(60, ' ');
  return line + label + "\n";
}

std::string header() {
  return record("     1.4            M", "ANTEX VERSION / SYST") + record("A", "PCV TYPE / REFANT") +
         record("", "END OF HEADER");
}

// F8.2 values after an 8-character row label.
std::string row(const std::string& label, const std::vector<double>& values_mm) {
  std::ostringstream out;
  out << label;
  for (double v : values_mm) {
    char cell[16];
    std::snprintf(cell, sizeof cell, "%8.2f", v);
    out << cell;
  }
  return out.str() + "\n";
}

std::string offset(double north_mm, double east_mm, double up_mm) {
  char text[40];
  std::snprintf(text, sizeof text, "%10.2f%10.2f%10.2f", north_mm, east_mm, up_mm);
  return record(text, "NORTH / EAST / UP");
}

// A receiver antenna with zenith nodes 0, 30, 60, 90 and the given frequency blocks.
std::string antenna(const std::string& type_radome, const std::string& serial, double dazi_deg,
                    const std::string& frequencies) {
  std::string type_field = type_radome;
  type_field.resize(20, ' ');
  std::string serial_field = serial;
  serial_field.resize(20, ' ');
  char dazi[16];
  std::snprintf(dazi, sizeof dazi, "  %6.1f", dazi_deg);
  return record("", "START OF ANTENNA") + record(type_field + serial_field, "TYPE / SERIAL NO") +
         record("ROBOT               Test                      1    01-JAN-26", "METH / BY / # / DATE") +
         record(dazi, "DAZI") + record("     0.0  90.0  30.0", "ZEN1 / ZEN2 / DZEN") +
         record("     2", "# OF FREQUENCIES") + frequencies + record("", "END OF ANTENNA");
}

std::string frequency(const std::string& code, const std::string& body) {
  return record("   " + code, "START OF FREQUENCY") + body + record("   " + code, "END OF FREQUENCY");
}

const std::string kSatellite = record("", "START OF ANTENNA") +
                               record("BLOCK IIIA          G04                 G074      2018-109A", "TYPE / SERIAL NO") +
                               record("     0.0", "DAZI") + record("     0.0  14.0   1.0", "ZEN1 / ZEN2 / DZEN") +
                               record("   G01", "START OF FREQUENCY") + offset(0, 0, 1000) +
                               record("   G01", "END OF FREQUENCY") + record("", "END OF ANTENNA");

// TEST0 NONE: G01 up 100 mm, NOAZI 0, 2, 4, 6 mm; G02 north 10 mm, east -20 mm, up 50 mm.
// TEST0 TZGD: G01 up 70 mm. TEST1 NONE with DAZI 90: G01 rows at 0, 90, 180, 270, 360.
std::string sample_file() {
  const std::string test0 = antenna(
      "TEST0           NONE", "", 0.0,
      frequency("G01", offset(0, 0, 100) + row("   NOAZI", {0, 2, 4, 6})) +
          frequency("G02", offset(10, -20, 50) + row("   NOAZI", {0, 0, 0, 0})));
  const std::string test0_radome = antenna("TEST0           TZGD", "", 0.0,
                                           frequency("G01", offset(0, 0, 70) + row("   NOAZI", {0, 0, 0, 0})));
  const std::string test0_serial = antenna("TEST0           NONE", "12345", 0.0,
                                           frequency("G01", offset(0, 0, 999) + row("   NOAZI", {0, 0, 0, 0})));
  const std::string test1 = antenna(
      "TEST1           NONE", "", 90.0,
      frequency("G01", offset(0, 0, 0) + row("   NOAZI", {0, 1, 2, 3}) + row("     0.0", {0, 1, 2, 3}) +
                           row("    90.0", {0, 3, 6, 9}) + row("   180.0", {0, 5, 10, 15}) +
                           row("   270.0", {0, 7, 14, 21}) + row("   360.0", {0, 1, 2, 3})));
  return header() + kSatellite + test0 + test0_radome + test0_serial + test1;
}

TEST(Antex, ReadsReceiverAntennasAndSkipsSatellites) {
  auto file = parse_antex("sample.atx", sample_file());
  ASSERT_TRUE(file) << file.error().message;
  EXPECT_EQ(file->pcv_type, 'A');
  EXPECT_EQ(file->satellite_antennas_skipped, 1u);
  ASSERT_EQ(file->receiver_antennas.size(), 4u);
  const AntexAntenna& a = file->receiver_antennas[0];
  EXPECT_EQ(a.type, "TEST0");
  EXPECT_EQ(a.radome, "NONE");
  EXPECT_EQ(a.name(), "TEST0           NONE");
  EXPECT_TRUE(a.serial.empty());
  EXPECT_EQ(a.zenith_nodes(), 4u);
  EXPECT_EQ(a.azimuth_rows(), 0u);
  const AntexFrequency* g02 = a.frequency("G02");
  ASSERT_NE(g02, nullptr);
  EXPECT_NEAR(g02->offset_neu_m.x(), 0.010, 1e-12);
  EXPECT_NEAR(g02->offset_neu_m.y(), -0.020, 1e-12);
  EXPECT_NEAR(g02->offset_neu_m.z(), 0.050, 1e-12);
  EXPECT_EQ(file->receiver_antennas[3].azimuth_rows(), 5u);
}

TEST(Antex, FindsTheTypeMeanWithRadomeFallback) {
  const AntexFile file = parse_antex("sample.atx", sample_file()).value();
  // The type mean, not the individual calibration with a serial number.
  auto exact = file.find("TEST0           NONE");
  ASSERT_TRUE(exact) << exact.error().message;
  EXPECT_NEAR((*exact)->frequency("G01")->offset_neu_m.z(), 0.100, 1e-12);
  // Written with one blank, or the type alone (radome NONE).
  EXPECT_EQ(file.find("TEST0 NONE").value(), *exact);
  EXPECT_EQ(file.find("TEST0").value(), *exact);
  // Its own radome when the file has it, else NONE.
  EXPECT_NEAR(file.find("TEST0 TZGD").value()->frequency("G01")->offset_neu_m.z(), 0.070, 1e-12);
  EXPECT_EQ(file.find("TEST0           SCIS").value(), *exact);
  // Absent: the file, the antenna and the closest names.
  auto missing = file.find("TEST9           NONE");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("sample.atx"), std::string::npos) << missing.error().message;
  EXPECT_NE(missing.error().message.find("TEST9"), std::string::npos);
  EXPECT_NE(missing.error().message.find("closest: 'TEST0           NONE'"), std::string::npos)
      << missing.error().message;
  EXPECT_FALSE(file.find("A NAME WITH TOO MANY BLANKS"));
}

TEST(Antex, InterpolatesZenithAndAzimuth) {
  const AntexFile file = parse_antex("sample.atx", sample_file()).value();
  const AntexAntenna& noazi = file.receiver_antennas[0];
  const AntexFrequency& g01 = *noazi.frequency("G01");
  EXPECT_NEAR(noazi.variation_m(g01, 0.0, 123.0), 0.000, 1e-12);
  EXPECT_NEAR(noazi.variation_m(g01, 45.0, 0.0), 0.003, 1e-12);  // halfway between 2 and 4 mm
  EXPECT_NEAR(noazi.variation_m(g01, 90.0, 0.0), 0.006, 1e-12);
  EXPECT_NEAR(noazi.variation_m(g01, 95.0, 0.0), 0.006, 1e-12);  // beyond the grid: its last node
  const AntexAntenna& grid = file.receiver_antennas[3];
  const AntexFrequency& f = *grid.frequency("G01");
  EXPECT_NEAR(grid.variation_m(f, 30.0, 90.0), 0.003, 1e-12);
  EXPECT_NEAR(grid.variation_m(f, 60.0, 180.0), 0.010, 1e-12);
  // Azimuth 45 at zenith 45: rows 0 (1.5 mm) and 90 (4.5 mm) halfway.
  EXPECT_NEAR(grid.variation_m(f, 45.0, 45.0), 0.003, 1e-12);
  // Between 270 (14 mm at zenith 60) and 360 (2 mm): 315 gives 8 mm; -45 is 315.
  EXPECT_NEAR(grid.variation_m(f, 60.0, 315.0), 0.008, 1e-12);
  EXPECT_NEAR(grid.variation_m(f, 60.0, -45.0), 0.008, 1e-12);
}

TEST(Antex, PhaseCentreRangeCorrection) {
  const AntexFile file = parse_antex("sample.atx", sample_file()).value();
  const Signal l1 = Signal::parse("G1C").value(), l2 = Signal::parse("G2W").value();
  const Signal qzss = Signal::parse("J1C").value(), galileo = Signal::parse("E5Q").value();
  const std::vector<Signal> signals{l1, l2, qzss, galileo};
  auto model = AntennaPhaseCentre::create(*file.find("TEST0").value(), signals, "sample.atx");
  ASSERT_TRUE(model) << model.error().message;
  const AzimuthElevation direction{30.0, 40.0};
  const double el = 40.0 * M_PI / 180.0, az = 30.0 * M_PI / 180.0;
  // L1: up 0.1 m, and at zenith 50 the PCV two thirds of the way from 2 mm (zenith 30) to 4 mm (60).
  const double pcv_m = 0.002 + (50.0 - 30.0) / 30.0 * 0.002;
  EXPECT_NEAR(model->range_correction_m(l1, direction), -0.1 * std::sin(el) + pcv_m, 1e-12);
  // L2: north 0.01, east -0.02, up 0.05.
  const double e_dot_pco = std::cos(el) * std::cos(az) * 0.01 - std::cos(el) * std::sin(az) * 0.02 + std::sin(el) * 0.05;
  EXPECT_NEAR(model->range_correction_m(l2, direction), -e_dot_pco, 1e-12);
  // QZSS J01 falls back to G01; Galileo E5a (no E05) to the closest GPS frequency, G02 here.
  EXPECT_EQ(model->frequency_of(qzss)->code, "G01");
  EXPECT_EQ(model->frequency_of(galileo)->code, "G02");
  EXPECT_EQ(antex_frequency_code(Signal::parse("C2I").value()), "C02");
  EXPECT_EQ(antex_frequency_code(Signal::parse("C1P").value()), "C01");
  EXPECT_EQ(antex_frequency_code(Signal::parse("R2C").value()), "R02");
  EXPECT_EQ(antex_frequency_code(Signal::parse("E7Q").value()), "E07");
}

// Replaces the first line holding `needle` by `replacement` (a full line with its newline).
std::string with_line(std::string text, const std::string& needle, const std::string& replacement) {
  const size_t at = text.find(needle);
  const size_t begin = text.rfind('\n', at) + 1;
  const size_t end = text.find('\n', at) + 1;
  return text.replace(begin, end - begin, replacement);
}

// The error of a broken file: its message, which must name the file and a line.
std::string error_of(const std::string& text) {
  auto file = parse_antex("broken.atx", text);
  if (file) return "(parsed)";
  EXPECT_EQ(file.error().code, ErrorCode::kParse) << file.error().message;
  EXPECT_NE(file.error().message.find("broken.atx:"), std::string::npos) << file.error().message;
  return file.error().message;
}

TEST(Antex, MalformedRecordsAreRefusedWithFileAndLine) {
  const std::string good = sample_file();
  EXPECT_NE(error_of("hello\n").find("ANTEX VERSION / SYST"), std::string::npos);
  EXPECT_NE(error_of(header().substr(0, header().rfind("END"))).find("END OF HEADER"), std::string::npos);
  // A non-number and a NaN in the offsets.
  EXPECT_NE(error_of(with_line(good, "      0.00      0.00    100.00", record("      0.00      0.00    abc.00", "NORTH / EAST / UP")))
                .find("phase centre offset"),
            std::string::npos);
  EXPECT_NE(error_of(with_line(good, "      0.00      0.00    100.00", record("      0.00      0.00       nan", "NORTH / EAST / UP")))
                .find("phase centre offset"),
            std::string::npos);
  // An absurd offset, a NOAZI row with a value missing, an infinite PCV.
  EXPECT_NE(error_of(with_line(good, "      0.00      0.00    100.00", offset(0, 0, 1e7))).find("within"), std::string::npos);
  EXPECT_NE(error_of(with_line(good, "   NOAZI    0.00    2.00", row("   NOAZI", {0, 2, 4}))).find("expected 4 PCV values"),
            std::string::npos);
  EXPECT_NE(error_of(with_line(good, "   NOAZI    0.00    2.00", "   NOAZI    0.00    2.00     inf    6.00\n"))
                .find("PCV value"),
            std::string::npos);
  // A zenith grid that is no grid, a DAZI that does not divide 360, an azimuth row out of order.
  EXPECT_NE(error_of(with_line(good, "     0.0  90.0  30.0", record("     0.0  90.0   0.0", "ZEN1 / ZEN2 / DZEN"))).find("DZEN"),
            std::string::npos);
  EXPECT_NE(error_of(with_line(good, "    90.0", record("    70.0", "DAZI"))).find("divisor of 360"), std::string::npos);
  EXPECT_NE(error_of(with_line(good, "    90.0    0.00", row("    45.0", {0, 3, 6, 9}))).find("azimuth row 90"),
            std::string::npos);
  // A block cut short, and a frequency without its end.
  const std::string cut = good.substr(0, good.rfind("END OF ANTENNA") - 60);
  EXPECT_NE(error_of(cut).find("END OF"), std::string::npos) << error_of(cut);
  const std::string unended = header() + antenna("TEST0           NONE", "", 0.0,
                                                  record("   G01", "START OF FREQUENCY") + offset(0, 0, 1) +
                                                      row("   NOAZI", {0, 0, 0, 0}) +
                                                      frequency("G02", offset(0, 0, 1) + row("   NOAZI", {0, 0, 0, 0})));
  EXPECT_NE(error_of(unended).find("expected END OF FREQUENCY of G01"), std::string::npos) << error_of(unended);
  // A type with a blank inside (no IGS code has one): no scenario or RINEX header could name it
  // (found by fuzz_antex: "LEIAR25.R3  '" in columns 1-16).
  const std::string blank_type = header() + antenna("LEIAR25.R3  '   LEIT", "", 0.0,
                                                    frequency("G01", offset(0, 0, 1) + row("   NOAZI", {0, 0, 0, 0})));
  EXPECT_NE(error_of(blank_type).find("broken.atx:5: expected an IGS antenna type without blanks in columns 1-16, got "
                                      "'LEIAR25.R3  ''"),
            std::string::npos)
      << error_of(blank_type);
  // The line number is the broken one: the antenna's end (line 6) comes without its TYPE / SERIAL NO.
  const std::string no_type = header() + record("", "START OF ANTENNA") + record("     0.0", "DAZI") + record("", "END OF ANTENNA");
  EXPECT_NE(error_of(no_type).find("broken.atx:6"), std::string::npos) << error_of(no_type);
}

// The generator with and without an antenna whose only term is 0.1 m up on L1.
TEST(Antex, GeneratorUpOffsetShortensL1ByItsSineOfElevation) {
  const std::string text = header() + antenna("UPONLY          NONE", "", 0.0,
                                              frequency("G01", offset(0, 0, 100) + row("   NOAZI", {0, 0, 0, 0})) +
                                                  frequency("G02", offset(0, 0, 0) + row("   NOAZI", {0, 0, 0, 0})));
  const AntexFile file = parse_antex("up.atx", text).value();
  const GnssTime start = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  static const orbits::BroadcastEphemerides ephemerides(orbits::make_nominal_constellation(start, 600.0).value());
  const Geodetic site{55.49, 8.46, 60.0};
  GeneratorSettings settings;
  settings.signals = {Signal::parse("G1C").value(), Signal::parse("G2W").value()};
  settings.profile = builtin_profile("ideal").value();
  const auto position = std::make_shared<StaticPosition>(geodetic_to_ecef(site));
  ObservationGenerator plain(settings, ephemerides, position);
  settings.antenna_phase_centre = std::make_shared<const AntennaPhaseCentre>(
      AntennaPhaseCentre::create(*file.find("UPONLY").value(), settings.signals, "up.atx").value());
  ObservationGenerator with_antenna(settings, ephemerides, position);
  const auto a = plain.observe(start).value();
  const auto b = with_antenna.observe(start).value();
  ASSERT_EQ(a.satellites.size(), b.satellites.size());
  int compared = 0;
  for (size_t i = 0; i < a.satellites.size(); ++i) {
    const auto& sa = a.satellites[i];
    const auto& sb = b.satellites[i];
    ASSERT_EQ(sa.signals.size(), sb.signals.size());
    for (size_t k = 0; k < sa.signals.size(); ++k) {
      const SignalMeasurement& ma = sa.signals[k];
      const SignalMeasurement& mb = sb.signals[k];
      const double wavelength_m = constants::kSpeedOfLight_mps / ma.carrier_hz;
      const double expected_m = ma.signal.band == '1' ? -0.1 * std::sin(sa.direction.elevation_deg * M_PI / 180.0) : 0.0;
      EXPECT_NEAR(mb.antenna_phase_centre_m, expected_m, 1e-12);
      EXPECT_NEAR(mb.pseudorange_m - ma.pseudorange_m, expected_m, 1e-7) << sa.satellite.to_string();
      EXPECT_NEAR((mb.carrier_phase_cycles - ma.carrier_phase_cycles) * wavelength_m, expected_m, 1e-7);
      EXPECT_EQ(mb.doppler_hz, ma.doppler_hz);
      ++compared;
    }
  }
  EXPECT_GE(compared, 8);
}

}  // namespace
}  // namespace skytrace::receiver
