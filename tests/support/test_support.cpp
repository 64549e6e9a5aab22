#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace skytrace::test {

std::filesystem::path shared_data_dir() {
  if (const char* env = std::getenv("SKYTRACE_SHARED_DATA"); env != nullptr && *env != '\0') {
    return env;
  }
  return SKYTRACE_DEFAULT_SHARED_DATA;
}

std::filesystem::path source_dir() { return SKYTRACE_SOURCE_DIR; }
std::filesystem::path binary_dir() { return SKYTRACE_BINARY_DIR; }

std::filesystem::path make_temp_dir(const std::string& name) {
  // One folder per test: ctest runs the tests of one fixture in parallel processes, and a folder
  // shared by them would be removed under another test's feet.
  std::filesystem::path dir = binary_dir() / "test-tmp" / name;
  if (const auto* test = ::testing::UnitTest::GetInstance()->current_test_info(); test != nullptr) {
    dir /= std::string(test->test_suite_name()) + "." + test->name();
  }
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string test_profile_yaml(int channels, bool output_requires_ephemeris) {
  return R"(name: test
signals: [G1C, E1C]
channels: )" + std::to_string(channels) + R"(
elevation_mask_deg: 10
antenna:
  elevation_deg: [0, 90]
  rhcp_gain_dbic: [0, 0]
  lhcp_gain_dbic: [-20, -20]
front_end:
  system_noise_temperature_k: 290
  implementation_loss_db: 1.5
tracking:
  dll_bandwidth_hz: 0.25
  pll_bandwidth_hz: 15
  fll_bandwidth_hz: 0.1
  correlator_spacing_chips: 0.1
  integration_time_s: 0.01
  acquisition_threshold_dbhz: 40
  tracking_threshold_dbhz: 20
  acquisition_time_s: 3
  half_cycle_resolution_s: 6
  cn0_resolution_dbhz: 0.25
  output_requires_ephemeris: )" + (output_requires_ephemeris ? "true" : "false") + R"(
oscillator:
  preset: ocxo
  initial_bias_s: 0
  initial_drift_s_per_s: 0
  steering: steered
)";
}

std::string moving_base_scenario_yaml(const std::filesystem::path& nav, const std::string& rover_enu_m, int duration_s) {
  const std::string antenna =
      "    elevation_mask_deg: 10\n    profile: ublox-f9p\n    signals: [G1C, G2L, E1C, E7Q, R1C, R2C, C2I, C7I]\n";
  std::string yaml = "name: heading\ntime:\n  start: 2020-06-25T06:00:00\n  scale: GPST\n  duration_s: ";
  yaml += std::to_string(duration_s);
  yaml += "\n  interval_s: 1\nreceivers:\n  - name: ANT1\n    position:\n      world_enu_m: [0.0, 0.0, 1.5]\n";
  yaml += antenna;
  yaml += "  - name: ANT2\n    position:\n      world_enu_m: [";
  yaml += rover_enu_m;
  yaml += "]\n";
  yaml += antenna;
  yaml += "    rtk:\n      base: ANT1\n      moving_base: true\n"
          "world:\n  latitude_deg: 55.4935\n  longitude_deg: 8.4880\n  elevation_m: 73.5\n"
          "ephemeris:\n  navigation:\n    - ";
  yaml += nav.string();
  yaml += "\nmodels:\n  receiver_clock: profile\n  noise: true\nseed: 3\n";
  return yaml;
}

}  // namespace skytrace::test
