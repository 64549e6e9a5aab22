// One clock per satellite with broadcast truth, on real navigation data. ESBC's merged file of
// 2020-06-25 holds Galileo I/NAV and F/NAV records, whose clock polynomials change at different
// times; a real satellite has one clock, so the simulated E1, E5a and E5b signals must not step
// against each other there. And GPS, whose file holds LNAV records only, must come out exactly as
// before the change (obs.rnx byte for byte).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::uint64_t fnv1a64(const std::string& bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

class OneClockPerSatelliteEsbc : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = test::shared_data_dir() / "real/esbc_2020177";
    nav_ = data_ / "ESBC00DNK_R_20201770000_01D_MN.rnx";
    if (!std::filesystem::exists(nav_)) GTEST_SKIP() << "ESBC data absent (set SKYTRACE_SHARED_DATA)";
    dir_ = test::make_temp_dir("one_clock_per_satellite");
  }
  test::ProcessResult run(const std::filesystem::path& scenario, const std::filesystem::path& out,
                          const std::string& extra = "") const {
    return test::run_command("env -u SOURCE_DATE_EPOCH " + test::shell_quote(test::skytrace_executable().string()) +
                             " run " + test::shell_quote(scenario.string()) + " --out " +
                             test::shell_quote(out.string()) + " --quiet " + extra);
  }
  std::filesystem::path data_, nav_, dir_;
};

TEST_F(OneClockPerSatelliteEsbc, GalileoE1E5aAndE5bKeepOneClockAcrossTheRecordChangesOfTheHour) {
  // Broadcast truth, noise-free, no atmosphere, ideal receiver clock: carrier phase differences
  // between two signals of one satellite hold nothing but the two ambiguities.
  const auto scenario = dir_ / "galileo.yaml";
  std::ofstream(scenario) << "name: one-clock\ntime: {start: 2020-06-25T00:00:00, scale: GPST, duration_s: 3600, "
                             "interval_s: 30}\nreceiver:\n  position: {ecef_m: [3582105.2910, 532589.7313, "
                             "5232754.8054]}\n  elevation_mask_deg: 5\n  signals: [E1C, E5Q, E7Q]\nephemeris:\n"
                             "  navigation: ["
                          << nav_.string()
                          << "]\nmodels: {ionosphere: none, troposphere: none, noise: false, receiver_clock: ideal}\n";
  const auto out = dir_ / "galileo";
  const auto r = run(scenario, out);
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // The record changes the old model stepped at: I/NAV and F/NAV records in force per epoch.
  const orbits::BroadcastEphemerides eph(orbits::read_rinex_nav(nav_).value());
  const GnssTime start = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  const SatelliteId e31{GnssSystem::kGalileo, 31};
  int changes = 0;
  const orbits::KeplerEphemeris *inav = nullptr, *fnav = nullptr;
  for (int k = 0; k <= 120; ++k) {
    const auto* i = eph.find_kepler(e31, start + 30.0 * k, orbits::NavMessage::kGalileoInav);
    const auto* f = eph.find_kepler(e31, start + 30.0 * k, orbits::NavMessage::kGalileoFnav);
    if (k > 0) changes += (i != inav) + (f != fnav);
    inav = i;
    fnav = f;
  }
  EXPECT_GE(changes, 4) << "E31 should change records within the hour";

  // obs.rnx: lambda1 L1 - lambda5 L5 and lambda1 L1 - lambda7 L7 constant over each satellite's
  // hour (one continuous arc each: noise-free, open sky).
  const io::ObservationFile obs = io::read_rinex_obs(out / "obs.rnx").value();
  const auto& types = obs.header.observation_types.at(GnssSystem::kGalileo);
  std::map<std::string, size_t> column;
  for (size_t i = 0; i < types.size(); ++i) column[types[i].code] = i;
  const double lambda1 = kC / kFrequencyL1_Hz, lambda5 = kC / kFrequencyL5_Hz, lambda7 = kC / kFrequencyE5b_Hz;
  std::map<SatelliteId, std::vector<std::pair<double, double>>> differences;
  for (const auto& epoch : obs.epochs) {
    for (const auto& sat : epoch.satellites) {
      if (sat.satellite.system != GnssSystem::kGalileo) continue;
      auto value = [&](const char* code) -> std::optional<double> {
        const size_t i = column.at(code);
        return i < sat.values.size() ? sat.values[i].value : std::nullopt;
      };
      const auto l1 = value("L1C"), l5 = value("L5Q"), l7 = value("L7Q");
      if (l1 && l5 && l7) {
        differences[sat.satellite].push_back({lambda1 * *l1 - lambda5 * *l5, lambda1 * *l1 - lambda7 * *l7});
      }
    }
  }
  ASSERT_GE(differences.size(), 6u);
  ASSERT_GE(differences[e31].size(), 100u);
  for (const auto& [sat, values] : differences) {
    double min15 = values.front().first, max15 = min15, min17 = values.front().second, max17 = min17;
    for (const auto& [d15, d17] : values) {
      min15 = std::min(min15, d15);
      max15 = std::max(max15, d15);
      min17 = std::min(min17, d17);
      max17 = std::max(max17, d17);
    }
    // RINEX keeps 0.001 cycles (0.2-0.25 mm per phase): 1 mm.
    EXPECT_LT(max15 - min15, 1e-3) << sat.to_string() << " E1-E5a phase, m";
    EXPECT_LT(max17 - min17, 1e-3) << sat.to_string() << " E1-E5b phase, m";
  }

  // truth.csv: E31's signals share one sat_clock_m at every epoch, and the E1 - E5a difference of
  // the clock each code sees (sat_clock - group delay) is constant: (gamma15 - 1) BGD(E1,E5a) of
  // the I/NAV record in force, which does not change for E31 that hour.
  std::istringstream truth(test::read_zst_text(out / "truth.csv.zst"));
  std::string line;
  std::getline(truth, line);
  std::map<std::string, std::map<std::string, std::pair<double, double>>> rows;  // time -> signal -> (clock, delay)
  while (std::getline(truth, line)) {
    std::vector<std::string> cells;
    std::stringstream in(line);
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
    if (cells.size() < 12 || cells[2] != "E31" || cells[3].empty()) continue;
    rows[cells[0]][cells[3]] = {std::stod(cells[9]), std::stod(cells[11])};
  }
  ASSERT_GE(rows.size(), 100u);
  std::optional<double> first;
  double largest_m = 0.0;
  for (const auto& [time, signals] : rows) {
    ASSERT_EQ(signals.size(), 3u) << time;
    EXPECT_EQ(signals.at("E1C").first, signals.at("E5Q").first) << time;
    EXPECT_EQ(signals.at("E1C").first, signals.at("E7Q").first) << time;
    const double difference_m = (signals.at("E1C").first - signals.at("E1C").second) -
                                (signals.at("E5Q").first - signals.at("E5Q").second);
    if (!first) first = difference_m;
    largest_m = std::max(largest_m, std::abs(difference_m - *first));
  }
  EXPECT_LT(largest_m, 1e-3);
  std::printf("[ figures ] E31 E1-E5a code clock difference %.4f m, constant to %.5f m over %zu epochs, %d record "
              "changes\n",
              *first, largest_m, rows.size(), changes);
}

TEST_F(OneClockPerSatelliteEsbc, GpsWithLnavRecordsOnlyIsExactlyAsBefore) {
  // The contract's realistic ESBC scenario (precise truth, noise, steered clock, seed 7) for its GPS
  // signals. The file's GPS records are all LNAV, whose record is every GPS signal's reference, so
  // one-clock-per-satellite changed nothing: obs.rnx is the file skytrace wrote before that change
  // (commit 1d3c1d5), byte for byte, except for two deliberate changes of session 4, each checked
  // column by column: L2W's phase (L1 C/A aiding of semi-codeless loops; the profile without the
  // aiding key reproduces 1d3c1d5's hash 0x11e6ee0c3fde63f7), then the four L2C columns (L2C power
  // per GPS block, and the refitted G2L loss; 0x06976b7b5220e15c before it), and in session 6 the
  // header's ANT # / TYPE, which now names the antenna profile in use (ASH701945E_M SCIS; the
  // records unchanged, 0x56b465d10e205e1f before), and in session 8 the G2W columns (L2 P(Y) power
  // per GPS block and the semi-codeless threshold: more G2W records, 0x8584037ad1e1a088 and 264,615
  // bytes before), then the D2W column (the C/A channel's Doppler, 0x7ed5f051b41c3ed8 before), and in
  // session 17 G18's C5Q, 4.1 m later (GPS III's L5 code term; every other value the same,
  // 0xf122589fc3034df1 before). Update the value only with a deliberate change of the GPS model.
  const auto scenario = test::shared_data_dir().parent_path() / "contract" / "esbc-realistic.yaml";
  if (!std::filesystem::exists(scenario)) GTEST_SKIP() << "contract scenario absent";
  const auto out = dir_ / "gps";
  const auto r = run(scenario, out, "--no-truth --set 'receiver.signals=[G1C, G2W, G2L, G5Q]'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string bytes = read_bytes(out / "obs.rnx");
  EXPECT_EQ(bytes.size(), 267303u);
  EXPECT_EQ(fnv1a64(bytes), 0x4761b8e6045173e6ULL);
}

}  // namespace
}  // namespace skytrace
