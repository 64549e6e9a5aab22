// Receiver realism acceptance on the independent stations (docs/validation.md): NYA1 2024-124 and
// SLAC 2021-118, both Trimble NetR9, simulated with the profile constants fitted on ESBC only
// (ESBC itself: Reproducibility.EsbcRealismAcceptanceOnL1). GPS and Galileo L1, satellites above
// 10 degrees. Limits: overlap >= 95 % both ways, pseudorange p68 <= 2.0 m, Doppler p68 <= 0.10
// m/s, epoch-differenced phase p68 <= 1 cm, C/N0 mean absolute difference <= 2.5 dB-Hz.
// What physics cannot meet here is asserted at its measured size, so that it cannot grow unseen:
// the phase at NYA1 (the real ionosphere's 30-s changes that Klobuchar does not follow, and the
// GPS IIR clocks' short-term noise, absent from broadcast clocks). SLAC, simulated over the hour
// its precise clocks cover, meets every limit.
// NYA1 also checks the NetR9's output rule (tracking.output_requires_ephemeris): rising satellites
// appear only once their first record has been transmitted (docs/validation.md).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <map>
#include <set>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

struct Limits {
  double sim_in_real = 0.95;
  double phase_m = 0.01;
};

class ValidationStations : public ::testing::Test {
 protected:
  // The scenarios name the data as ../../../shared/data from their folder.
  static std::filesystem::path data_in_scenario() {
    return (test::source_dir() / "examples/validation/../../../shared/data").lexically_normal();
  }

  // Runs `scenario` (examples/validation) into a fresh folder, returned.
  static std::filesystem::path run_scenario(const std::string& scenario) {
    const auto scenario_path = test::source_dir() / "examples/validation" / scenario;
    const auto out = test::make_temp_dir("validation_" + scenario);
    auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                               test::shell_quote(scenario_path.string()) + " --out " +
                               test::shell_quote(out.string()) + " --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return out;
  }

  // Runs `scenario` (examples/validation) and compares it with `real`; the JSON rows by signal.
  std::map<std::string, nlohmann::json> run_and_compare(const std::string& scenario, const std::string& real,
                                                        const std::vector<std::string>& navs,
                                                        const std::string& signals,
                                                        const std::string& extra = "",
                                                        std::filesystem::path* out_dir = nullptr) {
    if (!std::filesystem::exists(data_in_scenario() / real)) {
      return {};
    }
    const auto out = run_scenario(scenario);
    if (out_dir != nullptr) *out_dir = out;
    std::string command = test::shell_quote(test::skytrace_executable().string()) + " compare " +
                          test::shell_quote((data_in_scenario() / real).string()) + " " +
                          test::shell_quote((out / "obs.rnx").string());
    for (const auto& nav : navs) command += " --nav " + test::shell_quote((data_in_scenario() / nav).string());
    command += " --min-elevation-deg 10" + (signals.empty() ? std::string() : " --signals " + signals) + " " + extra +
               " --json " + test::shell_quote((out / "c.json").string());
    const auto r = test::run_command(command);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(out / "c.json");
    std::map<std::string, nlohmann::json> rows;
    const nlohmann::json report = nlohmann::json::parse(in);
    for (const auto& row : report.at("signals")) rows[row.at("signal").get<std::string>()] = row;
    return rows;
  }

  static void check(const nlohmann::json& row, bool has_doppler, const Limits& limits) {
    SCOPED_TRACE(row.dump(1));
    EXPECT_GE(row.at("overlap").at("real_in_sim").get<double>(), 0.95);
    EXPECT_GE(row.at("overlap").at("sim_in_real").get<double>(), limits.sim_in_real);
    EXPECT_LE(row.at("pseudorange_m").at("abs_p68").get<double>(), 2.0);
    if (has_doppler) {
      EXPECT_GT(row.at("doppler_mps").at("count").get<int>(), 500);
      EXPECT_LE(row.at("doppler_mps").at("abs_p68").get<double>(), 0.10);
    }
    EXPECT_LE(row.at("phase_difference_m").at("abs_p68").get<double>(), limits.phase_m);
    EXPECT_GT(row.at("cn0_dbhz").at("count").get<int>(), 500);
    EXPECT_LE(row.at("cn0_dbhz").at("mean_abs_difference").get<double>(), 2.5);
  }
};

TEST_F(ValidationStations, Nya1NetR9WithEsbcConstants) {
  const auto rows = run_and_compare("nya1-realistic.yaml",
                                    "real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx",
                                    {"real/nya1_2024124/NYA100NOR_S_20241240000_01D_GN.rnx",
                                     "real/nya1_2024124/NYA100NOR_S_20241240000_01D_EN.rnx"},
                                    "G1C,E1X");
  if (rows.empty()) GTEST_SKIP() << "NYA1 data absent (../shared/data beside the checkout)";
  ASSERT_EQ(rows.size(), 2u);
  // Measured: G1C phase 0.019 m, E1X 0.0115 m. E1X sim in real 99.9 % (87.3 % before the profile
  // output satellites only with a decoded ephemeris): the acceptance limit holds.
  check(rows.at("G1C"), true, Limits{0.95, 0.022});
  check(rows.at("E1X"), true, Limits{0.95, 0.013});
}

// The NetR9 outputs a satellite only once it holds a broadcast ephemeris for it. The station's own
// navigation file dates the first records: E10 transmitted 00:33:25 (real observations from
// 00:34:00), E30 01:01:25 and E11 01:28:25 (none in the first hour), G10 00:45:36 (from 00:46:00),
// G22 00:34:12 (from 00:34:30). Satellites tracked at the start are output at once.
TEST_F(ValidationStations, Nya1NetR9OutputsRisingSatellitesOnceTheirEphemerisIsTransmitted) {
  const std::string real_name = "real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx";
  if (!std::filesystem::exists(data_in_scenario() / real_name)) {
    GTEST_SKIP() << "NYA1 data absent (../shared/data beside the checkout)";
  }
  const auto out = run_scenario("nya1-realistic.yaml");
  const auto sim = io::read_rinex_obs(out / "obs.rnx");
  ASSERT_TRUE(sim) << sim.error().message;
  const auto real = io::read_rinex_obs(data_in_scenario() / real_name);
  ASSERT_TRUE(real) << real.error().message;
  const GnssTime start = GnssTime::parse_iso8601("2024-05-03T00:00:00", TimeScale::kGpst).value();
  const GnssTime end = start + 3600.0;
  // First epoch (before `end`) at which a satellite is in the file.
  const auto first = [&](const io::ObservationFile& file, const char* name) -> std::optional<GnssTime> {
    const SatelliteId sat = SatelliteId::parse(name).value();
    for (const auto& epoch : file.epochs) {
      if (epoch.time < end && epoch.find(sat) != nullptr) return epoch.time;
    }
    return std::nullopt;
  };
  const auto at = [&](const char* hms) {
    return GnssTime::parse_iso8601(std::string("2024-05-03T") + hms, TimeScale::kGpst).value();
  };
  EXPECT_FALSE(first(*sim, "E11")) << "E11's first record was transmitted at 01:28:25";
  EXPECT_FALSE(first(*sim, "E30")) << "E30's first record was transmitted at 01:01:25";
  EXPECT_FALSE(first(*real, "E11"));
  EXPECT_FALSE(first(*real, "E30"));
  const auto e10 = first(*sim, "E10");
  ASSERT_TRUE(e10);
  EXPECT_GE(*e10, at("00:33:25"));
  EXPECT_LE(*e10 - at("00:33:25"), 30.0) << e10->to_iso8601(TimeScale::kGpst);  // within one epoch
  EXPECT_LE(*e10 - *first(*real, "E10"), 30.0);
  EXPECT_GE(*e10 - *first(*real, "E10"), -30.0);
  // GPS: the epochs of the real receiver exactly.
  EXPECT_EQ(first(*sim, "G10"), at("00:46:00"));
  EXPECT_EQ(first(*real, "G10"), at("00:46:00"));
  EXPECT_EQ(first(*sim, "G22"), at("00:34:30"));
  EXPECT_EQ(first(*real, "G22"), at("00:34:30"));
  // Tracked from the start: output from the first epoch, as in the real file.
  for (const char* name : {"G05", "E02"}) {
    EXPECT_EQ(first(*sim, name), start) << name;
    EXPECT_EQ(first(*real, name), start) << name;
  }
  // The first output of a satellite that waited starts its arc for the user (LLI 1), as the
  // NetR9 does.
  const SatelliteId g10 = SatelliteId::parse("G10").value();
  for (const auto& epoch : sim->epochs) {
    if (const auto* record = epoch.find(g10)) {
      ASSERT_GE(record->values.size(), 2u);
      EXPECT_EQ(record->values[1].lli & 1, 1);  // L1C
      break;
    }
  }
}

TEST_F(ValidationStations, SlacNetR9WithEsbcConstants) {
  const auto rows = run_and_compare("slac-realistic.yaml", "real/slac_2021118/slac1180.21o",
                                    {"real/slac_2021118/brdc1180.21n"}, "G1C");
  if (rows.empty()) GTEST_SKIP() << "SLAC data absent (../shared/data beside the checkout)";
  ASSERT_EQ(rows.size(), 1u);
  // RINEX 2.11 without Doppler. The run is 19:30-20:30, the hour CODE's clock file covers: phase
  // 0.0083 m, the acceptance limit holds (0.0114 m over 19:00-21:00, when the half hours outside the
  // clock file silently had broadcast truth).
  EXPECT_EQ(rows.at("G1C").at("doppler_mps").at("count").get<int>(), 0);
  EXPECT_GT(rows.at("G1C").at("phase_difference_m").at("count").get<int>(), 1000);
  check(rows.at("G1C"), false, Limits{0.95, 0.01});
}

// Leave one out (docs/validation.md, scripts/validate-leave-one-out): recordings nobody fitted on,
// every signal both files have, with the open-sky limits for them (overlap >= 95 % both
// ways, code p68 <= 2.0 m; C/N0 cannot be compared: neither file has signal strengths). What is not
// met is asserted at its measured size so that it cannot grow unseen.
void expect_open_sky_limits(const nlohmann::json& row, double code_p68_m = 2.0) {
  SCOPED_TRACE(row.dump(1));
  EXPECT_GE(row.at("overlap").at("real_in_sim").get<double>(), 0.95);
  EXPECT_GE(row.at("overlap").at("sim_in_real").get<double>(), 0.95);
  EXPECT_LE(row.at("pseudorange_m").at("abs_p68").get<double>(), code_p68_m);
}

// GEONET 0759, Trimble 5700 + TRM29659.00 (antenna from the header's IGS name), RINEX 2.10, epochs
// tagged up to 5 ms off the second (matched within 10 ms, moved with the simulated Doppler).
// Measured: G1C p68 1.13 m, G2W 1.08 m, overlap 100 / 98.4 %.
TEST_F(ValidationStations, LeaveOneOutGsi0759Trimble5700) {
  const auto rows = run_and_compare("gsi0759-realistic.yaml", "real/gsi_0759_3040_2005092/07590920.05o",
                                    {"real/gsi_0759_3040_2005092/07590920.05n"}, "", "--epoch-tolerance-ms 10");
  if (rows.empty()) GTEST_SKIP() << "GSI data absent (../shared/data beside the checkout)";
  ASSERT_EQ(rows.size(), 2u);
  for (const char* signal : {"G1C", "G2W"}) {
    expect_open_sky_limits(rows.at(signal));
    EXPECT_GT(rows.at(signal).at("pseudorange_m").at("count").get<int>(), 700) << signal;
  }
}

// KMS3 2022-159, PolaRx5 + ASH701945E_M, every signal of the scenario. Measured code p68 over the
// limit: R1C 2.03, R2C 2.92, R2P 2.76, C5P 2.05 m (G5Q was 2.86 before GPS III's L5 code term,
// fitted on ESBC, and is 0.81 with it); the rest meets every limit, R3Q
// included (GLONASS-K1 R11 and M+ R21 transmit L3OC: the other GLONASS satellites in view, plain M
// and M+ whose L3 payload is off, do not).
TEST_F(ValidationStations, LeaveOneOutKms3PolaRx5) {
  std::filesystem::path out;
  const auto rows = run_and_compare("kms3-realistic.yaml", "real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_30S_MO.rnx",
                                    {"real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_MN.rnx"}, "", "", &out);
  if (rows.empty()) GTEST_SKIP() << "KMS3 data absent (../shared/data beside the checkout)";
  const std::map<std::string, double> measured = {
      {"R1C", 2.1}, {"R2C", 3.0}, {"R2P", 2.8}, {"C5P", 2.1}};
  for (const char* signal : {"G1C", "G2L", "G2W", "G5Q", "E1C", "E5Q", "E6C", "E7Q", "E8Q", "R1C", "R1P", "R2C",
                             "R2P", "R3Q", "C2I", "C5P", "C6I", "C7I"}) {
    ASSERT_TRUE(rows.count(signal)) << signal;
    const auto it = measured.find(signal);
    expect_open_sky_limits(rows.at(signal), it == measured.end() ? 2.0 : it->second);
  }
  EXPECT_GT(rows.at("R3Q").at("pseudorange_m").at("count").get<int>(), 30);
  // R3Q in the simulated file: R11 (K1 SVN 805) and R21 (M+ 855), not R03/R10/R13/R20 (plain M).
  auto sim = io::read_rinex_obs(out / "obs.rnx");
  ASSERT_TRUE(static_cast<bool>(sim));
  std::set<int> with_l3;
  size_t column = 0;
  const auto& types = sim->header.observation_types.at(GnssSystem::kGlonass);
  for (; column < types.size() && types[column].code != "C3Q"; ++column) {
  }
  ASSERT_LT(column, types.size());
  for (const auto& epoch : sim->epochs) {
    for (const auto& s : epoch.satellites) {
      if (s.satellite.system == GnssSystem::kGlonass && column < s.values.size() && s.values[column].value.has_value()) {
        with_l3.insert(s.satellite.number);
      }
    }
  }
  EXPECT_EQ(with_l3, (std::set<int>{11, 21}));
}

}  // namespace
}  // namespace skytrace
