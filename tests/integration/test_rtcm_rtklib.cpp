// The RTCM 3 stream of `skytrace run` (output.rtcm3) decoded by an independent implementation:
// RTKLIB's convbin turns obs.rtcm3 back into RINEX, and every observable must equal skytrace's own
// obs.rnx to the resolution of its MSM7 field (pseudorange 2^-29 ms, phase range 2^-31 ms plus an
// integer number of cycles constant over the carrier arc, phase-range rate 0.0001 m/s, C/N0
// 0.0625 dB-Hz), every epoch and satellite present in both; the ephemeris messages decode to the
// records of nav.rnx to the resolution of their fields. The NMEA file (output.nmea) carries valid
// checksums and fixes at the station.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "process.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/io/nmea.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

const Eigen::Vector3d kEsbcMarker(3582105.2910, 532589.7313, 5232754.8054);

class RtcmRtklib : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto contract = test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
    if (!std::filesystem::exists(contract) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      skip_reason_ = "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
      return;
    }
    if (!test::program_available("convbin")) {
      skip_reason_ = "convbin (Debian package rtklib) is not installed: run scripts/setup";
      return;
    }
    out_ = test::make_temp_dir("rtcm_rtklib_" + std::to_string(getpid()));
    // The contract scenario with the stream outputs on; its relative data path made absolute.
    std::ifstream in(contract);
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = text.str();
    const std::string relative = "../data/";
    for (size_t at = yaml.find(relative); at != std::string::npos; at = yaml.find(relative, at + 1)) {
      yaml.replace(at, relative.size(), test::shared_data_dir().string() + "/");
    }
    yaml += "\noutput:\n  rtcm3: true\n  nmea: true\n";
    std::ofstream(out_ / "scenario.yaml") << yaml;
    auto run = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                 test::shell_quote((out_ / "scenario.yaml").string()) + " --out " +
                                 test::shell_quote((out_ / "run").string()) + " --quiet --no-truth");
    if (run.exit_code != 0) {
      setup_error_ = "skytrace run: " + run.output;
      return;
    }
    auto conv = test::run_command("convbin -r rtcm3 -tr '2020/06/25 00:00:00' -f 5 -od -os " +
                                  test::shell_quote((out_ / "run/obs.rtcm3").string()) + " -o " +
                                  test::shell_quote((out_ / "conv.obs").string()) + " -n " +
                                  test::shell_quote((out_ / "conv.nav").string()) + " 2>&1");
    if (conv.exit_code != 0) setup_error_ = "convbin: " + conv.output;
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    if (!out_.empty() && !::testing::Test::HasFailure()) std::filesystem::remove_all(out_, ignored);
  }
  void SetUp() override {
    if (!skip_reason_.empty()) GTEST_SKIP() << skip_reason_;
    ASSERT_TRUE(setup_error_.empty()) << setup_error_;
  }

  static inline std::filesystem::path out_;
  static inline std::string skip_reason_, setup_error_;
};

double wavelength_m(const SatelliteId& sat, const std::string& code, const io::ObservationHeader& header) {
  const Signal signal = Signal::from_code(sat.system, code.substr(1)).value();
  int channel = 0;
  for (const auto& s : header.glonass_slots) {
    if (sat.system == GnssSystem::kGlonass && s.slot == sat.number) channel = s.channel;
  }
  return constants::kSpeedOfLight_mps / find_signal_info(signal)->carrier_frequency_hz(channel);
}

TEST_F(RtcmRtklib, ConvbinObservationsEqualSkytraceToTheMsm7Resolution) {
  const auto sky = io::read_rinex_obs(out_ / "run/obs.rnx");
  ASSERT_TRUE(sky.ok()) << sky.error().message;
  const auto conv = io::read_rinex_obs(out_ / "conv.obs");
  ASSERT_TRUE(conv.ok()) << conv.error().message;
  ASSERT_EQ(conv->epochs.size(), sky->epochs.size());

  const double light_ms_m = constants::kSpeedOfLight_mps * 1e-3;
  // Half a field step plus the two 3-decimal roundings of RINEX.
  const double code_tol_m = 0.5 * std::ldexp(1.0, -29) * light_ms_m + 0.001;
  const double phase_tol_m = 0.5 * std::ldexp(1.0, -31) * light_ms_m;
  const double rate_tol_mps = 0.5e-4;
  const double cn0_tol = 0.5 * 0.0625 + 0.001;

  std::map<std::pair<SatelliteId, std::string>, double> phase_offset_cycles;
  std::map<char, int> compared;
  double worst_code_m = 0.0, worst_phase_cycles = 0.0, worst_doppler_hz = 0.0, worst_cn0 = 0.0;
  for (size_t e = 0; e < sky->epochs.size(); ++e) {
    const auto& a = sky->epochs[e];
    const auto& b = conv->epochs[e];
    ASSERT_EQ(a.time, b.time) << e;
    ASSERT_EQ(a.satellites.size(), b.satellites.size()) << a.time.to_iso8601(TimeScale::kGpst);
    for (const auto& sa : a.satellites) {
      const auto* sb = b.find(sa.satellite);
      ASSERT_NE(sb, nullptr) << sa.satellite.to_string() << " missing at " << a.time.to_iso8601(TimeScale::kGpst);
      const auto& types = sky->header.observation_types.at(sa.satellite.system);
      for (size_t k = 0; k < sa.values.size(); ++k) {
        if (!sa.values[k].value) continue;
        const std::string code = types[k].code;
        const auto kb = conv->header.type_index(sa.satellite.system, code);
        ASSERT_TRUE(kb.has_value()) << code << " absent from convbin's header";
        ASSERT_LT(*kb, sb->values.size());
        ASSERT_TRUE(sb->values[*kb].value.has_value()) << sa.satellite.to_string() << " " << code;
        const double va = *sa.values[k].value;
        const double vb = *sb->values[*kb].value;
        const std::string where = sa.satellite.to_string() + " " + code + " " + a.time.to_iso8601(TimeScale::kGpst);
        const double lambda = wavelength_m(sa.satellite, code, sky->header);
        switch (code[0]) {
          case 'C':
            EXPECT_NEAR(vb, va, code_tol_m) << where;
            worst_code_m = std::max(worst_code_m, std::abs(vb - va));
            break;
          case 'L': {
            // An integer number of cycles apart, the same all along the arc.
            const auto key = std::make_pair(sa.satellite, code);
            if ((sa.values[k].lli & 1U) || !phase_offset_cycles.count(key)) {
              EXPECT_TRUE(sb->values[*kb].lli & 1U) << "convbin shows no loss of lock where skytrace starts an arc: " << where;
              phase_offset_cycles[key] = std::round(vb - va);
            }
            const double off = (vb - va) - phase_offset_cycles[key];
            EXPECT_NEAR(off, 0.0, phase_tol_m / lambda + 0.001) << where;
            worst_phase_cycles = std::max(worst_phase_cycles, std::abs(off));
            break;
          }
          case 'D':
            EXPECT_NEAR(vb, va, rate_tol_mps / lambda + 0.001) << where;
            worst_doppler_hz = std::max(worst_doppler_hz, std::abs(vb - va));
            break;
          case 'S':
            EXPECT_NEAR(vb, va, cn0_tol) << where;
            worst_cn0 = std::max(worst_cn0, std::abs(vb - va));
            break;
          default: break;
        }
        ++compared[code[0]];
      }
    }
  }
  EXPECT_GT(compared['C'], 5000);
  EXPECT_EQ(compared['C'], compared['L']);
  EXPECT_EQ(compared['C'], compared['D']);
  EXPECT_EQ(compared['C'], compared['S']);
  std::cout << "compared " << compared['C'] << " signals x 4 observables; worst differences: code " << worst_code_m
            << " m, phase " << worst_phase_cycles << " cycles (after the arc's integer), Doppler " << worst_doppler_hz
            << " Hz, C/N0 " << worst_cn0 << " dB-Hz\n";
  // The station messages give the antenna reference point and height.
  EXPECT_NEAR(conv->header.antenna_delta_hen_m[0], 0.2160, 1e-4);
}

TEST_F(RtcmRtklib, ConvbinEphemeridesEqualNavRnxToTheFieldResolution) {
  const auto sky = orbits::read_rinex_nav(out_ / "run/nav.rnx");
  ASSERT_TRUE(sky.ok()) << sky.error().message;
  const auto conv = orbits::read_rinex_nav(out_ / "conv.nav");
  ASSERT_TRUE(conv.ok()) << conv.error().message;
  EXPECT_EQ(conv->kepler.size(), sky->kepler.size());
  EXPECT_EQ(conv->glonass.size(), sky->glonass.size());
  const double pi = constants::kPi;
  for (const auto& a : sky->kepler) {
    const orbits::KeplerEphemeris* b = nullptr;
    for (const auto& x : conv->kepler) {
      if (x.satellite == a.satellite && x.toe == a.toe && x.message == a.message) b = &x;
    }
    const std::string what = a.satellite.to_string() + " " + std::string(to_string(a.message)) + " toe " +
                             a.toe.to_iso8601(TimeScale::kGpst);
    ASSERT_NE(b, nullptr) << what << " not decoded";
    const bool beidou = a.satellite.system == GnssSystem::kBeiDou;
    const bool galileo = a.satellite.system == GnssSystem::kGalileo;
    const double harmonic_step = std::ldexp(1.0, beidou ? -31 : -29);
    const double radius_step = std::ldexp(1.0, beidou ? -6 : -5);
    const double af0_step = std::ldexp(1.0, beidou ? -33 : galileo ? -34 : -31);
    const double af1_step = std::ldexp(1.0, beidou ? -50 : galileo ? -46 : -43);
    // Half a step of the field, and 12 significant digits of the RINEX text.
    const auto near = [&](double vb, double va, double step, const char* field) {
      EXPECT_NEAR(vb, va, 0.5 * step + 1e-11 * std::abs(va)) << what << " " << field;
    };
    EXPECT_EQ(b->toc, a.toc) << what;
    near(b->sqrt_a_sqrtm, a.sqrt_a_sqrtm, std::ldexp(1.0, -19), "sqrt A");
    near(b->eccentricity, a.eccentricity, std::ldexp(1.0, -33), "e");
    near(b->i0_rad, a.i0_rad, std::ldexp(pi, -31), "i0");
    near(b->omega0_rad, a.omega0_rad, std::ldexp(pi, -31), "Omega0");
    near(b->omega_rad, a.omega_rad, std::ldexp(pi, -31), "omega");
    near(b->m0_rad, a.m0_rad, std::ldexp(pi, -31), "M0");
    near(b->delta_n_rad_per_s, a.delta_n_rad_per_s, std::ldexp(pi, -43), "delta n");
    near(b->idot_rad_per_s, a.idot_rad_per_s, std::ldexp(pi, -43), "IDOT");
    near(b->omega_dot_rad_per_s, a.omega_dot_rad_per_s, std::ldexp(pi, -43), "Omega dot");
    near(b->cuc_rad, a.cuc_rad, harmonic_step, "Cuc");
    near(b->cus_rad, a.cus_rad, harmonic_step, "Cus");
    near(b->cic_rad, a.cic_rad, harmonic_step, "Cic");
    near(b->cis_rad, a.cis_rad, harmonic_step, "Cis");
    near(b->crc_m, a.crc_m, radius_step, "Crc");
    near(b->crs_m, a.crs_m, radius_step, "Crs");
    near(b->af0_s, a.af0_s, af0_step, "af0");
    near(b->af1_s_per_s, a.af1_s_per_s, af1_step, "af1");
    EXPECT_EQ(b->iode, a.iode) << what;
    EXPECT_EQ(b->health, a.health) << what;
    if (beidou) {
      near(b->group_delays.tgd1_s, a.group_delays.tgd1_s, 1e-10, "TGD1");
      near(b->group_delays.tgd2_s, a.group_delays.tgd2_s, 1e-10, "TGD2");
    } else if (galileo) {
      near(b->group_delays.bgd_e1e5a_s, a.group_delays.bgd_e1e5a_s, std::ldexp(1.0, -32), "BGD E1/E5a");
      if (a.message == orbits::NavMessage::kGalileoInav) {
        near(b->group_delays.bgd_e1e5b_s, a.group_delays.bgd_e1e5b_s, std::ldexp(1.0, -32), "BGD E1/E5b");
      }
    } else {
      EXPECT_EQ(b->iodc, a.iodc) << what;
      near(b->group_delays.tgd_s, a.group_delays.tgd_s, std::ldexp(1.0, -31), "TGD");
    }
  }
  for (const auto& a : sky->glonass) {
    const orbits::GlonassEphemeris* b = nullptr;
    for (const auto& x : conv->glonass) {
      if (x.satellite == a.satellite && x.toe == a.toe) b = &x;
    }
    const std::string what = a.satellite.to_string() + " toe " + a.toe.to_iso8601(TimeScale::kUtc);
    ASSERT_NE(b, nullptr) << what << " not decoded";
    EXPECT_EQ(b->frequency_channel, a.frequency_channel) << what;
    EXPECT_EQ(b->health, a.health) << what;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(b->position_m[i], a.position_m[i], 0.5 * std::ldexp(1e3, -11) + 1e-3) << what;
      EXPECT_NEAR(b->velocity_mps[i], a.velocity_mps[i], 0.5 * std::ldexp(1e3, -20) + 1e-9) << what;
      EXPECT_NEAR(b->acceleration_mps2[i], a.acceleration_mps2[i], 0.5 * std::ldexp(1e3, -30) + 1e-12) << what;
    }
    EXPECT_NEAR(b->minus_tau_n_s, a.minus_tau_n_s, 0.5 * std::ldexp(1.0, -30) + 1e-15) << what;
    EXPECT_NEAR(b->gamma_n, a.gamma_n, 0.5 * std::ldexp(1.0, -40) + 1e-20) << what;
  }
}

TEST_F(RtcmRtklib, NmeaFileHasValidSentencesAndFixesAtTheStation) {
  std::ifstream in(out_ / "run/fix.nmea");
  int gga = 0;
  for (std::string line; std::getline(in, line);) {
    ASSERT_TRUE(io::nmea_checksum_valid(line)) << line;
    if (line.compare(3, 3, "GGA") != 0) continue;
    ++gga;
    // $GNGGA,hhmmss.ss,ddmm.mmmmmmm,N,dddmm.mmmmmmm,E,q,nn,hdop,alt,M,sep,M,,
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    ASSERT_GE(f.size(), 12U) << line;
    ASSERT_EQ(f[6], "1") << line;
    Geodetic g;
    g.latitude_deg = std::stod(f[2].substr(0, 2)) + std::stod(f[2].substr(2)) / 60.0;
    g.longitude_deg = std::stod(f[4].substr(0, 3)) + std::stod(f[4].substr(3)) / 60.0;
    g.height_m = std::stod(f[9]) + std::stod(f[11]);
    const Eigen::Vector3d up = ecef_to_enu_rotation(ecef_to_geodetic(kEsbcMarker)).row(2).transpose();
    const Eigen::Vector3d antenna = kEsbcMarker + 0.2160 * up;
    EXPECT_LT((geodetic_to_ecef(g) - antenna).norm(), 0.5) << line;
  }
  EXPECT_EQ(gga, 121);
}

// fix.csv (output.fix, on by default): the position engine on the noise-free observations lands on
// the antenna to centimetres at every epoch.
TEST_F(RtcmRtklib, FixCsvHasEveryEpochAtTheAntenna) {
  std::ifstream in(out_ / "run/fix.csv");
  std::string header;
  ASSERT_TRUE(std::getline(in, header));
  ASSERT_EQ(header.rfind("time_gpst,week,tow_s,fix,satellites_used,latitude_deg", 0), 0U) << header;
  const Eigen::Vector3d up = ecef_to_enu_rotation(ecef_to_geodetic(kEsbcMarker)).row(2).transpose();
  const Eigen::Vector3d antenna = kEsbcMarker + 0.2160 * up;
  int rows = 0;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    ASSERT_GE(f.size(), 11U) << line;
    ASSERT_EQ(f[3], "3d") << line;
    const Eigen::Vector3d xyz(std::stod(f[8]), std::stod(f[9]), std::stod(f[10]));
    EXPECT_LT((xyz - antenna).norm(), 0.05) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 121);
}

}  // namespace
}  // namespace skytrace
