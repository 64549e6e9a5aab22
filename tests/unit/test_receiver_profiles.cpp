// Receiver profiles: the shipped YAML files, the search path, and messages naming file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <cstdlib>
#include <fstream>
#include <map>

#include "skytrace/receiver/antenna.hpp"
#include "skytrace/receiver/link_budget.hpp"
#include "skytrace/receiver/multipath.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {
namespace {

constexpr const char* kValid = R"(name: test
signals: [G1C, E1C, G2W]
signal_extra_loss_db: {G2W: 8}
channels: 12
elevation_mask_deg: 5
antenna:
  elevation_deg: [0, 90]
  rhcp_gain_dbic: [-5, 5]
  lhcp_gain_dbic: [-15, -20]
front_end:
  system_noise_temperature_k: 290
  implementation_loss_db: 2
tracking:
  dll_bandwidth_hz: 0.5
  pll_bandwidth_hz: 10
  fll_bandwidth_hz: 2
  correlator_spacing_chips: 0.1
  integration_time_s: 0.02
  acquisition_threshold_dbhz: 30
  tracking_threshold_dbhz: 22
  acquisition_time_s: 2
  half_cycle_resolution_s: 6
  cn0_resolution_dbhz: 1
oscillator:
  preset: tcxo
  initial_bias_s: 1.0e-4
  initial_drift_s_per_s: 1.0e-7
  steering: free-running
)";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

std::string error_of(const std::string& text) {
  auto p = parse_profile(text, "mine.yaml");
  EXPECT_FALSE(p) << "accepted";
  return p ? std::string() : p.error().message;
}

TEST(ReceiverProfiles, ParsesEveryField) {
  const ReceiverProfile p = parse_profile(kValid, "mine.yaml").value();
  EXPECT_EQ(p.name, "test");
  ASSERT_EQ(p.signals.size(), 3u);
  EXPECT_DOUBLE_EQ(p.tracked(Signal::parse("G2W").value())->extra_loss_db, 8.0);
  EXPECT_EQ(p.tracked(Signal::parse("G5Q").value()), nullptr);
  EXPECT_EQ(p.channel_count, 12);
  EXPECT_DOUBLE_EQ(p.elevation_mask_deg, 5.0);
  EXPECT_DOUBLE_EQ(p.antenna.rhcp_dbic(45.0, 123.0), 0.0);
  EXPECT_DOUBLE_EQ(p.antenna.lhcp_dbic(90.0, 0.0), -20.0);
  EXPECT_DOUBLE_EQ(p.antenna.rhcp_dbic(-20.0, 0.0), -5.0);  // clamped below the table
  EXPECT_DOUBLE_EQ(p.implementation_loss_db, 2.0);
  EXPECT_DOUBLE_EQ(p.pll_bandwidth_hz, 10.0);
  EXPECT_DOUBLE_EQ(p.acquisition_threshold_dbhz, 30.0);
  EXPECT_DOUBLE_EQ(p.tracking_threshold_dbhz, 22.0);
  EXPECT_DOUBLE_EQ(p.acquisition_time_s, 2.0);
  EXPECT_DOUBLE_EQ(p.half_cycle_resolution_s, 6.0);
  EXPECT_DOUBLE_EQ(p.oscillator.h0, oscillator_preset("tcxo")->h0);
  EXPECT_FALSE(p.oscillator.steered);
  EXPECT_DOUBLE_EQ(p.oscillator.initial_bias_s, 1e-4);
  EXPECT_FALSE(p.output_requires_ephemeris);  // optional, false by default
}

TEST(ReceiverProfiles, OutputRequiresEphemerisIsATrackingKey) {
  const std::string with = replaced(kValid, "  cn0_resolution_dbhz: 1\n", "  cn0_resolution_dbhz: 1\n  output_requires_ephemeris: true\n");
  EXPECT_TRUE(parse_profile(with, "mine.yaml").value().output_requires_ephemeris);
  const std::string e = error_of(replaced(with, "output_requires_ephemeris: true", "output_requires_ephemeris: sometimes"));
  EXPECT_NE(e.find("mine.yaml:24: tracking.output_requires_ephemeris: expected true or false, got 'sometimes'"),
            std::string::npos)
      << e;
  // The NetR9 outputs a satellite only once it holds its ephemeris (NYA1, docs/validation.md);
  // u-blox and Septentrio receivers output raw measurements without.
  EXPECT_TRUE(load_profile("trimble-netr9").value().output_requires_ephemeris);
  for (const char* name : {"ideal", "septentrio-polarx5", "septentrio-mosaic-x5", "ublox-f9p", "ublox-m8t"}) {
    EXPECT_FALSE(load_profile(name).value().output_requires_ephemeris) << name;
  }
}

TEST(ReceiverProfiles, ErrorsNameFileLineAndField) {
  // Missing parameter.
  std::string e = error_of(replaced(kValid, "  pll_bandwidth_hz: 10\n", ""));
  EXPECT_NE(e.find("mine.yaml:"), std::string::npos) << e;
  EXPECT_NE(e.find("tracking: missing required key 'pll_bandwidth_hz'"), std::string::npos) << e;
  // Out of range: the line of the value.
  e = error_of(replaced(kValid, "system_noise_temperature_k: 290", "system_noise_temperature_k: -3"));
  EXPECT_NE(e.find("mine.yaml:11: front_end.system_noise_temperature_k: value -3 out of range"), std::string::npos) << e;
  e = error_of(replaced(kValid, "channels: 12", "channels: 2.5"));
  EXPECT_NE(e.find("channels: expected a whole number"), std::string::npos) << e;
  e = error_of(replaced(kValid, "tracking_threshold_dbhz: 22", "tracking_threshold_dbhz: 35"));
  EXPECT_NE(e.find("tracking.tracking_threshold_dbhz: must not exceed"), std::string::npos) << e;
  e = error_of(replaced(kValid, "tracking_threshold_dbhz: 22", "tracking_threshold_dbhz: 22\n  semicodeless_threshold_dbhz: 25"));
  EXPECT_NE(e.find("tracking.semicodeless_threshold_dbhz: must not exceed tracking.tracking_threshold_dbhz"),
            std::string::npos) << e;
  for (const char* outside : {"20", "31"}) {
    e = error_of(replaced(kValid, "tracking_threshold_dbhz: 22",
                          std::string("tracking_threshold_dbhz: 22\n  reacquisition_threshold_dbhz: ") + outside));
    EXPECT_NE(e.find("tracking.reacquisition_threshold_dbhz: must lie between tracking.tracking_threshold_dbhz and "
                     "tracking.acquisition_threshold_dbhz"),
              std::string::npos)
        << e;
  }
  e = error_of(replaced(kValid, "rhcp_gain_dbic: [-5, 5]", "rhcp_gain_dbic: [-5, 5, 6]"));
  EXPECT_NE(e.find("antenna.rhcp_gain_dbic: expected 2 gains"), std::string::npos) << e;
  e = error_of(replaced(kValid, "elevation_deg: [0, 90]", "elevation_deg: [90, 0]"));
  EXPECT_NE(e.find("antenna.elevation_deg: values must increase"), std::string::npos) << e;
  e = error_of(replaced(kValid, "signals: [G1C, E1C, G2W]", "signals: [G1C, E1C, G2W, X9Z]"));
  EXPECT_NE(e.find("signals[3]"), std::string::npos) << e;
  e = error_of(replaced(kValid, "{G2W: 8}", "{G5Q: 8}"));
  EXPECT_NE(e.find("signal_extra_loss_db.G5Q: signal G5Q is not among the profile's signals"), std::string::npos) << e;
  e = error_of(replaced(kValid, "  steering: free-running\n", "  steering: free-running\n  jitter: 3\n"));
  EXPECT_NE(e.find("oscillator.jitter: unknown key"), std::string::npos) << e;
  e = error_of(replaced(kValid, "  preset: tcxo\n", ""));  // no preset: the coefficients are required
  EXPECT_NE(e.find("oscillator: missing required key 'h0'"), std::string::npos) << e;
  e = error_of(replaced(kValid, "steering: free-running", "steering: sometimes"));
  EXPECT_NE(e.find("oscillator.steering: unknown value 'sometimes'"), std::string::npos) << e;
  e = error_of("name: [unclosed\n");
  EXPECT_NE(e.find("mine.yaml:"), std::string::npos) << e;
}

TEST(ReceiverProfiles, AzimuthTableWrapsAroundNorth) {
  const std::string text = replaced(kValid, R"(  elevation_deg: [0, 90]
  rhcp_gain_dbic: [-5, 5]
  lhcp_gain_dbic: [-15, -20])",
                                    R"(  elevation_deg: [0, 90]
  azimuth_deg: [0, 90, 180, 270]
  rhcp_gain_dbic: [[0, 0], [2, 2], [4, 4], [6, 6]]
  lhcp_gain_dbic: [[-9, -9], [-9, -9], [-9, -9], [-9, -9]])");
  const ReceiverProfile p = parse_profile(text, "mine.yaml").value();
  EXPECT_DOUBLE_EQ(p.antenna.rhcp_dbic(30.0, 45.0), 1.0);
  EXPECT_DOUBLE_EQ(p.antenna.rhcp_dbic(30.0, 315.0), 3.0);  // between 270 (6) and 360 = 0 (0)
  EXPECT_DOUBLE_EQ(p.antenna.rhcp_dbic(30.0, -45.0), 3.0);
  const std::string e = error_of(replaced(text, "[[0, 0], [2, 2], [4, 4], [6, 6]]", "[[0, 0], [2, 2]]"));
  EXPECT_NE(e.find("antenna.rhcp_gain_dbic: expected one row per azimuth (4), got 2"), std::string::npos) << e;
}

TEST(ReceiverProfiles, ShippedProfilesLoadAndTrackWhatTheHardwareTracks) {
  for (const char* name : {"ideal", "septentrio-polarx5", "septentrio-mosaic-x5", "trimble-netr9", "ublox-f9p",
                           "ublox-m8t"}) {
    auto p = load_profile(name);
    ASSERT_TRUE(p) << p.error().message;
    EXPECT_EQ(p->name, name);
  }
  const auto tracks = [](const ReceiverProfile& p, const char* code) {
    return p.tracked(Signal::parse(code).value()) != nullptr;
  };
  const ReceiverProfile ideal = load_profile("ideal").value();
  EXPECT_TRUE(ideal.all_signals);
  EXPECT_EQ(ideal.dll_bandwidth_hz + ideal.pll_bandwidth_hz + ideal.fll_bandwidth_hz, 0.0);  // noise-free
  EXPECT_TRUE(tracks(ideal, "I9A"));
  // u-blox M8T: L1 only; F9P: L1/L2 (E5b, B2I), no L5.
  const ReceiverProfile m8t = load_profile("ublox-m8t").value();
  for (const TrackedSignal& s : m8t.signals) EXPECT_TRUE(s.signal.band == '1' || (s.signal.band == '2' && s.signal.system == GnssSystem::kBeiDou)) << s.signal.to_string();
  EXPECT_FALSE(tracks(m8t, "G2L"));
  EXPECT_FALSE(tracks(m8t, "R2C"));
  const ReceiverProfile f9p = load_profile("ublox-f9p").value();
  EXPECT_TRUE(tracks(f9p, "G2L"));
  EXPECT_TRUE(tracks(f9p, "E7Q"));
  EXPECT_FALSE(tracks(f9p, "G5Q"));
  EXPECT_FALSE(tracks(f9p, "E5Q"));
  EXPECT_FALSE(tracks(f9p, "G2W"));  // no semi-codeless tracking
  const ReceiverProfile polarx5 = load_profile("septentrio-polarx5").value();
  for (const char* code : {"G1C", "G2W", "G2L", "G5Q", "E1C", "E5Q", "E7Q", "E8Q", "R1C", "R2C", "C2I", "C7I", "J1C", "J2L"}) {
    EXPECT_TRUE(tracks(polarx5, code)) << code;  // the contract scenario esbc-realistic.yaml
  }
}

class TempDir {
 public:
  TempDir() : path_(std::filesystem::temp_directory_path() / ("skytrace-profiles-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

void write(const std::filesystem::path& file, const std::string& text) {
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

TEST(ReceiverProfiles, SearchOrderScenarioFolderThenEnvironmentThenProject) {
  TempDir dir;
  const auto scenario_dir = dir.path() / "scenario";
  const auto env_dir = dir.path() / "env";
  write(env_dir / "ideal.yaml", replaced(kValid, "name: test", "name: from-env"));
  write(env_dir / "custom.yaml", replaced(kValid, "name: test", "name: custom-env"));
  ::setenv("SKYTRACE_PROFILE_PATH", (dir.path() / "missing").string().append(":").append(env_dir.string()).c_str(), 1);
  EXPECT_EQ(load_profile("ideal", scenario_dir).value().name, "from-env");
  write(scenario_dir / "profiles" / "ideal.yaml", replaced(kValid, "name: test", "name: from-scenario"));
  EXPECT_EQ(load_profile("ideal", scenario_dir).value().name, "from-scenario");
  EXPECT_EQ(load_profile("custom", scenario_dir).value().name, "custom-env");
  const auto names = available_profile_names(scenario_dir);
  EXPECT_NE(std::find(names.begin(), names.end(), "custom"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "ublox-f9p"), names.end());
  ::unsetenv("SKYTRACE_PROFILE_PATH");
  EXPECT_EQ(load_profile("ideal").value().name, "ideal");  // the project's
  // By path, relative to the scenario's folder.
  write(scenario_dir / "rx" / "mine.yaml", replaced(kValid, "name: test", "name: by-path"));
  EXPECT_EQ(load_profile("rx/mine.yaml", scenario_dir).value().name, "by-path");
  auto missing = load_profile("no-such-receiver", scenario_dir);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("unknown receiver profile 'no-such-receiver' (known: "), std::string::npos);
  EXPECT_NE(missing.error().message.find("ublox-m8t"), std::string::npos);
  // A broken file found by name names itself.
  write(scenario_dir / "profiles" / "broken.yaml", replaced(kValid, "  fll_bandwidth_hz: 2\n", ""));
  auto broken = load_profile("broken", scenario_dir);
  ASSERT_FALSE(broken);
  EXPECT_NE(broken.error().message.find("broken.yaml:"), std::string::npos) << broken.error().message;
  EXPECT_NE(broken.error().message.find("fll_bandwidth_hz"), std::string::npos);
}

TEST(ReceiverProfiles, CycleSlipTimeFollowsViterbi) {
  // rho = 1 / sigma^2 = 4, B = 10 Hz: pi^2 * 4 * I0(4)^2 / 20 with I0(4) = 11.301922 (tables): 252.13 s.
  EXPECT_NEAR(mean_time_to_slip_s(0.5, 10.0, false), 252.13, 0.01);
  // A Costas loop's SNR is a quarter: sigma 0.25 rad gives the same rho.
  EXPECT_NEAR(mean_time_to_slip_s(0.25, 10.0, true), 252.13, 0.01);
  EXPECT_TRUE(std::isinf(mean_time_to_slip_s(0.01, 10.0, true)));
  EXPECT_TRUE(std::isinf(mean_time_to_slip_s(0.0, 10.0, true)));
  // The slip probability's shortcut: the lower bound of T it rests on holds, and every draw on
  // the uniform grid decides as with the exact probability, over the loop SNRs a run meets.
  for (double rho = 0.05; rho < 320.0; rho *= 1.01) {
    const double jitter_rad = 1.0 / std::sqrt(rho);
    const double exact_s = mean_time_to_slip_s(jitter_rad, 15.0, false);
    if (rho >= 1.0 && std::isfinite(exact_s)) {
      EXPECT_GT(exact_s, std::numbers::pi * std::exp(2.0 * rho) / (4.0 * 15.0) * (1.0 - 1e-12)) << rho;
    }
    for (const double interval_s : {0.05, 1.0, 30.0}) {
      const double exact = -std::expm1(-interval_s / exact_s);
      const double fast = slip_probability(jitter_rad, 15.0, false, interval_s);
      EXPECT_EQ(fast > 0.0, exact > 0.0) << rho;
      if (exact >= 0x1p-60) {
        EXPECT_EQ(fast, exact) << rho;
      }
      // The draws u = k 2^-53 nearest to the probabilities decide alike.
      for (const double u : {0.0, 0x1p-53, 0x1p-52, std::floor(exact * 0x1p53) * 0x1p-53}) {
        EXPECT_EQ(u < fast, u < exact) << rho << " " << u;
      }
    }
  }
  // Jitter grows as C/N0 falls.
  const ReceiverProfile p = parse_profile(kValid, "mine.yaml").value();
  EXPECT_GT(pll_jitter_rad(p, 25.0), pll_jitter_rad(p, 45.0));
  // 10 Hz / 10^4.5 Hz (1 + 1 / (2 * 0.02 * 10^4.5)): 0.017790 rad at 45 dB-Hz.
  EXPECT_NEAR(pll_jitter_rad(p, 45.0), 0.017790, 1e-5);
}

TEST(ReceiverProfiles, DataAndPilotComponents) {
  const auto data = [](const char* code) { return has_data_modulation(*find_signal_info(Signal::parse(code).value())); };
  EXPECT_TRUE(data("G1C"));
  EXPECT_TRUE(data("G2W"));
  EXPECT_TRUE(data("R1C"));
  EXPECT_TRUE(data("C2I"));
  EXPECT_TRUE(data("E1B"));
  EXPECT_FALSE(data("G2L"));
  EXPECT_FALSE(data("G5Q"));
  EXPECT_FALSE(data("E1C"));
  EXPECT_FALSE(data("E5Q"));
  EXPECT_FALSE(data("C1P"));
  EXPECT_FALSE(data("J2L"));
  EXPECT_TRUE(data("C7I"));  // B2I (BDS-2) has data on I
}

// ---------------------------------------------------------------- antenna profiles

constexpr const char* kAntenna = R"(name: mine
igs_names: ["MINE0001 NONE"]
elevation_deg: [0, 90]
gain_dbic:
  "1, 2": [-5, 5]
  R1: [-6, 4]
band_response_db:
  2: -1.25
lhcp_rejection_db: [3, 20]
front_end:
  antenna_temperature_k: 100
  lna_gain_db: 30
  lna_noise_figure_db: 2
  cable_loss_db: 3
)";

std::string antenna_error_of(const std::string& text) {
  auto a = parse_antenna_profile(text, "mine.yaml");
  EXPECT_FALSE(a) << "accepted";
  return a ? std::string() : a.error().message;
}

TEST(AntennaProfiles, BandsByDigitOrSystemAndLhcpFromTheRejection) {
  const AntennaProfile a = parse_antenna_profile(kAntenna, "mine.yaml").value();
  EXPECT_EQ(a.igs_names, std::vector<std::string>{"MINE0001        NONE"});
  EXPECT_EQ(a.rinex_type, "MINE0001        NONE");
  const AntennaBand* l1 = a.band_for(Signal::parse("G1C").value());
  const AntennaBand* l2 = a.band_for(Signal::parse("G2W").value());
  const AntennaBand* g1 = a.band_for(Signal::parse("R1C").value());
  ASSERT_TRUE(l1 && l2 && g1);
  EXPECT_EQ(l1->pattern, l2->pattern);  // one table shared by the bands of an entry
  EXPECT_DOUBLE_EQ(l2->response_db, -1.25);
  EXPECT_DOUBLE_EQ(g1->pattern->rhcp_dbic(90.0, 0.0), 4.0);  // GLONASS G1 has its own
  EXPECT_DOUBLE_EQ(l1->pattern->lhcp_dbic(90.0, 0.0), 5.0 - 20.0);
  EXPECT_DOUBLE_EQ(g1->pattern->lhcp_dbic(0.0, 0.0), -6.0 - 3.0);
  EXPECT_EQ(a.band_for(Signal::parse("G5Q").value()), nullptr);
  // Friis: 100 K + 290 (10^0.2 - 1) + 290 (10^0.3 - 1) / 10^3.
  EXPECT_NEAR(a.front_end->noise_temperature_k(), 100.0 + 169.6 + 0.289, 0.05);
}

TEST(AntennaProfiles, MessagesNameFileLineAndField) {
  std::string e = antenna_error_of(replaced(kAntenna, "[-6, 4]", "[-6, 25]"));
  EXPECT_NE(e.find("mine.yaml:6: gain_dbic.R1[1]: value 25 out of range [-40, 20]"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "[-5, 5]", "[-45, 5]"));
  EXPECT_NE(e.find("gain_dbic.1, 2[0]: value -45 out of range [-40, 20]"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "  R1:", "  X1:"));
  EXPECT_NE(e.find("mine.yaml:6: gain_dbic.X1: band 'X1'"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "  2: -1.25", "  5: -1.25"));
  EXPECT_NE(e.find("band_response_db.5: band 5 has no gain_dbic table"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "lhcp_rejection_db: [3, 20]\n", ""));
  EXPECT_NE(e.find("give one of lhcp_gain_dbic"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "[-5, 5]", "[-5, 5, 6]"));
  EXPECT_NE(e.find("gain_dbic.1, 2: expected 2 gains"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "  cable_loss_db: 3\n", ""));
  EXPECT_NE(e.find("front_end: missing required key 'cable_loss_db'"), std::string::npos) << e;
  e = antenna_error_of(replaced(kAntenna, "name: mine\n", "name: mine\nradome: SCIS\n"));
  EXPECT_NE(e.find("radome: unknown key"), std::string::npos) << e;
}

TEST(AntennaProfiles, ShippedAntennasAndEveryProfilesDefaultCoverItsSignals) {
  const auto names = available_antenna_names();
  for (const char* name : {"choke-ring-ash701945e", "choke-ring-ash701073", "choke-ring-dm", "survey-patch", "ann-mb", "helical", "smartphone",
                           "generic-geodetic"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
    auto a = load_antenna(name);
    ASSERT_TRUE(a) << a.error().message;
    EXPECT_EQ(a->name, name);
    EXPECT_TRUE(a->front_end.has_value()) << name;
  }
  for (const char* name : {"ideal", "septentrio-polarx5", "septentrio-mosaic-x5", "trimble-netr9", "ublox-f9p",
                           "ublox-m8t"}) {
    auto p = builtin_profile(name);  // attaches the default antenna for every tracked signal
    ASSERT_TRUE(p) << p.error().message;
    EXPECT_FALSE(p->default_antenna.empty()) << name;
    EXPECT_FALSE(p->inline_antenna) << name;  // receiver properties only
    for (const TrackedSignal& t : p->signals) EXPECT_TRUE(t.antenna) << name << " " << t.signal.to_string();
  }
}

TEST(AntennaProfiles, DefaultAntennasKeepTheFormerLinkBudgetToTheBit) {
  // The PolaRx5's former inline table and extra losses (before issue #13).
  AntennaPattern former;
  former.elevation_deg = {-90, -10, 0, 5, 10, 15, 20, 25, 30, 40, 50, 60, 70, 80, 90};
  former.rhcp_gain_dbic = {{-40, -25.0, -18.6, -12.6, -10.0, -8.4, -6.7, -5.1, -2.9, -0.3, 1.9, 3.2, 4.1, 4.5, 4.7}};
  const std::map<std::string, double> former_extra_db = {{"G1C", 0.0}, {"G5Q", 5.5}, {"E5Q", 8.0}, {"E6C", 12.0},
                                                         {"C6I", 2.75}, {"C5P", 0.0}, {"J5Q", 0.0}, {"G2W", -9.75},
                                                         {"E8Q", 2.0}, {"R3Q", 0.0}};
  const ReceiverProfile p = builtin_profile("septentrio-polarx5").value();
  EXPECT_EQ(p.system_noise_temperature_k, 290.0);  // the default's chain replaced by itself
  EXPECT_EQ(p.antenna_rinex_type, "ASH701945E_M    SCIS");
  const Eigen::Vector3d satellite_m(15e6, 5e6, 20e6), receiver_m(3582105.0, 532589.0, 5232754.0);
  for (const auto& [code, extra_db] : former_extra_db) {
    const TrackedSignal& t = *p.tracked(Signal::parse(code).value());
    for (const double elevation_deg : {3.0, 17.0, 44.4, 88.0}) {
      const LinkBudget b = link_budget(p, t, satellite_m, receiver_m, elevation_deg, 0.0, 0.0);
      EXPECT_EQ(b.antenna_gain_dbic, former.rhcp_dbic(elevation_deg, 0.0)) << code;
      EXPECT_EQ(b.implementation_loss_db, 1.5 + extra_db) << code;
    }
  }
}

TEST(AntennaProfiles, AnotherAntennaChangesGainNoiseAndReflections) {
  ReceiverProfile p = load_profile("ublox-f9p").value();
  const std::vector<Signal> signals = {Signal::parse("G1C").value()};
  ASSERT_TRUE(attach_antenna(p, "smartphone", signals, {}));
  const AntennaProfile phone = load_antenna("smartphone").value();
  const AntennaProfile patch = load_antenna("ann-mb").value();
  EXPECT_EQ(p.antenna_name, "smartphone");
  EXPECT_EQ(p.antenna_rinex_type, "");  // no IGS name
  EXPECT_NEAR(p.system_noise_temperature_k,
              350.0 - patch.front_end->noise_temperature_k() + phone.front_end->noise_temperature_k(), 1e-9);
  EXPECT_GT(p.system_noise_temperature_k, 350.0);
  EXPECT_LT(p.tracked(signals[0])->antenna->rhcp_dbic(60.0, 0.0), -9.0);
  // A once-reflected (LHCP) path from 10 degrees: the phone's linear antenna barely rejects it.
  SignalPath reflected;
  reflected.type = PathType::kReflected;
  reflected.rhcp_amplitude = 0.0;
  reflected.lhcp_amplitude = 0.5;
  const double through_phone = std::abs(antenna_amplitude(*phone.bands.at("1").pattern,
                                                          reflected, 10.0, 0.0, 60.0, 0.0));
  const double through_choke =
      std::abs(antenna_amplitude(*load_antenna("choke-ring-ash701945e").value().bands.at("1").pattern, reflected, 10.0,
                                 0.0, 60.0, 0.0));
  EXPECT_GT(through_phone, 10.0 * through_choke);
  // A band the antenna lacks names the antenna's file and the band.
  ReceiverProfile polarx5 = load_profile("septentrio-polarx5").value();
  const Status st = attach_antenna(polarx5, "smartphone", {Signal::parse("G2W").value()}, {});
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("smartphone.yaml: gain_dbic: no band 2 for G2W"), std::string::npos)
      << st.error().message;
}

TEST(AntennaProfiles, FoundByNamePathOrIgsName) {
  const AntennaProfile exact = load_antenna("ASH701945E_M    SCIS").value();
  EXPECT_EQ(exact.name, "choke-ring-ash701945e");
  EXPECT_EQ(exact.rinex_type, "ASH701945E_M    SCIS");
  // One space, lower case, a radome no profile lists: the type decides, the header keeps the radome.
  const AntennaProfile other_radome = load_antenna("trm59800.00 leit").value();
  EXPECT_EQ(other_radome.name, "survey-patch");
  EXPECT_EQ(other_radome.rinex_type, "TRM59800.00     LEIT");
  EXPECT_EQ(load_antenna("TRM59800.80").value().name, "choke-ring-dm");  // radome NONE
  const AntennaProfile nya1 = load_antenna("ASH701073.1     SNOW").value();
  EXPECT_EQ(nya1.name, "choke-ring-ash701073");  // the L1/L2 element: ESBC's band responses
  EXPECT_DOUBLE_EQ(nya1.bands.at("5").response_db, -5.5);
  EXPECT_DOUBLE_EQ(nya1.bands.at("6").response_db, -2.75);
  TempDir dir;
  const auto scenario_dir = dir.path() / "scenario";
  write(scenario_dir / "profiles" / "antennas" / "mine.yaml", kAntenna);
  write(scenario_dir / "ant" / "other.yaml", replaced(kAntenna, "name: mine", "name: other"));
  EXPECT_EQ(load_antenna("mine", scenario_dir).value().name, "mine");
  EXPECT_EQ(load_antenna("ant/other.yaml", scenario_dir).value().name, "other");
  EXPECT_EQ(load_antenna("MINE0001", scenario_dir).value().name, "mine");
  auto unknown = load_antenna("no-such-antenna", scenario_dir);
  ASSERT_FALSE(unknown);
  const std::string& e = unknown.error().message;
  EXPECT_NE(e.find("unknown antenna 'no-such-antenna'"), std::string::npos) << e;
  EXPECT_NE(e.find("known: ann-mb, choke-ring-ash701073, choke-ring-ash701945e, choke-ring-dm, generic-geodetic, helical, mine, "),
            std::string::npos) << e;
  auto missing = load_antenna("ant/none.yaml", scenario_dir);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("antenna profile file not found"), std::string::npos);
  // A receiver profile names its default antenna; an inline table and a default together are refused.
  std::string e2 = error_of(replaced(kValid, "channels: 12\n", "channels: 12\ndefault_antenna: survey-patch\n"));
  EXPECT_NE(e2.find("antenna: give default_antenna or an inline antenna table, not both"), std::string::npos) << e2;
}

}  // namespace
}  // namespace skytrace::receiver
