// `skytrace iq` checked by a real software receiver: GNSS-SDR (Debian 12's gnss-sdr 0.0.17) runs
// the configuration skytrace wrote on the samples as they are, and what it makes of them is held
// against the same run's obs.rnx, nav.rnx and the scenario's position (docs/iq.md).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <cstdio>
#include <functional>
#include <regex>
#include <set>

#include "process.hpp"
#include "skytrace/baseband/beidou_b1i.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::filesystem::path contract(const std::string& name) {
  return test::shared_data_dir().parent_path() / "contract" / name;
}

std::optional<std::filesystem::path> file_ending(const std::filesystem::path& dir, char last) {
  if (!std::filesystem::exists(dir)) return std::nullopt;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (!name.empty() && name.back() == last) return entry.path();
  }
  return std::nullopt;
}

class IqGnssSdr : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!test::program_available("gnss-sdr")) GTEST_SKIP() << "gnss-sdr absent (scripts/setup installs it)";
    if (!std::filesystem::exists(contract("esbc-open-sky.yaml")) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
    }
  }
  // skytrace iq on a contract scenario (at 1 s, the gnss-sdr profile) for one band, then GNSS-SDR
  // in the output folder; the samples are removed afterwards (up to a gigabyte).
  std::filesystem::path run_both(const std::string& band, const std::string& arguments, bool keep_samples = false) {
    const auto dir = test::make_temp_dir("iq_gnss_sdr_" + band);
    const std::string signal = band == "L1" ? "G1C" : band == "E1" ? "E1C" : band == "B1" ? "C2I" : "R1C";
    const auto iq = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " iq " +
                                      test::shell_quote(contract("esbc-open-sky.yaml").string()) + " --out " +
                                      test::shell_quote(dir.string()) + " --band " + band + " " + arguments +
                                      " --quiet --set time.interval_s=1 --set receiver.profile=gnss-sdr --set "
                                      "'receiver.signals=[" + signal + "]' 2>&1");
    EXPECT_EQ(iq.exit_code, 0) << iq.output;
    run_receiver(dir, band);
    if (!keep_samples) std::filesystem::remove(dir / ("iq_" + band + ".sc8"));
    return dir;
  }
  // GNSS-SDR on the samples in `dir` (its earlier outputs there replaced).
  static void run_receiver(const std::filesystem::path& dir, const std::string& band) {
    std::filesystem::remove_all(dir / ("gnss-sdr-" + band));
    std::filesystem::create_directories(dir / ("gnss-sdr-" + band));
    const auto receiver = test::run_command("cd " + test::shell_quote(dir.string()) + " && timeout 600 gnss-sdr --config_file=gnss-sdr-" +
                                            band + ".conf > gnss-sdr.log 2>&1");
    EXPECT_EQ(receiver.exit_code, 0) << receiver.output;
  }
};

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// GNSS-SDR's fixes in its log, against the contract's antenna (marker + 0.216 m up): count, worst.
std::pair<int, double> fixes_against_antenna(const std::string& log) {
  const Eigen::Vector3d marker(3582105.2910, 532589.7313, 5232754.8054);
  const Geodetic marker_geodetic = ecef_to_geodetic(marker);
  const Eigen::Vector3d antenna = enu_to_ecef(Eigen::Vector3d(0.0, 0.0, 0.2160), marker_geodetic);
  const std::regex position(R"(Lat = ([-0-9.]+) \[deg\], Long = ([-0-9.]+) \[deg\], Height = ([-0-9.]+) \[m\])");
  int fixes = 0;
  double worst_m = 0.0;
  for (std::sregex_iterator it(log.begin(), log.end(), position), end; it != end; ++it) {
    const Eigen::Vector3d p = geodetic_to_ecef(Geodetic{std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3])});
    worst_m = std::max(worst_m, (p - antenna).norm());
    ++fixes;
  }
  return {fixes, worst_m};
}

// The satellites of a run's obs.rnx (those its samples hold), and those of them whose ephemeris
// GNSS-SDR accepts (it requires IODC == IODE over all ten bits:
// Gps_Navigation_Message::satellite_validation; G18's record has IODC 388, IODE 132).
std::pair<std::set<std::string>, std::set<std::string>> satellites_in_samples(const std::filesystem::path& dir) {
  std::set<std::string> in_samples;
  std::set<std::string> usable_by_gnss_sdr;
  auto sim = io::read_rinex_obs(dir / "obs.rnx");
  auto sim_nav = orbits::read_rinex_nav(dir / "nav.rnx");
  EXPECT_TRUE(sim && sim_nav);
  if (!sim || !sim_nav) return {};
  for (const auto& epoch : sim->epochs) {
    for (const auto& s : epoch.satellites) in_samples.insert(s.satellite.to_string());
  }
  for (const auto& eph : sim_nav->kepler) {
    if (eph.iodc == eph.iode && in_samples.contains(eph.satellite.to_string())) {
      usable_by_gnss_sdr.insert(eph.satellite.to_string());
    }
  }
  return {in_samples, usable_by_gnss_sdr};
}

// The satellites of GNSS-SDR's RINEX observation file in `folder` (none without one).
std::set<std::string> satellites_observed(const std::filesystem::path& folder) {
  std::set<std::string> observed;
  const auto path = file_ending(folder, 'O');
  if (!path) return observed;
  auto real = io::read_rinex_obs(*path);
  if (!real) return observed;
  for (const auto& epoch : real->epochs) {
    for (const auto& s : epoch.satellites) observed.insert(s.satellite.to_string());
  }
  return observed;
}

// A record GNSS-SDR decoded against the one it came from: the broadcast values are the RINEX
// ones scaled to integers, so they come back to the last digit GNSS-SDR writes.
void expect_same_orbit_and_clock(const orbits::KeplerEphemeris& decoded, const orbits::KeplerEphemeris& ours) {
  EXPECT_EQ(decoded.toe - ours.toe, 0.0);
  EXPECT_NEAR(decoded.sqrt_a_sqrtm, ours.sqrt_a_sqrtm, 1e-9 * ours.sqrt_a_sqrtm);
  EXPECT_NEAR(decoded.eccentricity, ours.eccentricity, 1e-9);
  EXPECT_NEAR(decoded.m0_rad, ours.m0_rad, 1e-9);
  EXPECT_NEAR(decoded.omega0_rad, ours.omega0_rad, 1e-9);
  EXPECT_NEAR(decoded.omega_rad, ours.omega_rad, 1e-9);
  EXPECT_NEAR(decoded.i0_rad, ours.i0_rad, 1e-9);
  EXPECT_NEAR(decoded.omega_dot_rad_per_s, ours.omega_dot_rad_per_s, 1e-15);
  EXPECT_NEAR(decoded.delta_n_rad_per_s, ours.delta_n_rad_per_s, 1e-15);
  EXPECT_NEAR(decoded.idot_rad_per_s, ours.idot_rad_per_s, 1e-15);
  EXPECT_NEAR(decoded.cuc_rad, ours.cuc_rad, 1e-9);
  EXPECT_NEAR(decoded.cus_rad, ours.cus_rad, 1e-9);
  EXPECT_NEAR(decoded.cic_rad, ours.cic_rad, 1e-9);
  EXPECT_NEAR(decoded.cis_rad, ours.cis_rad, 1e-9);
  EXPECT_NEAR(decoded.crs_m, ours.crs_m, 1e-6);
  EXPECT_NEAR(decoded.crc_m, ours.crc_m, 1e-6);
  EXPECT_NEAR(decoded.af0_s, ours.af0_s, 1e-12);
  EXPECT_NEAR(decoded.af1_s_per_s, ours.af1_s_per_s, 1e-17);
}

TEST_F(IqGnssSdr, OpenSkyDecodesTheEphemeridesAndFixesWithinFiveMetres) {
  const auto dir = run_both("L1", "--set time.duration_s=90", true);
  const auto satellites = satellites_in_samples(dir);
  const std::set<std::string>& in_samples = satellites.first;
  const std::set<std::string>& usable_by_gnss_sdr = satellites.second;
  // GNSS-SDR runs its blocks on threads of its own: when it acquires each satellite, and so which
  // ephemerides it holds by the end and where its first fixes fall, varies from run to run, more
  // under load (a fresh-clone CI run once ended without G07, another with a first fix 5.9 m off).
  // A run that misses a satellite or a limit is repeated once on the same samples; the limits below
  // are the same for either run.
  const auto run_complete = [&] {
    const auto [fixes, worst_m] = fixes_against_antenna(read_text(dir / "gnss-sdr.log"));
    return satellites_observed(dir / "gnss-sdr-L1") == usable_by_gnss_sdr && fixes >= 15 && worst_m <= 5.0;
  };
  if (!run_complete()) {
    std::cout << "GNSS-SDR's first run missed a satellite or a limit: run again on the same samples\n";
    run_receiver(dir, "L1");
  }
  std::filesystem::remove(dir / "iq_L1.sc8");
  const std::string log = read_text(dir / "gnss-sdr.log");
  ASSERT_GE(in_samples.size(), 8u);
  // It tracks every satellite of the samples.
  for (const auto& sat : in_samples) {
    const std::string prn = sat.substr(1);
    EXPECT_NE(log.find("for satellite GPS PRN " + prn), std::string::npos) << sat << " never tracked";
  }
  const auto real_obs_path = file_ending(dir / "gnss-sdr-L1", 'O');
  ASSERT_TRUE(real_obs_path) << log.substr(log.size() > 4000 ? log.size() - 4000 : 0);
  EXPECT_EQ(satellites_observed(dir / "gnss-sdr-L1"), usable_by_gnss_sdr);

  // The ephemerides it decoded are nav.rnx's records, field by field.
  auto sim_nav = orbits::read_rinex_nav(dir / "nav.rnx");
  ASSERT_TRUE(sim_nav);
  const auto real_nav_path = file_ending(dir / "gnss-sdr-L1", 'N');
  ASSERT_TRUE(real_nav_path);
  auto real_nav = orbits::read_rinex_nav(*real_nav_path);
  ASSERT_TRUE(real_nav) << real_nav.error().message;
  int compared = 0;
  for (const auto& decoded : real_nav->kepler) {
    const orbits::KeplerEphemeris* ours = nullptr;
    for (const auto& eph : sim_nav->kepler) {
      if (eph.satellite == decoded.satellite && eph.iode == decoded.iode) ours = &eph;
    }
    ASSERT_NE(ours, nullptr) << decoded.satellite.to_string() << " IODE " << decoded.iode << " is not in nav.rnx";
    SCOPED_TRACE(decoded.satellite.to_string());
    ++compared;
    EXPECT_EQ(decoded.toc - ours->toc, 0.0);
    EXPECT_EQ(decoded.health, ours->health);
    expect_same_orbit_and_clock(decoded, *ours);
    EXPECT_NEAR(decoded.group_delays.tgd_s, ours->group_delays.tgd_s, 1e-12);
  }
  EXPECT_EQ(compared, static_cast<int>(usable_by_gnss_sdr.size()));

  // Its observations against the run's own (common clock removed per epoch).
  const auto compared_json = dir / "compare.json";
  const auto cmp = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " compare " +
                                     test::shell_quote(real_obs_path->string()) + " " +
                                     test::shell_quote((dir / "obs.rnx").string()) + " --json " +
                                     test::shell_quote(compared_json.string()) + " 2>&1");
  ASSERT_EQ(cmp.exit_code, 0) << cmp.output;
  std::ifstream json_file(compared_json);
  const auto j = nlohmann::json::parse(json_file);
  const nlohmann::json* g1c = nullptr;
  for (const auto& s : j.at("signals")) {
    if (s.at("signal") == "G1C") g1c = &s;
  }
  ASSERT_NE(g1c, nullptr) << cmp.output;
  // GNSS-SDR runs its blocks on threads of its own: when it acquires and first fixes varies from run
  // to run (more under load), hence the room in the counts.
  EXPECT_GE(g1c->at("pseudorange_m").at("count").get<int>(), 100) << cmp.output;
  EXPECT_LE(g1c->at("pseudorange_m").at("abs_p68").get<double>(), 1.0) << cmp.output;
  EXPECT_LE(g1c->at("doppler_mps").at("abs_p68").get<double>(), 0.05) << cmp.output;
  EXPECT_LE(g1c->at("phase_difference_m").at("abs_p68").get<double>(), 0.01) << cmp.output;
  EXPECT_LE(g1c->at("cn0_dbhz").at("mean_abs_difference").get<double>(), 1.5) << cmp.output;

  // Its fixes: within 5 m of the antenna (the contract's marker, 0.216 m below the antenna).
  const auto [fixes, worst_m] = fixes_against_antenna(log);
  EXPECT_GE(fixes, 15);
  EXPECT_LE(worst_m, 5.0);
  std::cout << "GNSS-SDR: " << satellites_observed(dir / "gnss-sdr-L1").size() << " satellites, " << fixes << " fixes, worst 3D error " << worst_m
            << " m; " << g1c->dump() << "\n";
}

// Galileo E1 OS (E1-B with I/NAV, E1-C pilot, CBOC), 90 s at 5 MS/s: GNSS-SDR acquires every
// satellite, decodes the I/NAV words into nav.rnx's records and fixes. It tracks the pilot
// (track_pilot) but labels its observations 1B (C1B, L1B, D1B, S1B): they are compared with
// obs.rnx's E1C, the signal the samples take their power and timing from.
TEST_F(IqGnssSdr, GalileoInavDecodesToTheRecordsAndItFixesWithinFiveMetres) {
  const auto dir = run_both("E1", "--sample-rate 5e6 --set time.duration_s=90 --set models.ionosphere=none", true);
  auto sim = io::read_rinex_obs(dir / "obs.rnx");
  auto sim_nav = orbits::read_rinex_nav(dir / "nav.rnx");
  ASSERT_TRUE(sim && sim_nav);
  std::set<int> in_samples;
  for (const auto& epoch : sim->epochs) {
    for (const auto& s : epoch.satellites) in_samples.insert(s.satellite.number);
  }
  ASSERT_GE(in_samples.size(), 6u);
  // As for GPS: GNSS-SDR's threads make when it acquires each satellite vary from run to run; a
  // run that misses a satellite or a limit is repeated once on the same samples.
  const auto decoded_prns = [&] {
    std::set<int> prns;
    const auto nav_path = file_ending(dir / "gnss-sdr-E1", 'L');
    if (!nav_path) return prns;
    auto nav = orbits::read_rinex_nav(*nav_path);
    if (!nav) return prns;
    for (const auto& eph : nav->kepler) prns.insert(eph.satellite.number);
    return prns;
  };
  const auto run_complete = [&] {
    const auto [fixes, worst_m] = fixes_against_antenna(read_text(dir / "gnss-sdr.log"));
    return decoded_prns() == in_samples && fixes >= 15 && worst_m <= 5.0;
  };
  if (!run_complete()) {
    std::cout << "GNSS-SDR's first run missed a satellite or a limit: run again on the same samples\n";
    run_receiver(dir, "E1");
  }
  std::filesystem::remove(dir / "iq_E1.sc8");
  const std::string log = read_text(dir / "gnss-sdr.log");
  for (const int prn : in_samples) {
    const std::string name = std::string("Galileo PRN E") + (prn < 10 ? "0" : "") + std::to_string(prn);
    bool locked = false;
    for (std::size_t at = log.find("secondary code locked"); at != std::string::npos;
         at = log.find("secondary code locked", at + 1)) {
      locked |= log.substr(at, log.find('\n', at) - at).find(name + " ") != std::string::npos;
    }
    EXPECT_TRUE(locked) << name << " never synchronised to its pilot's secondary code";
  }
  // Every satellite's I/NAV record decoded: GNSS-SDR's RINEX (written after its first fix) holds
  // nav.rnx's records field by field.
  const auto nav_path = file_ending(dir / "gnss-sdr-E1", 'L');
  ASSERT_TRUE(nav_path) << log.substr(log.size() > 4000 ? log.size() - 4000 : 0);
  auto real_nav = orbits::read_rinex_nav(*nav_path);
  ASSERT_TRUE(real_nav) << real_nav.error().message;
  EXPECT_EQ(decoded_prns(), in_samples);
  for (const auto& decoded : real_nav->kepler) {
    SCOPED_TRACE(decoded.satellite.to_string());
    const orbits::KeplerEphemeris* ours = nullptr;
    for (const auto& eph : sim_nav->kepler) {
      if (eph.satellite == decoded.satellite && eph.iode == decoded.iode) ours = &eph;
    }
    ASSERT_NE(ours, nullptr) << "IODnav " << decoded.iode << " is not in nav.rnx";
    expect_same_orbit_and_clock(decoded, *ours);
    EXPECT_NEAR(decoded.group_delays.bgd_e1e5a_s, ours->group_delays.bgd_e1e5a_s, 2.4e-10);
    EXPECT_NEAR(decoded.group_delays.bgd_e1e5b_s, ours->group_delays.bgd_e1e5b_s, 2.4e-10);
  }
  // Its observations against obs.rnx (common clock removed per epoch), relabelled 1B -> 1C.
  const auto obs_path = file_ending(dir / "gnss-sdr-E1", 'O');
  ASSERT_TRUE(obs_path);
  {
    std::ifstream in(*obs_path);
    std::ofstream out(dir / "gnss-sdr-obs.rnx");
    for (std::string line; std::getline(in, line);) {
      if (line.find("SYS / # / OBS TYPES") != std::string::npos) {
        line = std::regex_replace(line, std::regex(R"(([CLDS])1B)"), "$011C");
      }
      out << line << "\n";
    }
  }
  const auto cmp = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " compare " +
                                     test::shell_quote((dir / "gnss-sdr-obs.rnx").string()) + " " +
                                     test::shell_quote((dir / "obs.rnx").string()) + " --json " +
                                     test::shell_quote((dir / "compare.json").string()) + " 2>&1");
  ASSERT_EQ(cmp.exit_code, 0) << cmp.output;
  std::ifstream json_file(dir / "compare.json");
  const auto j = nlohmann::json::parse(json_file);
  const nlohmann::json* e1c = nullptr;
  for (const auto& sig : j.at("signals")) {
    if (sig.at("signal") == "E1C") e1c = &sig;
  }
  ASSERT_NE(e1c, nullptr) << cmp.output;
  EXPECT_GE(e1c->at("pseudorange_m").at("count").get<int>(), 100) << cmp.output;
  EXPECT_LE(e1c->at("pseudorange_m").at("abs_p68").get<double>(), 1.0) << cmp.output;
  EXPECT_LE(e1c->at("doppler_mps").at("abs_p68").get<double>(), 0.05) << cmp.output;
  EXPECT_LE(e1c->at("phase_difference_m").at("abs_p68").get<double>(), 0.01) << cmp.output;
  EXPECT_LE(e1c->at("cn0_dbhz").at("mean_abs_difference").get<double>(), 1.5) << cmp.output;
  const auto [fixes, worst_m] = fixes_against_antenna(log);
  EXPECT_GE(fixes, 15);
  EXPECT_LE(worst_m, 5.0);
  std::cout << "GNSS-SDR Galileo: " << in_samples.size() << " satellites in the samples, " << real_nav->kepler.size()
            << " records decoded, " << fixes << " fixes, worst 3D " << worst_m << " m; " << e1c->dump() << "\n";
}

// GNSS-SDR's pseudoranges against obs.rnx's for a system whose observation epochs GNSS-SDR tags
// off the instant it measures (GLONASS, BeiDou): per common epoch both less their mean over the
// satellites, then the tag offset fitted with the range rates; returns the offset and the p68 of
// what remains.
std::pair<double, double> code_after_time_tag_fit(const io::ObservationFile& real, const io::ObservationFile& sim,
                                                  GnssSystem system, const std::string& code,
                                                  const std::string& doppler,
                                                  const std::function<double(int)>& wavelength_m_of) {
  auto column = [system](const io::ObservationFile& f, const std::string& wanted) {
    const auto& types = f.header.observation_types.at(system);
    for (size_t i = 0; i < types.size(); ++i) {
      if (types[i].code == wanted) return i;
    }
    return types.size();
  };
  const size_t real_c = column(real, code), sim_c = column(sim, code), sim_d = column(sim, doppler);
  std::vector<std::pair<double, double>> centred;  // (residual, range rate)
  for (const auto& re : real.epochs) {
    const io::ObservationEpoch* se = nullptr;
    for (const auto& e : sim.epochs) {
      if (std::abs(e.time - re.time) < 1e-3) se = &e;
    }
    if (se == nullptr) continue;
    std::vector<std::pair<double, double>> here;
    for (const auto& rs : re.satellites) {
      const auto* ss = se->find(rs.satellite);
      if (ss == nullptr || real_c >= rs.values.size() || !rs.values[real_c].value || sim_c >= ss->values.size() ||
          !ss->values[sim_c].value || sim_d >= ss->values.size() || !ss->values[sim_d].value) {
        continue;
      }
      here.push_back({*rs.values[real_c].value - *ss->values[sim_c].value,
                      -*ss->values[sim_d].value * wavelength_m_of(rs.satellite.number)});
    }
    if (here.size() < 4) continue;
    double mean_r = 0.0, mean_v = 0.0;
    for (const auto& [r, v] : here) {
      mean_r += r / static_cast<double>(here.size());
      mean_v += v / static_cast<double>(here.size());
    }
    for (const auto& [r, v] : here) centred.push_back({r - mean_r, v - mean_v});
  }
  if (centred.size() < 20) return {0.0, 1e9};
  double rv = 0.0, vv = 0.0;
  for (const auto& [r, v] : centred) {
    rv += r * v;
    vv += v * v;
  }
  const double tag_offset_s = rv / vv;
  std::vector<double> residual;
  for (const auto& [r, v] : centred) residual.push_back(std::abs(r - tag_offset_s * v));
  std::sort(residual.begin(), residual.end());
  return {tag_offset_s, residual[residual.size() * 68 / 100]};
}

// A copy of a GNSS-SDR RINEX file without the header lines of `labels` (and with `replace` applied
// to TIME OF FIRST OBS), for the fields GNSS-SDR writes malformed (docs/iq.md).
void copy_repaired(const std::filesystem::path& from, const std::filesystem::path& to,
                   const std::vector<std::string>& labels, const std::pair<std::string, std::string>& replace = {}) {
  std::ifstream in(from);
  std::ofstream out(to);
  for (std::string line; std::getline(in, line);) {
    bool drop = false;
    for (const auto& label : labels) drop = drop || line.find(label) != std::string::npos;
    if (drop) continue;
    if (!replace.first.empty() && line.find("TIME OF FIRST OBS") != std::string::npos &&
        line.find(replace.first) != std::string::npos) {
      line.replace(line.find(replace.first), replace.first.size(), replace.second);
    }
    out << line << "\n";
  }
}

// GLONASS L1OF (FDMA around 1602 MHz, 9 MS/s, 60 s): GNSS-SDR tracks every satellite, decodes the
// strings into nav.rnx's records and fixes. Its GLONASS observation epochs are tagged about 60 ms
// off the instant it measures (GNSS-SDR's receiver time, not steered for GLONASS): that offset
// times each satellite's range rate is fitted out with the clock before the code is compared.
TEST_F(IqGnssSdr, GlonassStringsDecodeToTheRecordsAndItFixes) {
  const auto dir = run_both("G1", "--sample-rate 9e6 --set time.duration_s=60 --set models.ionosphere=none", true);
  // A run without its fixes (GNSS-SDR's acquisition late under load) is repeated once on the same
  // samples, as for GPS and BeiDou.
  const auto run_complete = [&] {
    const auto [fixes, worst_m] = fixes_against_antenna(read_text(dir / "gnss-sdr.log"));
    return file_ending(dir / "gnss-sdr-G1", 'G') && fixes >= 10 && worst_m <= 20.0;
  };
  if (!run_complete()) {
    std::cout << "GNSS-SDR's first run missed a fix or a limit: run again on the same samples\n";
    run_receiver(dir, "G1");
  }
  std::filesystem::remove(dir / "iq_G1.sc8");
  const std::string log = read_text(dir / "gnss-sdr.log");
  auto sim = io::read_rinex_obs(dir / "obs.rnx");
  auto sim_nav = orbits::read_rinex_nav(dir / "nav.rnx");
  ASSERT_TRUE(sim && sim_nav);
  std::set<int> slots;
  for (const auto& epoch : sim->epochs) {
    for (const auto& s : epoch.satellites) slots.insert(s.satellite.number);
  }
  ASSERT_GE(slots.size(), 6u);
  // GNSS-SDR searches GLONASS by frequency channel (its table names one slot per channel, which
  // the decoded string 4 corrects): every channel of the samples is tracked.
  std::map<int, int> channel_of;
  for (const auto& slot : sim->header.glonass_slots) channel_of[slot.slot] = slot.channel;
  for (int slot : slots) {
    const std::string block = "(Block " + std::to_string(channel_of[slot]) + ")";
    bool tracked = false;
    for (size_t at = log.find("Tracking of GLONASS L1 C/A signal started"); at != std::string::npos;
         at = log.find("Tracking of GLONASS L1 C/A signal started", at + 1)) {
      tracked = tracked || log.substr(at, log.find('\n', at) - at).find(block) != std::string::npos;
    }
    EXPECT_TRUE(tracked) << "R" << slot << " (channel " << channel_of[slot] << ") never tracked";
  }
  // The strings decoded: every record GNSS-SDR wrote is one of nav.rnx's, field by field (its toe
  // written a second early by GNSS-SDR's own time conversion). GNSS-SDR 0.0.17 writes its TIME
  // SYSTEM CORR lines with a decimal in the integer reference-time field, which the reader refuses
  // as malformed: those header lines are dropped before reading.
  const auto real_nav_path = file_ending(dir / "gnss-sdr-G1", 'G');
  ASSERT_TRUE(real_nav_path) << log.substr(log.size() > 4000 ? log.size() - 4000 : 0);
  copy_repaired(*real_nav_path, dir / "gnss-sdr-nav.rnx", {"TIME SYSTEM CORR"});
  auto real_nav = orbits::read_rinex_nav(dir / "gnss-sdr-nav.rnx");
  ASSERT_TRUE(real_nav) << real_nav.error().message;
  ASSERT_GE(real_nav->glonass.size(), 4u);
  for (const auto& decoded : real_nav->glonass) {
    const orbits::GlonassEphemeris* ours = nullptr;
    for (const auto& eph : sim_nav->glonass) {
      if (eph.satellite == decoded.satellite && std::abs(eph.toe - decoded.toe) <= 1.0) ours = &eph;
    }
    ASSERT_NE(ours, nullptr) << decoded.satellite.to_string() << " is not in nav.rnx";
    SCOPED_TRACE(decoded.satellite.to_string());
    EXPECT_LE((decoded.position_m - ours->position_m).norm(), 0.5);       // 2^-11 km per axis
    EXPECT_LE((decoded.velocity_mps - ours->velocity_mps).norm(), 2e-3);  // 2^-20 km/s
    EXPECT_LE((decoded.acceleration_mps2 - ours->acceleration_mps2).norm(), 2e-6);
    EXPECT_NEAR(decoded.minus_tau_n_s, ours->minus_tau_n_s, 1e-9);
    EXPECT_NEAR(decoded.gamma_n, ours->gamma_n, 1e-12);
    EXPECT_EQ(decoded.frequency_channel, ours->frequency_channel);
    EXPECT_EQ(decoded.health, ours->health);
  }
  // Code and carrier against obs.rnx.
  const auto real_path = file_ending(dir / "gnss-sdr-G1", 'O');
  ASSERT_TRUE(real_path);
  auto real = io::read_rinex_obs(*real_path);
  ASSERT_TRUE(real) << real.error().message;
  const auto [tag_offset_s, p68_m] = code_after_time_tag_fit(
      *real, *sim, GnssSystem::kGlonass, "C1C", "D1C",
      [&](int slot) { return constants::kSpeedOfLight_mps / (1602.0e6 + 562.5e3 * channel_of[slot]); });
  EXPECT_LT(std::abs(tag_offset_s), 0.5);
  EXPECT_LE(p68_m, 5.0);  // GNSS-SDR's GLONASS loops do not narrow: about 3 m
  // The phase: skytrace compare's epoch-differenced carrier.
  const auto cmp = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " compare " +
                                     test::shell_quote(real_path->string()) + " " +
                                     test::shell_quote((dir / "obs.rnx").string()) + " --json " +
                                     test::shell_quote((dir / "compare.json").string()) + " 2>&1");
  ASSERT_EQ(cmp.exit_code, 0) << cmp.output;
  std::ifstream json_file(dir / "compare.json");
  const auto j = nlohmann::json::parse(json_file);
  const nlohmann::json* r1c = nullptr;
  for (const auto& sig : j.at("signals")) {
    if (sig.at("signal") == "R1C") r1c = &sig;
  }
  ASSERT_NE(r1c, nullptr);
  EXPECT_LE(r1c->at("phase_difference_m").at("abs_p68").get<double>(), 0.01) << cmp.output;
  const auto [fixes, worst_m] = fixes_against_antenna(log);
  EXPECT_GE(fixes, 10);
  EXPECT_LE(worst_m, 20.0);
  std::cout << "GNSS-SDR GLONASS: " << slots.size() << " satellites, " << real_nav->glonass.size()
            << " records decoded, time tag offset " << tag_offset_s << " s, code p68 " << p68_m << " m after it, "
            << fixes << " fixes, worst 3D " << worst_m << " m; " << r1c->dump() << "\n";
}

// BeiDou B1I, 90 s at 5 MS/s: GNSS-SDR decodes D1 (MEO, IGSO) and D2 (GEO: the record in ten
// pages of 3 s) into nav.rnx's records and fixes. Its BeiDou RINEX files need two repairs before
// they are read: the observation epochs are GPS time under a "BDT" label (its fixes and the
// epochs agree in GPS time), and the navigation header's TIME SYSTEM CORR and LEAP SECONDS lines
// leave integer fields blank or zero-padded (refused as malformed by the reader).
TEST_F(IqGnssSdr, BeidouD1AndD2DecodeToTheRecordsAndItFixesWithinFiveMetres) {
  const auto dir = run_both("B1", "--sample-rate 5e6 --set time.duration_s=90 --set models.ionosphere=none", true);
  auto sim = io::read_rinex_obs(dir / "obs.rnx");
  auto sim_nav = orbits::read_rinex_nav(dir / "nav.rnx");
  ASSERT_TRUE(sim && sim_nav);
  std::set<int> in_samples, geo_in_samples;
  for (const auto& epoch : sim->epochs) {
    for (const auto& s : epoch.satellites) {
      in_samples.insert(s.satellite.number);
      if (baseband::beidou_geo_prn(s.satellite.number)) geo_in_samples.insert(s.satellite.number);
    }
  }
  ASSERT_GE(in_samples.size(), 5u);
  ASSERT_GE(geo_in_samples.size(), 1u);  // C05 from Denmark
  // Whether GNSS-SDR synchronised to a GEO's D2 bits: D2's preamble found at 500 bit/s.
  const auto synchronised_to = [](const std::string& log, int prn) {
    const std::string locked = "bit synchronization locked in channel";
    const std::string tag = std::string("PRN ") + (prn < 10 ? "0" : "") + std::to_string(prn) + " ";
    bool synchronised = false;
    for (std::size_t at = log.find(locked); at != std::string::npos; at = log.find(locked, at + 1)) {
      const std::size_t end = log.find('\n', at);
      synchronised |= log.substr(at, end - at).find(tag) != std::string::npos;
    }
    return synchronised;
  };
  // As for GPS: under load GNSS-SDR's acquisition falls behind its file source and reaches the
  // satellites later in the samples (a fresh-clone CI run beside a soak test tracked the first ones
  // at 47 s and never fixed; one beside two fuzzers never reached the GEO). A run without a fix, or
  // without the bits of every GEO in the samples, is repeated once on the same samples.
  const auto run_complete = [&] {
    const std::string first_log = read_text(dir / "gnss-sdr.log");
    const auto [fixes, worst_m] = fixes_against_antenna(first_log);
    const bool every_geo = std::all_of(geo_in_samples.begin(), geo_in_samples.end(),
                                       [&](int prn) { return synchronised_to(first_log, prn); });
    return file_ending(dir / "gnss-sdr-B1", 'N') && file_ending(dir / "gnss-sdr-B1", 'O') && fixes >= 5 && worst_m <= 5.0 &&
           every_geo;
  };
  if (!run_complete()) {
    std::cout << "GNSS-SDR's first run missed a fix, a limit or a GEO: run again on the same samples\n";
    run_receiver(dir, "B1");
  }
  std::filesystem::remove(dir / "iq_B1.sc8");
  const std::string log = read_text(dir / "gnss-sdr.log");
  const auto nav_path = file_ending(dir / "gnss-sdr-B1", 'N');
  const auto obs_path = file_ending(dir / "gnss-sdr-B1", 'O');
  ASSERT_TRUE(nav_path && obs_path) << log.substr(log.size() > 4000 ? log.size() - 4000 : 0);
  copy_repaired(*nav_path, dir / "gnss-sdr-nav.rnx", {"TIME SYSTEM CORR", "LEAP SECONDS"});
  copy_repaired(*obs_path, dir / "gnss-sdr-obs.rnx", {}, {"BDT", "GPS"});
  auto real_nav = orbits::read_rinex_nav(dir / "gnss-sdr-nav.rnx");
  ASSERT_TRUE(real_nav) << real_nav.error().message;
  ASSERT_GE(real_nav->kepler.size(), 4u);
  std::set<int> geo_decoded;
  for (const auto& decoded : real_nav->kepler) {
    SCOPED_TRACE(decoded.satellite.to_string());
    if (baseband::beidou_geo_prn(decoded.satellite.number)) geo_decoded.insert(decoded.satellite.number);
    EXPECT_TRUE(in_samples.contains(decoded.satellite.number));
    const orbits::KeplerEphemeris* ours = nullptr;
    for (const auto& eph : sim_nav->kepler) {
      if (eph.satellite == decoded.satellite && std::abs(eph.toe - decoded.toe) < 1.0) ours = &eph;
    }
    ASSERT_NE(ours, nullptr) << "not in nav.rnx";
    EXPECT_NEAR(decoded.sqrt_a_sqrtm, ours->sqrt_a_sqrtm, 1e-9 * ours->sqrt_a_sqrtm);
    EXPECT_NEAR(decoded.eccentricity, ours->eccentricity, 1e-9);
    EXPECT_NEAR(decoded.m0_rad, ours->m0_rad, 1e-9);
    EXPECT_NEAR(decoded.omega0_rad, ours->omega0_rad, 1e-9);
    EXPECT_NEAR(decoded.omega_rad, ours->omega_rad, 1e-9);
    EXPECT_NEAR(decoded.i0_rad, ours->i0_rad, 1e-9);
    EXPECT_NEAR(decoded.omega_dot_rad_per_s, ours->omega_dot_rad_per_s, 1e-15);
    EXPECT_NEAR(decoded.crs_m, ours->crs_m, 1e-6);
    EXPECT_NEAR(decoded.af0_s, ours->af0_s, 1e-12);
    EXPECT_NEAR(decoded.af1_s_per_s, ours->af1_s_per_s, 1e-17);
    // The harmonic terms and rates (D2 splits Cuc and Cic over two pages).
    EXPECT_NEAR(decoded.cuc_rad, ours->cuc_rad, 1e-9);
    EXPECT_NEAR(decoded.cus_rad, ours->cus_rad, 1e-9);
    EXPECT_NEAR(decoded.cic_rad, ours->cic_rad, 1e-9);
    EXPECT_NEAR(decoded.cis_rad, ours->cis_rad, 1e-9);
    EXPECT_NEAR(decoded.crc_m, ours->crc_m, 0.02);
    EXPECT_NEAR(decoded.delta_n_rad_per_s, ours->delta_n_rad_per_s, 1e-12);
    EXPECT_NEAR(decoded.idot_rad_per_s, ours->idot_rad_per_s, 1e-12);
  }
  // Every GEO in the samples: its ten D2 pages decoded into nav.rnx's record (checked above), or,
  // when GNSS-SDR reached it too late in the 90 s for ten pages (it searches the PRNs in turn on
  // few channels, later under load), at least synchronised to its D2 bits: D2's preamble found at
  // 500 bit/s in the samples.
  for (const int prn : geo_in_samples) {
    if (geo_decoded.contains(prn)) continue;
    EXPECT_TRUE(synchronised_to(log, prn)) << "C" << prn << ": neither decoded nor synchronised to its D2 bits";
  }
  auto real = io::read_rinex_obs(dir / "gnss-sdr-obs.rnx");
  ASSERT_TRUE(real) << real.error().message;
  const auto [tag_offset_s, p68_m] = code_after_time_tag_fit(
      *real, *sim, GnssSystem::kBeiDou, "C2I", "D2I", [](int) { return constants::kSpeedOfLight_mps / 1561.098e6; });
  EXPECT_LT(std::abs(tag_offset_s), 0.5);
  EXPECT_LE(p68_m, 1.0);
  const auto [fixes, worst_m] = fixes_against_antenna(log);
  EXPECT_GE(fixes, 5);
  EXPECT_LE(worst_m, 5.0);
  std::cout << "GNSS-SDR BeiDou: " << in_samples.size() << " satellites in the samples (" << geo_in_samples.size()
            << " GEO), " << real_nav->kepler.size() << " records decoded (" << geo_decoded.size() << " GEO), time tag offset " << tag_offset_s << " s, code p68 " << p68_m << " m after it, "
            << fixes << " fixes, worst 3D " << worst_m << " m\n";
}

// Pseudoranges of GPS C1C per (epoch, satellite) from a RINEX file.
std::map<std::pair<std::int64_t, std::string>, double> c1c_by_epoch(const io::ObservationFile& file) {
  std::map<std::pair<std::int64_t, std::string>, double> out;
  const auto& types = file.header.observation_types.at(GnssSystem::kGps);
  size_t column = types.size();
  for (size_t i = 0; i < types.size(); ++i) {
    if (types[i].code == "C1C") column = i;
  }
  for (const auto& epoch : file.epochs) {
    for (const auto& s : epoch.satellites) {
      if (s.satellite.system != GnssSystem::kGps || column >= s.values.size() || !s.values[column].value) continue;
      out[{std::llround(epoch.time.gpst_seconds_approx()), s.satellite.to_string()}] = *s.values[column].value;
    }
  }
  return out;
}

// One wall reflecting (contract wall.yaml with multipath on): GNSS-SDR's code error on the
// satellites the wall affects follows skytrace's DLL model (receiver/multipath) at the profile's
// correlator spacing (1 chip, gnss-sdr.conf's half a chip either side). GNSS-SDR's code error: its
// pseudorange minus the run's multipath-free one (obs.rnx less truth's code_multipath_m), less the
// epoch's median over the satellites the model leaves unaffected (the receiver clock). Raw
// pseudoranges here: carrier smoothing would average the multipath.
TEST_F(IqGnssSdr, WallMultipathCodeErrorFollowsTheDllModel) {
  const auto dir = test::make_temp_dir("iq_gnss_sdr_wall");
  const auto iq = test::run_command(
      test::shell_quote(test::skytrace_executable().string()) + " iq " +
      test::shell_quote(contract("wall.yaml").string()) + " --out " + test::shell_quote(dir.string()) +
      " --quiet --truth-format csv --set models.multipath=true --set time.duration_s=120 --set time.interval_s=1"
      " --set receiver.profile=gnss-sdr --set 'receiver.signals=[G1C]' 2>&1");
  ASSERT_EQ(iq.exit_code, 0) << iq.output;
  const auto smoothing = test::run_command("cd " + test::shell_quote(dir.string()) +
                                           " && sed -i 's/enable_carrier_smoothing=true/enable_carrier_smoothing=false/'"
                                           " gnss-sdr-L1.conf && mkdir -p gnss-sdr-L1 && timeout 600 gnss-sdr"
                                           " --config_file=gnss-sdr-L1.conf > gnss-sdr.log 2>&1");
  ASSERT_EQ(smoothing.exit_code, 0);
  const auto real_path = file_ending(dir / "gnss-sdr-L1", 'O');
  ASSERT_TRUE(real_path);
  auto real = io::read_rinex_obs(*real_path);
  auto sim = io::read_rinex_obs(dir / "obs.rnx");
  ASSERT_TRUE(real && sim);
  const auto real_pr = c1c_by_epoch(*real);
  const auto sim_pr = c1c_by_epoch(*sim);
  // The model's code error per (epoch, satellite) from truth.csv.
  std::map<std::pair<std::int64_t, std::string>, double> model_m;
  std::ifstream truth(dir / "truth.csv");
  std::string line;
  std::getline(truth, line);
  auto split = [](const std::string& text) {
    std::vector<std::string> fields;
    std::stringstream ss(text);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
    return fields;
  };
  const auto header = split(line);
  auto column = [&](const std::string& name) {
    return static_cast<size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const size_t time_col = column("time_gpst"), sat_col = column("sat"), signal_col = column("signal"),
               mp_col = column("code_multipath_m");
  ASSERT_LT(mp_col, header.size());
  while (std::getline(truth, line)) {
    const auto f = split(line);
    if (f.size() <= mp_col || f[signal_col] != "G1C" || f[mp_col].empty()) continue;
    auto t = GnssTime::parse_iso8601(f[time_col], TimeScale::kGpst);
    ASSERT_TRUE(t);
    model_m[{std::llround(t->gpst_seconds_approx()), f[sat_col]}] = std::stod(f[mp_col]);
  }
  // Per epoch: GNSS-SDR's error less the clock from the unaffected satellites.
  std::map<std::string, std::vector<std::pair<double, double>>> per_satellite;  // (model, GNSS-SDR)
  std::map<std::int64_t, std::vector<std::pair<std::string, std::pair<double, double>>>> epochs;
  for (const auto& [key, pr] : real_pr) {
    auto s = sim_pr.find(key);
    auto m = model_m.find(key);
    if (s == sim_pr.end() || m == model_m.end()) continue;
    epochs[key.first].push_back({key.second, {m->second, pr - (s->second - m->second)}});
  }
  for (const auto& [t, sats] : epochs) {
    std::vector<double> clock;
    for (const auto& [sat, v] : sats) {
      if (std::abs(v.first) < 0.1) clock.push_back(v.second);
    }
    if (clock.size() < 3) continue;
    std::nth_element(clock.begin(), clock.begin() + static_cast<long>(clock.size() / 2), clock.end());
    const double receiver_clock_m = clock[clock.size() / 2];
    for (const auto& [sat, v] : sats) per_satellite[sat].push_back({v.first, v.second - receiver_clock_m});
  }
  double xy = 0.0, xx = 0.0, yy = 0.0;
  int affected = 0;
  std::string summary;
  for (const auto& [sat, values] : per_satellite) {
    double model2 = 0.0, sdr2 = 0.0;
    for (const auto& [m, e] : values) {
      model2 += m * m;
      sdr2 += e * e;
    }
    const double model_rms = std::sqrt(model2 / static_cast<double>(values.size()));
    summary += sat + ": model rms " + std::to_string(model_rms) + " m, GNSS-SDR rms " +
               std::to_string(std::sqrt(sdr2 / static_cast<double>(values.size()))) + " m\n";
    if (model_rms < 0.5 || values.size() < 40) continue;
    ++affected;
    for (const auto& [m, e] : values) {
      xy += m * e;
      xx += m * m;
      yy += e * e;
    }
  }
  ASSERT_GE(affected, 2) << summary;
  // Least-squares slope of GNSS-SDR's error on the model's, and their correlation.
  const double slope = xy / xx;
  const double correlation = xy / std::sqrt(xx * yy);
  EXPECT_NEAR(slope, 1.0, 0.2) << summary;
  EXPECT_GT(correlation, 0.9) << summary;
  std::cout << "wall multipath: " << affected << " satellites affected, slope " << slope << ", correlation "
            << correlation << "\n" << summary;
}

TEST(IqBadInput, RatesBandsAndSignalsTheReceiverLacksAreRefusedWithNothingWritten) {
  if (!std::filesystem::exists(contract("esbc-open-sky.yaml"))) GTEST_SKIP() << "contract scenario absent";
  const auto dir = test::make_temp_dir("iq_bad_input");
  const std::string base = test::shell_quote(test::skytrace_executable().string()) + " iq " +
                           test::shell_quote(contract("esbc-open-sky.yaml").string()) + " --quiet --set time.duration_s=2";
  struct Case {
    std::string arguments;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--sample-rate 1e6", "output.iq.sample_rate_hz"},
      {"--band G1 --sample-rate 4e6 --set 'receiver.signals=[R1C]'", "band G1 needs at least 8.9e+06 complex samples/s"},
      {"--band G1 --sample-rate 9e6 --set 'receiver.signals=[G1C]'", "does not list signal R1C"},
      {"--band B1 --sample-rate 3e6 --set 'receiver.signals=[C2I]'", "band B1 needs at least 4.092e+06 complex samples/s"},
      {"--band L5", "output.iq.bands"},
      {"--band E1 --sample-rate 3e6 --set 'receiver.signals=[E1C]'", "band E1 needs at least 4.092e+06 complex samples/s"},
      {"--band E1 --sample-rate 5e6 --set 'receiver.signals=[G1C]'", "does not list signal E1C"},
      {"--format sc4", "output.iq.format"},
      {"--set 'receiver.signals=[E1C]'", "does not list signal G1C"},
  };
  for (const auto& c : cases) {
    const auto out = dir / "out";
    const auto r = test::run_command(base + " --out " + test::shell_quote(out.string()) + " " + c.arguments + " 2>&1");
    EXPECT_EQ(r.exit_code, 3) << c.arguments << ": " << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.arguments << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(out / "iq_L1.sc8")) << c.arguments;
  }
}

// A disk that fills up: a file size limit (ulimit -f, SIGXFSZ ignored so that the write fails
// with EFBIG as it would with ENOSPC) stops the run at the samples' write, naming the file.
TEST(IqBadInput, AWriteThatFailsLeavesNothingAndExitsFive) {
  if (!std::filesystem::exists(contract("esbc-open-sky.yaml")) ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "contract scenario or ESBC data absent";
  }
  const auto dir = test::make_temp_dir("iq_full_disk");
  const auto out = dir / "out";
  const auto r = test::run_command(
      "sh -c " + test::shell_quote("trap '' XFSZ; ulimit -f 20000; " +
                                   test::shell_quote(test::skytrace_executable().string()) + " iq " +
                                   test::shell_quote(contract("esbc-open-sky.yaml").string()) + " --out " +
                                   test::shell_quote(out.string()) +
                                   " --quiet --set time.duration_s=5 --set time.interval_s=1") +
      " 2>&1");
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.output.find("iq_L1.sc8: write failed"), std::string::npos) << r.output;
  EXPECT_TRUE(!std::filesystem::exists(out) || std::filesystem::is_empty(out)) << r.output;
}

}  // namespace
}  // namespace skytrace
