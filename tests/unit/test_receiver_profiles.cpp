// Receiver profiles: the shipped YAML files, the search path, and messages naming file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>

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

}  // namespace
}  // namespace skytrace::receiver
